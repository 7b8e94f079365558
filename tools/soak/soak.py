"""`make soak`: a long run of the bridge under full load, checked for leaks and stalls.

Starts a private roscore, the headless simulator and `scripts/hello_ros.py` (the mission flying Drone1
while the bridge runs in the same process), subscribes to every topic that process publishes, and samples
the process's RSS and thread count every few seconds. A separate probe process receives actual_pose alone.
After a warm-up it reports delivered rates, the bridge's drop counts and per-stream peaks (from its status
topic), and the largest gaps between two actual_pose messages, as seen by the probe (the verdict) and by
the monitor, with the sim-time step and the lateness across each (where the gap came from). A wake probe,
a process that only sleeps, gives the host's own scheduling delays for comparison.

With SOAK_RELOADS=1 the bridge is the node itself (`projectairsim_node.py` with a mapping file of its
own), and the monitor edits that mapping every 30 s (SOAK_EDIT_S) and reloads the scene every 2 minutes
(SOAK_SCENE_S) through the node's load_scene topic.

Pass: RSS growth under 20 MB after warm-up, thread and open-file counts that stay within 2 and 4 of their
post-warm-up values, and no delay over 100 ms that the bridge added on its own: each actual_pose gap less
the time within it that the wake probe was kept waiting (the host's scheduling delay, which held up every
process). Gaps across a scene reload are reported apart. Exit code 0 on pass, 1 on fail. SOAK_SECONDS sets
the length (600).
As root it runs the kernel's ksoftirqd threads at nice -10 for the run (`tools/soak/hosttune.py`);
SOAK_HOST_TUNING=0 leaves the host alone.
"""

from __future__ import annotations

import json
import os
import shutil
import signal
import sys
import tempfile
import threading
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from airsim_mapper.tuning import SWITCH_INTERVAL_S
from tools.rig import ROOT, Rig, RigError, descendants
from tools.soak import hosttune
from tools.soak.cpu import CpuMark, command_name, cpu_mark, cpu_shares

NODE = "soak_hello"
RELOAD_NODE = "soak_node"
SCENE = "scene_drone_sensors.jsonc"
POSE_TOPIC = "/airsim_node/Drone1/actual_pose"
SAMPLE_PERIOD_S = 5.0
RSS_LIMIT_MB = 20.0
THREAD_SLACK = 2
FD_SLACK = 4
RELOAD_GRACE_S = 5.0  # after a scene reload or a mapping edit: its gap and samples are reported apart
POSE_GAP_LIMIT_S = 0.100
WAKE_PERIOD_S = 0.005  # the wake probe's sleep
WAKE_LATE_S = 0.005  # a wake-up later than this is written down


@dataclass
class Sample:
    t: float
    rss_mb: float
    threads: int
    fds: int = 0


@dataclass
class Verdict:
    failures: list[str] = field(default_factory=list)

    def check(self, ok: bool, message: str) -> None:
        if not ok:
            self.failures.append(message)


def sample(pid: int, t0: float) -> Sample:
    rss_kb = 0
    for line in Path(f"/proc/{pid}/status").read_text().splitlines():
        if line.startswith("VmRSS:"):
            rss_kb = int(line.split()[1])
    tasks, fds = len(os.listdir(f"/proc/{pid}/task")), len(os.listdir(f"/proc/{pid}/fd"))
    return Sample(time.monotonic() - t0, rss_kb / 1024.0, tasks, fds)


def cpu_marks(rig: Rig) -> list[CpuMark]:
    """CPU marks of the rig's processes, their children (render worker, roscore's) and this monitor."""
    pids = {"monitor": os.getpid()}
    for child in rig.children:
        pids[child.name] = child.pid
        for pid in sorted(descendants({child.pid})):
            label = f"{child.name}/{command_name(pid)}"
            pids[label if label not in pids else f"{label} {pid}"] = pid
    return [mark for name, pid in pids.items() if (mark := cpu_mark(name, pid)) is not None]


