"""Where the ROS 2 node's CPU goes, thread by thread, beside the bare rclpy forwarder's: pose only @100.

`.venv/bin/python -m tools.bench.ros2_threads [--rounds N] [--seconds S]` runs the bench's replay server,
then the node and the forwarder in turn, each while the bench's probe reads the pose (a second time, after
a first that waits for the pose to flow), and prints each
process's cores and its busiest threads (by their OS names: the Python threads are `python`, the receive
thread the busiest of them) from `/proc/<pid>/task/*/schedstat` read at both ends of a window inside the
probe's.
"""

from __future__ import annotations

import argparse
import contextlib
import os
import tempfile
import threading
import time
from pathlib import Path

from tools.bench import scenes
from tools.bench.e2e import Bench, Session

SETTLE_S = 3.0  # from the probe's start to the window's
SHOWN = 6  # threads printed per process


def thread_cpu_ns(pid: int) -> dict[tuple[str, str], int]:
    """(tid, name) -> CPU nanoseconds so far, for each live thread of `pid`."""
    out = {}
    for tid in os.listdir(f"/proc/{pid}/task"):
        with contextlib.suppress(OSError):
            name = Path(f"/proc/{pid}/task/{tid}/comm").read_text().strip()
            out[(tid, name)] = int(Path(f"/proc/{pid}/task/{tid}/schedstat").read_text().split()[0])
    return out


def window(session: Session, label: str, seconds: float) -> str:
    """One line: the cores of `session`'s node and of its busiest threads over a window while the probe
    reads the pose."""
    pid, cores = session.node.pid, {}

    def sample() -> None:
        time.sleep(SETTLE_S)
        before, start = thread_cpu_ns(pid), time.monotonic()
        time.sleep(seconds)
        after, elapsed = thread_cpu_ns(pid), time.monotonic() - start
        cores.update({key: (ns - before[key]) / 1e9 / elapsed for key, ns in after.items() if key in before})

    session.probe(f"{label}_warm", [scenes.pose_topic(1)])  # returns once the node has been publishing
    sampler = threading.Thread(target=sample)
    sampler.start()
    session.probe(label, [scenes.pose_topic(1)])
    sampler.join()
    busiest = sorted(cores.items(), key=lambda item: -item[1])[:SHOWN]
    threads = ", ".join(f"{name} {share:.4f}" for (_tid, name), share in busiest)
    return f"{label:9s} {sum(cores.values()):.4f} cores: {threads}"


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--rounds", type=int, default=2)
    parser.add_argument("--seconds", type=float, default=8.0)
    args = parser.parse_args(argv)
    workdir = Path(tempfile.mkdtemp(prefix="airsim_mapper_ros2_threads_"))
    # the probe's window covers the settling and the measured window
    bench = Bench(workdir, warmup_s=2.0, duration_s=args.seconds + 2 * SETTLE_S, flavours=(2,))
    try:
        scene = bench.scene("single", 1, scenes.CameraSetup(1920, 1080, 1 / 30, (0, 1)), lidar=True)
        for _ in range(args.rounds):
            with bench.bridge_session(scene, ros=2) as session:
                print(window(session, "bridge", args.seconds), flush=True)
            with bench.forwarder_session(scene, ros=2) as session:
                print(window(session, "forwarder", args.seconds), flush=True)
    finally:
        bench.close()
    print(f"load average {os.getloadavg()[0]:.1f} at the end", flush=True)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
