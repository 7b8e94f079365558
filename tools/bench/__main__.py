"""`make bench`: converter costs, camera renderers, end-to-end figures, side by side; writes out/bench.json.

python -m tools.bench [--quick] [--costs-only] [--profile] [--ros 1|2] [--out out/bench.json]
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import tempfile
import time
from pathlib import Path
from typing import Any

from tools import camera_probe
from tools.bench import costs, encoders, host, renderers, sampling, scenes, tables, targets, transports
from tools.bench.e2e import Bench, rotated
from tools.bench.results import latency_rounds, quiet_round

CAMERA_HZ, LIDAR_HZ, SCALE_CAMERA_HZ = targets.CAMERA_HZ, scenes.LIDAR_HZ, targets.SCALE_CAMERA_HZ
SCALE_DRONES = (1, 2, 5, 10)
LATENCY_ROUNDS = 3  # the pose p99 targets are judged on the median of this many interleaved rounds


def more_rounds(
    bench: Bench,
    key: str,
    scene: str,
    topics: list[str],
    kinds: tuple[str, ...] = ("bridge", "forwarder", "receive_floor"),
    rounds: int = LATENCY_ROUNDS,
    first: dict[str, Any] | None = None,
    camera: bool = True,
    ros: int = 1,
) -> list[dict[str, Any]]:
    """`rounds` - 1 more rounds of one case, each through `kinds` (the bridge, the bare forwarder and
    the receive loop alone), in an order rotated by one each round so that a slow spell of the host falls
    on each of them in turn. The first round is the case's main runs (`first`, as `latency_rounds`
    reads them). While fewer than `rounds` rounds were quiet (`quiet_round`), one more is run, up to
    `rounds` more in all. Without `camera` the forwarder and the receive loop subscribe no camera (the
    bridge subscribes what its probe reads). `ros`: the flavour of the bridge and the forwarder."""

    def bridge(n: int) -> dict[str, Any]:
        with bench.bridge_session(scene, ros=ros) as session:
            return session.probe(f"{key}_round{n}", topics)

    def forwarder(n: int) -> dict[str, Any]:
        with bench.forwarder_session(scene, camera=camera, ros=ros) as session:
            return session.probe(f"forwarder_{key}_round{n}", topics)

    def receive_floor(n: int) -> dict[str, Any]:
        return bench.receive_floor(scene, camera=camera)

    runs = {"bridge": bridge, "forwarder": forwarder, "receive_floor": receive_floor}
    names = list(kinds)
    more: list[dict[str, Any]] = []
    calm = int(first is None or quiet_round(first))
    n = 1
    while n < rounds or (calm < rounds and n < 2 * rounds):
        more.append({name: runs[name](n + 1) for name in rotated(names, n)})
        calm += quiet_round(more[-1])
        n += 1
    return more


def run_e2e(bench: Bench, profile_dir: Path | None, rounds: int = LATENCY_ROUNDS) -> dict[str, Any]:
    """Every end-to-end figure, the latency cases in `rounds` interleaved rounds. Each bridge session
    measures at most one heavy topic (docs/performance.md)."""
    out: dict[str, Any] = {
        "baselines": {},
        "bridge": {},
        "pose": {},
        "client_pose": {},
        "scale": {},
        "forwarder": {},
        "receive_floor": {},
        "rounds": {},
    }
    floor = out["forwarder"]
    base = out["baselines"]
    base["rospy_image"] = bench.rospy_baseline("image", CAMERA_HZ)
    base["pynng_image"] = bench.pynng_baseline("image", CAMERA_HZ)
    base["rospy_cloud"] = bench.rospy_baseline("cloud", LIDAR_HZ)
    base["pynng_cloud"] = bench.pynng_baseline("cloud", LIDAR_HZ)

    single = bench.scene("single", 1, scenes.CameraSetup(1920, 1080, 1 / CAMERA_HZ, (0, 1)), lidar=True)
    load = bench.scene("load", 1, scenes.CameraSetup(1920, 1080, 1 / 60.0, (0,)))
    hd = bench.scene("hd720", 1, scenes.CameraSetup(1280, 720, 1 / CAMERA_HZ, (0,)))
    image_only, pose_only = [scenes.image_topic(1)], [scenes.pose_topic(1)]
    camera_topics = image_only + pose_only

    def profile(name: str) -> str | None:
        return str(profile_dir / f"bridge_{name}.prof") if profile_dir else None

    with bench.bridge_session(single, profile=profile("camera")) as session:
        out["pose"]["idle"] = session.probe("pose_idle", pose_only)
        # the camera at its nominal 30 Hz, with pose measured alongside: pose under nominal camera load
        out["bridge"]["camera"] = session.probe("camera", camera_topics)
        # the same with the images read by another subscriber process, as another node of a ROS graph
        out["bridge"]["camera_apart"] = session.probe("camera_apart", pose_only, apart=image_only)
    # The floor: the same frames through the client's own receive loop into plain rospy publishers.
    with bench.forwarder_session(single) as session:
        floor["pose_idle"] = session.probe("forwarder_pose_idle", pose_only)
    # pose only is two small CPU figures: its ratio is judged on the median of interleaved rounds too
    first = latency_rounds(out, "pose_idle")[0]
    out["rounds"]["pose_idle"] = more_rounds(
        bench, "pose_idle", single, pose_only, ("bridge", "forwarder"), rounds, first, camera=False
    )
    with bench.forwarder_session(single, camera=True) as session:
        floor["camera"] = session.probe("forwarder_camera", camera_topics)
        floor["camera_apart"] = session.probe("forwarder_camera_apart", pose_only, apart=image_only)
    out["receive_floor"]["camera"] = bench.receive_floor(single, camera=True)
    first = latency_rounds(out, "camera")[0]
    out["rounds"]["camera"] = more_rounds(bench, "camera", single, camera_topics, rounds=rounds, first=first)
    with bench.bridge_session(hd) as session:
        out["bridge"]["camera_720p"] = session.probe("camera_720p", camera_topics)
    with bench.forwarder_session(hd, camera=True) as session:
        floor["camera_720p"] = session.probe("forwarder_camera_720p", camera_topics)
    # The same idle pose stream with a mapping that drops the per-camera frames: what those frames cost.
    lean = scenes.write_mapping_without_camera_frames(bench.config_dir)
    with bench.bridge_session(single, node_args=("--mapping", str(lean))) as session:
        out["pose"]["idle_without_camera_frames"] = session.probe("pose_idle_lean", pose_only)
    out["pose"]["waiting"] = bench.waiting_node()  # no scene: nothing arrives, nothing is published
    with bench.bridge_session(single, profile=profile("depth")) as session:
        out["bridge"]["depth"] = session.probe("depth", [scenes.image_topic(1, "depth_planar_camera")])
    out["transports"] = transports.run(bench, single)  # image_transport's compressed topics subscribed
    with bench.bridge_session(single, profile=profile("lidar")) as session:
        out["bridge"]["lidar"] = session.probe("lidar", [scenes.lidar_topic(1)])
    with bench.bridge_session(single, decode="client") as session:
        out["bridge"]["lidar_client_path"] = session.probe("lidar_client", [scenes.lidar_topic(1)])
    loaded = [scenes.pose_topic(1), scenes.image_topic(1)]
    with bench.bridge_session(load, profile=profile("load")) as session:  # 1080p at 60 Hz: saturating
        out["pose"]["camera_load"] = session.probe("pose_load", loaded)
    with bench.forwarder_session(load, camera=True) as session:
        floor["camera_load"] = session.probe("forwarder_pose_load", loaded)
    with bench.bridge_session(load, runner="mission", profile=profile("mission")) as session:
        out["pose"]["camera_load_mission"] = session.probe("pose_load_mission", loaded)
    first = latency_rounds(out, "camera_load")[0]
    out["rounds"]["camera_load"] = more_rounds(
        bench, "camera_load", load, loaded, ("bridge", "forwarder"), rounds, first
    )

    for drones in SCALE_DRONES:
        scene = bench.scene(f"scale{drones}", drones, scenes.CameraSetup(320, 240, 1 / SCALE_CAMERA_HZ, (0,)))
        topics = [t for i in range(1, drones + 1) for t in (scenes.pose_topic(i), scenes.image_topic(i))]
        with bench.bridge_session(scene, profile=profile(f"scale{drones}")) as session:
            out["scale"][str(drones)] = session.probe(f"scale{drones}", topics)
        if drones == SCALE_DRONES[-1]:
            with bench.forwarder_session(scene, camera=True) as session:
                floor["scale"] = session.probe(f"forwarder_scale{drones}", topics)
            out["receive_floor"]["scale"] = bench.receive_floor(scene, camera=True)
            first = latency_rounds(out, "scale")[0]
            out["rounds"]["scale"] = more_rounds(
                bench, f"scale{drones}", scene, topics, rounds=rounds, first=first
            )
    return out


def run_e2e_ros2(bench: Bench, profile_dir: Path | None, rounds: int = LATENCY_ROUNDS) -> dict[str, Any]:
    """The ROS 2 rows, in the shape of `run_e2e`'s results: the node in .venv-ros2 beside the bare rclpy
    forwarder (forwarder_ros2.py) on the same frames, pose only, 1080p and 720p cameras @30 with pose, and
    ten drones; pose only, 1080p and ten drones in `rounds` interleaved rounds."""
    out: dict[str, Any] = {"bridge": {}, "pose": {}, "scale": {}, "forwarder": {}, "rounds": {}}
    floor = out["forwarder"]
    single = bench.scene("single", 1, scenes.CameraSetup(1920, 1080, 1 / CAMERA_HZ, (0, 1)), lidar=True)
    hd = bench.scene("hd720", 1, scenes.CameraSetup(1280, 720, 1 / CAMERA_HZ, (0,)))
    pose_only, camera_topics = [scenes.pose_topic(1)], [scenes.image_topic(1), scenes.pose_topic(1)]
    profile = str(profile_dir / "bridge_ros2_camera.prof") if profile_dir else None
    with bench.bridge_session(single, profile=profile, ros=2) as session:
        out["pose"]["idle"] = session.probe("ros2_pose_idle", pose_only)
        out["bridge"]["camera"] = session.probe("ros2_camera", camera_topics)
    with bench.forwarder_session(single, ros=2) as session:
        floor["pose_idle"] = session.probe("ros2_forwarder_pose_idle", pose_only)
    with bench.forwarder_session(single, camera=True, ros=2) as session:
        floor["camera"] = session.probe("ros2_forwarder_camera", camera_topics)
    for key, topics, camera in (("pose_idle", pose_only, False), ("camera", camera_topics, True)):
        first = latency_rounds(out, key)[0]
        out["rounds"][key] = more_rounds(
            bench, f"ros2_{key}", single, topics, ("bridge", "forwarder"), rounds, first, camera, ros=2
        )
    with bench.bridge_session(hd, ros=2) as session:
        out["bridge"]["camera_720p"] = session.probe("ros2_camera_720p", camera_topics)
    with bench.forwarder_session(hd, camera=True, ros=2) as session:
        floor["camera_720p"] = session.probe("ros2_forwarder_camera_720p", camera_topics)
    drones = SCALE_DRONES[-1]
    scene = bench.scene(f"scale{drones}", drones, scenes.CameraSetup(320, 240, 1 / SCALE_CAMERA_HZ, (0,)))
    topics = [t for i in range(1, drones + 1) for t in (scenes.pose_topic(i), scenes.image_topic(i))]
    with bench.bridge_session(scene, ros=2) as session:
        out["scale"][str(drones)] = session.probe(f"ros2_scale{drones}", topics)
    with bench.forwarder_session(scene, camera=True, ros=2) as session:
        floor["scale"] = session.probe(f"ros2_forwarder_scale{drones}", topics)
    first = latency_rounds(out, "scale")[0]
    out["rounds"]["scale"] = more_rounds(
        bench, f"ros2_scale{drones}", scene, topics, ("bridge", "forwarder"), rounds, first, ros=2
    )
    return out


def _positive(text: str) -> int:
    value = int(text)
    if value < 1:
        raise argparse.ArgumentTypeError(f"must be at least 1, not {value}")
    return value


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", default="out/bench.json")
    parser.add_argument("--quick", action="store_true", help="shorter measurement windows (3 s)")
    parser.add_argument("--costs-only", action="store_true", help="only the in-process converter costs")
    parser.add_argument("--profile", action="store_true", help="cProfile the bridge node of each session")
    parser.add_argument(
        "--rounds",
        type=_positive,
        default=LATENCY_ROUNDS,
        help="interleaved rounds of each pose latency case and of pose only's CPU, judged on the median of "
        "the quiet ones; a round that lost CPU time to a hypervisor is run again, up to N more (default "
        f"{LATENCY_ROUNDS}; more give steadier figures on a noisy host)",
    )
    parser.add_argument(
        "--ros",
        type=int,
        choices=(1, 2),
        help="only the ROS1 rows (with the converter costs and the renderers), or only the ROS 2 rows "
        "(default: both)",
    )
    args = parser.parse_args(argv)
    flavours = (args.ros,) if args.ros else (1, 2)
    os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
    started = time.monotonic()
    host_at_start = sampling.host_sample()
    results: dict[str, Any] = {
        "machine": {
            "cpus": os.cpu_count(),
            "python": platform.python_version(),
            "load_average_at_start": os.getloadavg()[0],
            "stolen_share_since_boot": sampling.stolen_share(sampling.HostSample(0, 0), host_at_start),
            "idle_wake_ms": sampling.wake_delays_ms(),
        },
    }
    if 1 in flavours:
        results["costs"] = costs.run()
        print(tables.costs_table(results["costs"]), flush=True)
        # the image_transport converters against the library's own encode of the same frame, in this run
        results["encoders"] = encoders.converter_costs(repeat=5 if args.quick else 30)
        print(encoders.converter_table(results["encoders"]), flush=True)
        results["renderers"] = renderers.run()
        print(renderers.table(results["renderers"]), flush=True)
        # the server's own camera path: all seven types of one 1280x720 camera, render worker to socket
        results["server_camera"] = camera_probe.run(seconds=3.0 if args.quick else 8.0)
        print(camera_probe.table(results["server_camera"]), flush=True)
    if not args.costs_only:
        workdir = Path(tempfile.mkdtemp(prefix="airsim_mapper_bench_"))
        profile_dir = workdir if args.profile else None
        duration = 3.0 if args.quick else 8.0
        bench = Bench(workdir, warmup_s=2.0, duration_s=duration, flavours=flavours)
        try:
            if 1 in flavours:
                results["e2e"] = run_e2e(bench, profile_dir, args.rounds)
            if 2 in flavours:
                results["e2e_ros2"] = run_e2e_ros2(bench, profile_dir, args.rounds)
        finally:
            bench.close()
        results["machine"]["windows"] = bench.windows
        results["machine"]["windows_retaken"] = bench.windows_retaken
        results["workdir"] = str(workdir)
        if "e2e" in results:
            print(tables.e2e_table(results["e2e"]), flush=True)
            raw = {key: results["e2e"]["bridge"][key] for key in ("camera", "depth")}
            print(transports.table(results["e2e"]["transports"], raw), flush=True)
        if "e2e_ros2" in results:
            print(tables.ros2_table(results["e2e_ros2"]), flush=True)
    results["targets"] = targets.targets(results)
    results["seconds"] = time.monotonic() - started
    results["machine"]["load_average_at_end"] = os.getloadavg()[0]
    results["machine"]["stolen_share"] = sampling.stolen_share(host_at_start, sampling.host_sample())
    print(tables.targets_table(results["targets"]), flush=True)
    out = Path(args.out)
    out.parent.mkdir(parents=True, exist_ok=True)
    out.write_text(json.dumps(results, indent=1, default=float))
    machine = results["machine"]
    print(
        f"results: {out} ({results['seconds']:.0f} s); load average {machine['load_average_at_start']:.1f} "
        f"at start, {machine['load_average_at_end']:.1f} at end, on {machine['cpus']} cores"
    )
    print(host.host_line(machine))
    e2e = results.get("e2e", {})
    for warning in (
        host.floor_over_target(e2e),
        host.forwarder_over_latency_target(e2e),
        host.forwarder_over_cpu_target(e2e),
        host.forwarder_under_compressed_rate(e2e),
    ):
        if warning:
            print(warning)
    noisy = host.noisy_host(machine)
    if noisy:
        print(noisy)
    # Only the start counts: at the end the load average includes the bench's own processes.
    if machine["load_average_at_start"] > (machine["cpus"] or 1) / 2:
        print(
            "warning: other work was running on this machine; the end-to-end figures are not representative"
        )
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