class Listener:
    """Subscribes to every topic of the bridge node; counts messages and times actual_pose."""

    def __init__(self) -> None:
        self.counts: dict[str, int] = {}
        self.pose_times: list[float] = []
        self.pose_stamps: list[float] = []  # header stamps (sim time): tells lost messages from late ones
        self.status: dict = {}
        self.peaks: dict[str, dict[str, float]] = {}  # per simulator topic: the largest status peaks
        self.collect_peaks = False
        self.gc_max_ms = 0.0  # the bridge's longest garbage collection after warm-up
        self._lock = threading.Lock()
        self._subs: list = []

    def attach(self, topics: list[str]) -> None:
        import rospy
        from std_msgs.msg import String

        for topic in topics:
            if topic.endswith("/status"):
                self._subs.append(rospy.Subscriber(topic, String, self._on_status))
            elif topic == POSE_TOPIC:
                from geometry_msgs.msg import PoseStamped

                self._subs.append(
                    rospy.Subscriber(topic, PoseStamped, self._on_pose, queue_size=50, tcp_nodelay=True)
                )
            else:
                self._subs.append(rospy.Subscriber(topic, rospy.AnyMsg, self._counter(topic), queue_size=50))

    def _counter(self, topic: str):
        def on_message(_msg) -> None:
            with self._lock:
                self.counts[topic] = self.counts.get(topic, 0) + 1

        return on_message

    def _on_pose(self, msg) -> None:
        now = time.monotonic()
        with self._lock:
            self.counts[POSE_TOPIC] = self.counts.get(POSE_TOPIC, 0) + 1
            self.pose_times.append(now)
            self.pose_stamps.append(msg.header.stamp.to_sec())

    def _on_status(self, msg) -> None:
        self.status = json.loads(msg.data)
        if not self.collect_peaks:
            return
        with self._lock:
            self.gc_max_ms = max(self.gc_max_ms, self.status.get("gc_max_ms") or 0.0)
            for topic, stream in self.status.get("streams", {}).items():
                mine = self.peaks.setdefault(topic, {})
                for key, value in stream.items():
                    if key.endswith("_max_ms"):
                        mine[key] = max(mine.get(key, 0.0), value)

    def snapshot(self) -> tuple[dict[str, int], list[float], list[float]]:
        with self._lock:
            return dict(self.counts), list(self.pose_times), list(self.pose_stamps)


def node_topics(node: str) -> list[str]:
    import rosgraph

    state = rosgraph.Master("/soak").getSystemState()
    return sorted(topic for topic, nodes in state[0] if f"/{node}" in nodes and topic not in ("/rosout",))


def explain_gaps(times: list[float], stamps: list[float], wakes: Wakes | None = None, worst: int = 5) -> None:
    """Print the largest receive gaps with the sim-time step across them and the lateness after them.

    The headless server's steppable clock runs at wall speed, so `receive time - stamp` is a constant plus
    the delivery delay; its minimum over the run is the floor. A gap followed by a late message (lateness
    close to the gap) was a delay on the way; a gap with a matching stamp step and no lateness means no
    pose was produced or all were dropped. With `wakes`, two more columns: the longest stretch of the gap
    in which the wake probe was kept waiting (close to the gap, the host held up every process, not only
    the bridge), and the bridge's own part of the gap (`own_delays`), which the verdict judges.
    """
    import numpy as np

    if len(times) < 2:
        return
    t, st = np.asarray(times), np.asarray(stamps)
    gaps, steps = np.diff(t), np.diff(st)
    late = (t - st) - (t - st).min()
    host_cells = " / host delay / the bridge's own" if wakes is not None else ""
    head = "receive gap / sim-time step / lateness after" + host_cells
    own = own_delays(times, wakes)
    print(f"largest actual_pose gaps after warm-up ({head}, ms):")
    for i in np.argsort(gaps)[::-1][:worst]:
        host = [wakes.largest_within(t[i], t[i + 1]), own[i]] if wakes is not None else []
        cells = [gaps[i], steps[i], late[i + 1], *host]
        print("  " + " / ".join(f"{cell * 1000:7.1f}" for cell in cells))
    print(f"gaps over 50 ms: {int((gaps > 0.05).sum())}, over 100 ms: {int((gaps > 0.1).sum())}")
    print(
        f"actual_pose lateness p50 / p99 / max: {np.percentile(late, 50) * 1000:.1f} / "
        f"{np.percentile(late, 99) * 1000:.1f} / {late.max() * 1000:.1f} ms"
    )


