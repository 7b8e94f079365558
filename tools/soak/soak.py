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

import os
import shutil
import signal
import sys
import tempfile
import threading
import time
from pathlib import Path
from typing import Any

from airsim_mapper.common.tuning import SWITCH_INTERVAL_S
from tools.rig import ROOT, Rig, RigError, descendants
from tools.soak import hosttune
from tools.soak.cpu import CpuMark, command_name, cpu_mark, cpu_shares
from tools.soak.gaps import explain_gaps
from tools.soak.listener import Listener, node_topics
from tools.soak.probes import POSE_TOPIC, WAKE_PERIOD_S, pose_probe, read_probe, read_wakes, since, wake_probe
from tools.soak.verdict import Events, Sample, judge_poses, print_cpu, report

NODE = "soak_hello"
RELOAD_NODE = "soak_node"
SCENE = "scene_drone_sensors.jsonc"
SAMPLE_PERIOD_S = 5.0


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
