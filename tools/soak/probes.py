"""The soak's two probe processes and their files: the pose probe receives actual_pose alone, the wake probe
only sleeps (its late wake-ups are the host's scheduling delays)."""

from __future__ import annotations

import signal
import sys
import threading
import time
from dataclasses import dataclass, field
from pathlib import Path

from airsim_mapper.common.tuning import SWITCH_INTERVAL_S

POSE_TOPIC = "/airsim_node/Drone1/actual_pose"
WAKE_PERIOD_S = 0.005  # the wake probe's sleep
WAKE_LATE_S = 0.005  # a wake-up later than this is written down


def pose_probe(out: Path) -> int:
    """A process that only receives actual_pose (TCP_NODELAY) and writes `receive time, stamp` lines.

    The gap verdict comes from here: the monitor (listener.py) receives every image and cloud of the
    bridge, about 100 MB/s, and a pause of its own would count against the bridge.
    """
    import rospy
    from geometry_msgs.msg import PoseStamped

    rospy.init_node("soak_pose_probe", anonymous=True, disable_signals=True)
    sys.setswitchinterval(SWITCH_INTERVAL_S)
    lines: list[str] = []

    def on_pose(msg) -> None:
        lines.append(f"{time.monotonic():.6f} {msg.header.stamp.to_sec():.6f}\n")

    rospy.Subscriber(POSE_TOPIC, PoseStamped, on_pose, queue_size=100, tcp_nodelay=True)
    stop = threading.Event()
    signal.signal(signal.SIGINT, lambda *_: stop.set())
    while not stop.wait(1.0):
        pass
    out.write_text("".join(lines))
    return 0


@dataclass
class Wakes:
    """What the wake probe saw: its wake-ups and the late ones as (time it fell asleep, delay) pairs."""

    count: int = 0
    late: list[tuple[float, float]] = field(default_factory=list)

    def since(self, start: float) -> Wakes:
        """The late wake-ups from `start` on (the count stays the run's)."""
        return Wakes(self.count, [(t, d) for t, d in self.late if t >= start])

    def largest_within(self, start: float, end: float) -> float:
        """The longest stretch of [start, end) that a late wake-up's delay covered (0 if none did)."""
        covered = (min(end, t + WAKE_PERIOD_S + d) - max(start, t + WAKE_PERIOD_S) for t, d in self.late)
        return max((c for c in covered if c > 0.0), default=0.0)

    def covered_within(self, start: float, end: float) -> float:
        """How much of [start, end) the late wake-ups' delays covered, overlaps counted once."""
        spans = sorted(
            (max(start, t + WAKE_PERIOD_S), min(end, t + WAKE_PERIOD_S + d))
            for t, d in self.late
            if t + WAKE_PERIOD_S < end and t + WAKE_PERIOD_S + d > start
        )
        total, reached = 0.0, start
        for low, high in spans:
            low = max(low, reached)
            if high > low:
                total += high - low
                reached = high
        return total

    def largest(self) -> float:
        """The longest delay of the run."""
        return max((d for _, d in self.late), default=0.0)

    def over(self, limit_s: float) -> int:
        """How many wake-ups came later than `limit_s`."""
        return sum(1 for _, d in self.late if d > limit_s)


def wake_probe(out: Path) -> int:
    """A process that only sleeps `WAKE_PERIOD_S` at a time; writes each wake-up late by over 5 ms.

    It runs at the bridge's priority in a session of its own, like every process of the rig, and does
    nothing else: its delays are the host's scheduling delays, the floor under any pose gap. Each late
    wake-up is written as it happens; the count of all wake-ups last, on SIGINT.
    """
    stop = threading.Event()
    signal.signal(signal.SIGINT, lambda *_: stop.set())
    count = 0
    with out.open("w") as sink:
        before = time.monotonic()
        while not stop.is_set():
            time.sleep(WAKE_PERIOD_S)
            now = time.monotonic()
            if now - before - WAKE_PERIOD_S > WAKE_LATE_S:
                sink.write(f"{before:.6f} {now - before - WAKE_PERIOD_S:.6f}\n")
                sink.flush()
            count += 1
            before = now
        sink.write(f"wakes {count}\n")
    return 0


def read_wakes(path: Path) -> Wakes | None:
    """The wake probe's file; None if it is missing or unfinished (the probe did not stop cleanly)."""
    lines = path.read_text().splitlines() if path.exists() else []
    if not lines or not lines[-1].startswith("wakes "):
        return None
    rows = [line.split() for line in lines[:-1]]
    return Wakes(int(lines[-1].split()[1]), [(float(r[0]), float(r[1])) for r in rows])


def since(start: float, times: list[float], stamps: list[float]) -> tuple[list[float], list[float]]:
    """The (receive time, stamp) pairs received at or after `start`."""
    kept = [(t, st) for t, st in zip(times, stamps) if t >= start]
    return [t for t, _ in kept], [st for _, st in kept]


def read_probe(path: Path) -> tuple[list[float], list[float]]:
    rows = [line.split() for line in path.read_text().splitlines()] if path.exists() else []
    return [float(r[0]) for r in rows], [float(r[1]) for r in rows]