def own_delays(times: list[float], wakes: Wakes | None) -> list[float]:
    """Each gap between two receive times less the time within it that the host kept the wake probe waiting.

    The wake probe does nothing but sleep, at the bridge's priority: while it waits for a CPU, so does every
    process of the rig, and a pose gap then says nothing about the bridge. What is left is the delay the
    bridge (or the server, or the link) added on its own. Without wake-ups, the gaps themselves.
    """
    pairs = list(zip(times, times[1:]))
    if wakes is None:
        return [end - start for start, end in pairs]
    return [max(0.0, end - start - wakes.covered_within(start, end)) for start, end in pairs]


def across_events(times: list[float], events: list[float], grace: float) -> list[bool]:
    """Per gap between two receive times: does it overlap an [event, event + grace) window?"""
    return [
        any(start < event + grace and end > event for event in events) for start, end in zip(times, times[1:])
    ]


def gap_percentile(times: list[float], q: float) -> float:
    import numpy as np

    return float(np.percentile(np.diff(times), q)) if len(times) > 1 else float("inf")


def largest_gap(times: list[float]) -> float:
    import numpy as np

    return float(np.diff(times).max()) if len(times) > 1 else float("inf")


def tune_host() -> list[hosttune.KernelThread]:
    """ksoftirqd ahead of the busy threads for the run (SOAK_HOST_TUNING=0: leave the host alone).

    Returns the threads' previous state, for `hosttune.restore`; empty if the host was left alone.
    """
    if os.environ.get("SOAK_HOST_TUNING", "1") == "0":
        print("host: left as is (SOAK_HOST_TUNING=0)", flush=True)
        return []
    try:
        previous = hosttune.raise_softirq_priority()
    except hosttune.HostTuningError as exc:
        print(f"host: left as is ({exc}); pose gaps include the kernel's network delays", flush=True)
        return []
    names = ", ".join(t.name for t in previous)
    was = ", ".join(t.describe() for t in previous)
    print(f"host: {names} at nice {hosttune.SOFTIRQ_NICE} for the run, then back to {was}", flush=True)
    return previous


def host_speed_ms() -> float:
    """Milliseconds for a fixed pure-Python loop: this machine's speed at the moment (best of 3).

    Measured on the idle machine before and after the run; a shared host's speed varies within an hour
    (docs/reliability.md), and a run on a slow stretch says more about the host than about the bridge.
    """
    best = float("inf")
    for _ in range(3):
        start = time.perf_counter()
        total = 0
        for i in range(1_000_000):
            total += i
        best = min(best, time.perf_counter() - start)
    return round(best * 1000, 1)


def mapping_text(queue_size: int) -> str:
    """The soak's mapping with reloads: the default one, its IMU bridges' queue size edited."""
    return f"version: 1\nextends: default\nrules:\n  - {{name: imu, queue_size: {queue_size}}}\n"


class Reloader:
    """Edits the node's mapping every `edit_s` and reloads its scene every `scene_s` (SOAK_RELOADS=1)."""

    def __init__(self, mapping: Path, node: str, edit_s: float, scene_s: float) -> None:
        self.mapping, self.edit_s, self.scene_s = mapping, edit_s, scene_s
        self.topic = f"/ProjectAirSim/node/{node}/load_scene"
        self.edits: list[float] = []  # monotonic times
        self.scenes: list[float] = []
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._run, name="reloader", daemon=True)

    def start(self) -> None:
        self._thread.start()

    def stop(self) -> None:
        self._stop.set()
        self._thread.join(timeout=5.0)

    def _run(self) -> None:
        import rospy
        from std_msgs.msg import String

        publisher = rospy.Publisher(self.topic, String, queue_size=1)
        start = time.monotonic()
        next_edit, next_scene = start + self.edit_s, start + self.scene_s
        while not self._stop.wait(max(0.0, min(next_edit, next_scene) - time.monotonic())):
            now = time.monotonic()
            if now >= next_scene:
                publisher.publish(String(data=SCENE))
                self.scenes.append(now)
                next_scene += self.scene_s
            elif now >= next_edit:
                self.mapping.write_text(mapping_text(2 if len(self.edits) % 2 == 0 else 1))
                self.edits.append(now)
                next_edit += self.edit_s


def start_bridge(rig: Rig, sim, seconds: float, workdir: Path) -> tuple[Any, str, Reloader | None]:
    """The process that runs the bridge: hello_ros (mission and bridge), or the node with reloads."""
    if os.environ.get("SOAK_RELOADS", "0") != "1":
        argv = [str(ROOT / "scripts" / "hello_ros.py"), "--nodename", NODE, *sim.ports.args()]
        return rig.python("hello_ros", [*argv, "--seconds", str(seconds + 120)]), NODE, None
    mapping = workdir / "soak_mapping.yaml"
    mapping.write_text(mapping_text(1))
    node = rig.node(sim.ports, "--scene", SCENE, "--mapping", str(mapping), node_name=RELOAD_NODE)
    edit_s = float(os.environ.get("SOAK_EDIT_S", "30"))
    scene_s = float(os.environ.get("SOAK_SCENE_S", "120"))
    return node, RELOAD_NODE, Reloader(mapping, RELOAD_NODE, edit_s, scene_s)


def run(seconds: float, workdir: Path) -> int:
    rig = Rig(workdir)
    warmup = min(60.0, max(20.0, seconds * 0.2))
    speed_before = host_speed_ms()
    tuned = tune_host()
    reloader: Reloader | None = None
    try:
        rig.roscore()
        os.environ.update(
            {k: rig.env[k] for k in ("ROS_MASTER_URI", "ROS_HOSTNAME", "ROS_LOG_DIR", "ROS_HOME")}
        )
        sim = rig.simserver()
        bridge, node, reloader = start_bridge(rig, sim, seconds, workdir)
        import rospy

        rospy.init_node("soak_listener", anonymous=True, disable_signals=True)
        sys.setswitchinterval(SWITCH_INTERVAL_S)  # the monitor must not add GIL waits to the gaps it measures
        from airsim_mapper.engine.process_tuning import GcPauses

        own_gc = GcPauses()
        rig.wait_topics([POSE_TOPIC], bridge)
        time.sleep(1.0)
        probe_file = workdir / "pose_probe.txt"
        probe = rig.python("pose_probe", ["-m", "tools.soak", "--pose-probe", str(probe_file)])
        wake_file = workdir / "wake_probe.txt"
        waker = rig.python("wake_probe", ["-m", "tools.soak", "--wake-probe", str(wake_file)])
        listener = Listener()
        topics = node_topics(node)
        listener.attach(topics)
        plan = f"soak: {seconds:.0f} s, warm-up {warmup:.0f} s, {len(topics)} topics subscribed"
        if reloader is not None:
            plan += f", a mapping edit every {reloader.edit_s:.0f} s"
            plan += f", a scene reload every {reloader.scene_s:.0f} s"
            reloader.start()
        print(plan, flush=True)
        t0 = time.monotonic()
        cpu_before: list[CpuMark] = []
        cpu_t0 = t0
        samples: list[Sample] = []
        counts_at_warmup: dict[str, int] = {}
        while time.monotonic() - t0 < seconds:
            bridge.check_alive()
            s = sample(bridge.pid, t0)
            samples.append(s)
            if not counts_at_warmup and s.t >= warmup:
                cpu_before, cpu_t0 = cpu_marks(rig), time.monotonic()
                counts_at_warmup = listener.snapshot()[0]
                listener.collect_peaks = True
                own_gc.take_peak_ms()
            print(f"  t={s.t:6.0f} s  rss={s.rss_mb:7.1f} MB  threads={s.threads}  files={s.fds}", flush=True)
            time.sleep(SAMPLE_PERIOD_S)
        if reloader is not None:
            reloader.stop()
        counts, pose_times, pose_stamps = listener.snapshot()
        nice0_cores = print_cpu(cpu_shares(cpu_before, cpu_marks(rig), time.monotonic() - cpu_t0))
        pose_times, pose_stamps = since(t0 + warmup, pose_times, pose_stamps)
        probe.stop(timeout=30.0)  # on SIGINT the probe writes its file
        probe_times, probe_stamps = since(t0 + warmup, *read_probe(probe_file))
        waker.stop(timeout=30.0)
        wakes = read_wakes(wake_file)
        wakes = wakes.since(t0 + warmup) if wakes is not None else None
        print(f"the wake probe (a process that only sleeps {WAKE_PERIOD_S * 1000:.0f} ms at a time):")
        if wakes is None:
            print(f"  it did not finish its file ({wake_file}): no host delays to compare")
        else:
            print(
                f"  {wakes.count} wake-ups in all; after warm-up {wakes.over(0.02)} late by over 20 ms, "
                f"{wakes.over(0.05)} by over 50 ms, the latest by {wakes.largest() * 1000:.1f} ms"
            )
        print("the pose probe (a process receiving actual_pose only):")
        explain_gaps(probe_times, probe_stamps, wakes)
        print("the monitor (its process also receives every other stream):")
        explain_gaps(pose_times, pose_stamps, wakes)
        print(f"longest garbage collection after warm-up: bridge {listener.gc_max_ms:.1f} ms, ", end="")
        print(f"this monitor {own_gc.take_peak_ms():.1f} ms (a pause here delays what it measures)")
        print("bridge stream peaks after warm-up (ms): arrival gap / wait for worker / handling")
        for topic, peaks in sorted(listener.peaks.items()):
            cells = [peaks.get(k, 0.0) for k in ("arrival_gap_max_ms", "wait_max_ms", "handle_max_ms")]
            print(f"  {cells[0]:7.1f} / {cells[1]:7.1f} / {cells[2]:7.1f}  {topic}")
        events = Events()
        if reloader is not None:
            events = Events([t - t0 for t in reloader.edits], [t - t0 for t in reloader.scenes])
        poses = judge_poses(probe_times, wakes, [t0 + t for t in events.scenes])
        measured = (samples, warmup, counts, counts_at_warmup, poses, pose_times, listener.status, seconds)
        host_wake_max_ms = round(wakes.largest() * 1000, 1) if wakes is not None else None
    finally:
        if reloader is not None:
            reloader.stop()
        rig.stop_all(timeout=15.0)
        hosttune.restore(tuned)
        if "rospy" in sys.modules:
            sys.modules["rospy"].signal_shutdown("soak done")
    speeds = [speed_before, host_speed_ms()]
    print(f"host speed: a fixed Python loop took {speeds[0]} ms before the run, {speeds[1]} ms after")
    host = {"ksoftirqd_nice": hosttune.SOFTIRQ_NICE if tuned else None, "host_speed_ms": speeds}
    host.update(cpu_nice0_cores=nice0_cores, cpus=os.cpu_count(), host_wake_max_ms=host_wake_max_ms)
    return report(*measured, host, events)


@dataclass
class Events:
    """When (seconds into the run) the mapping was edited and the scene reloaded."""

    edits: list[float] = field(default_factory=list)
    scenes: list[float] = field(default_factory=list)

    def near(self, t: float) -> bool:
        """True within RELOAD_GRACE_S after any event: a sample there is left out of the flat checks."""
        return any(0.0 <= t - event < RELOAD_GRACE_S for event in (*self.edits, *self.scenes))


@dataclass
class PoseJudgement:
    """The probe's actual_pose gaps: the largest, the bridge's own part (judged), and those across reloads."""

    times: list[float]
    largest_own_s: float
    largest_across_reload_s: float | None


def judge_poses(times: list[float], wakes: Wakes | None, scenes: list[float]) -> PoseJudgement:
    """The bridge's own delays (`own_delays`) of the gaps outside a scene reload's window, and apart the
    largest gap across a reload (a reload rebuilds every bridge: a pause there is expected)."""
    own = own_delays(times, wakes)
    gaps = [end - start for start, end in zip(times, times[1:])]
    near = across_events(times, scenes, RELOAD_GRACE_S)
    kept = [value for value, skip in zip(own, near) if not skip]
    across = [gap for gap, skip in zip(gaps, near) if skip]
    return PoseJudgement(
        times, max(kept, default=float("inf")), max(across, default=None) if scenes else None
    )


def print_cpu(shares: list[tuple[str, float, int]]) -> float:
    """Print each process's CPU after warm-up; return the cores used at nice 0 or below (what competes)."""
    print(f"CPU after warm-up (% of one core, nice value) on {os.cpu_count()} CPUs:")
    for name, percent, nice in shares:
        if percent >= 0.5:
            print(f"  {percent:6.1f}  nice {nice:3d}  {name}")
    nice0 = sum(percent for _, percent, nice in shares if nice <= 0) / 100.0
    print(f"  {nice0:6.2f} cores at nice 0 or below, in all")
    return round(nice0, 2)


def report(
    samples: list[Sample],
    warmup: float,
    counts: dict[str, int],
    counts_at_warmup: dict[str, int],
    poses: PoseJudgement,
    monitor_pose_times: list[float],
    status: dict,
    seconds: float,
    host: dict | None = None,
    events: Events | None = None,
) -> int:
    events = events or Events()
    after = [s for s in samples if s.t >= warmup and not events.near(s.t)]
    verdict = Verdict()
    verdict.check(len(after) >= 2, f"run too short for a verdict after the {warmup:.0f} s warm-up")
    window = max(1e-9, seconds - warmup)
    rates = {topic: (counts[topic] - counts_at_warmup.get(topic, 0)) / window for topic in sorted(counts)}
    print("delivered rates after warm-up (Hz):")
    for topic, rate in rates.items():
        print(f"  {rate:8.1f}  {topic}")
    streams = status.get("streams", {})
    print("bridge streams (received / dropped):")
    for topic, s in sorted(streams.items()):
        print(f"  {s['received']:8d} / {s['dropped']:6d}  {topic}")
    gap, own = largest_gap(poses.times), poses.largest_own_s
    summary = {
        "largest_pose_gap_ms": round(gap * 1000, 1),
        "largest_bridge_delay_ms": round(own * 1000, 1),  # the verdict's figure
        "p99_pose_gap_ms": round(gap_percentile(poses.times, 99) * 1000, 1),
        "monitor_largest_pose_gap_ms": round(largest_gap(monitor_pose_times) * 1000, 1),
        "state": status.get("state"),
        "sim_losses": status.get("sim_losses"),
        **(host or {}),
    }
    if events.edits or events.scenes:
        across = poses.largest_across_reload_s
        summary.update(mapping_edits=len(events.edits), scene_reloads=len(events.scenes))
        summary.update(largest_pose_gap_across_reload_ms=None if across is None else round(across * 1000, 1))
        summary.update(reloads_rejected=(status.get("mapping") or {}).get("rejections"))
    if after:
        rss_growth = max(s.rss_mb for s in after) - after[0].rss_mb
        threads, fds = [s.threads for s in after], [s.fds for s in after]
        summary.update(rss_start_mb=round(after[0].rss_mb, 1), rss_growth_mb=round(rss_growth, 1))
        summary.update(
            threads_min=min(threads), threads_max=max(threads), files_min=min(fds), files_max=max(fds)
        )
        verdict.check(rss_growth < RSS_LIMIT_MB, f"RSS grew {rss_growth:.1f} MB (limit {RSS_LIMIT_MB:.0f})")
        verdict.check(
            max(threads) - min(threads) <= THREAD_SLACK, f"thread count varied {min(threads)}..{max(threads)}"
        )
        verdict.check(max(fds) - min(fds) <= FD_SLACK, f"open files varied {min(fds)}..{max(fds)}")
    verdict.check(
        own <= POSE_GAP_LIMIT_S,
        f"the bridge added {own * 1000:.0f} ms to an actual_pose gap on its own (limit 100; the largest gap "
        f"was {gap * 1000:.0f} ms)",
    )
    print("summary: " + json.dumps(summary))
    print("rates: " + json.dumps({topic: round(rate, 2) for topic, rate in rates.items()}))
    for failure in verdict.failures:
        print(f"FAIL: {failure}")
    print("PASS" if not verdict.failures else "FAIL", flush=True)
    return 0 if not verdict.failures else 1


def pose_probe(out: Path) -> int:
    """A process that only receives actual_pose (TCP_NODELAY) and writes `receive time, stamp` lines.

    The gap verdict comes from here: the monitor above receives every image and cloud of the bridge, about
    100 MB/s, and a pause of its own would count against the bridge.
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


def main() -> int:
    if len(sys.argv) == 3 and sys.argv[1] == "--pose-probe":
        return pose_probe(Path(sys.argv[2]))
    if len(sys.argv) == 3 and sys.argv[1] == "--wake-probe":
        return wake_probe(Path(sys.argv[2]))
    seconds = float(os.environ.get("SOAK_SECONDS", "600"))
    workdir = Path(tempfile.mkdtemp(prefix="airsim-mapper-soak-"))
    # SIGTERM unwinds like Ctrl-C, so the rig is stopped and the host setting restored
    signal.signal(signal.SIGTERM, lambda *_: sys.exit(128 + signal.SIGTERM))
    try:
        code = run(seconds, workdir)
    except RigError as exc:
        print(f"soak: {exc}", file=sys.stderr)
        return 1
    if code == 0:
        shutil.rmtree(workdir, ignore_errors=True)
    else:
        print(f"logs kept in {workdir}")
    return code
