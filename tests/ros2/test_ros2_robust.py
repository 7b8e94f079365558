"""What the ROS1 node survives, on ROS 2 too: the simulator restarted under it, its mapping edited while it
runs, a second scene loaded while it streams, and SIGINT or SIGTERM at any of those moments, with nothing
left running. A watcher in .venv-ros2 (watch_ros2.py) reports what a ROS 2 user sees as it happens."""

from __future__ import annotations

import json
import signal
import subprocess
import time
from pathlib import Path

import pytest
from harness import Child, Rig, SimPorts, wait_until
from ros2kit import ROOT, ros2_env

from tools.rig import descendants

pytestmark = pytest.mark.live  # starts the server, the node and watchers

NODE = ROOT / ".venv-ros2" / "bin" / "airsim-mapper-node"
HERE = Path(__file__).resolve().parent
WATCH, LISTENER = HERE / "watch_ros2.py", HERE / "listen_ros2.py"
SCENE = "scene_drone_sensors.jsonc"
NODE_NAME = "/projectairsim"
STATUS = "/airsim_mapper/projectairsim/status"
LOAD_SCENE = "/ProjectAirSim/node/projectairsim/load_scene"
DRONE = "/airsim_node/Drone1"
POSE = ("geometry_msgs/PoseStamped", f"{DRONE}/actual_pose")
IMAGE = ("sensor_msgs/Image", f"{DRONE}/DownCamera/scene_camera/image")
DEPTH = ("sensor_msgs/Image", f"{DRONE}/DownCamera/depth_planar_camera/image")
NEW_IMAGE = ("sensor_msgs/Image", f"{DRONE}/DownCamera/scene_camera/image_raw")
CHASE_IMAGE = f"{DRONE}/Chase/scene_camera/image"
ODOM = f"{DRONE}/odom"
POSE_COPY = ("geometry_msgs/PoseStamped", f"{DRONE}/pose_copy")
TF, TF_STATIC = ("tf2_msgs/TFMessage", "/tf"), ("tf2_msgs/TFMessage", "/tf_static")
START = "version: 1\nextends: default\n"
# a rule added (pose_copy), one removed (odometry), one changed (camera_image: renamed, without Chase)
EDIT = """version: 1
extends: default
remove: [odometry]
rules:
  - name: camera_image
    ros: <namespace>/airsim_node/<robot_name>/<camera_name>/<image_type>/image_raw
    match: {camera_name: "!Chase"}
  - name: pose_copy
    for_each: robot
    direction: sim_to_ros
    sim: /Sim/<scene_name>/robots/<robot_name>/actual_pose
    ros: <namespace>/airsim_node/<robot_name>/pose_copy
    type: geometry_msgs/PoseStamped
    converter: pose
    frame_id: <frame_prefix>map
"""
INVALID = EDIT + "  - {name: imu, converter: imuu}\n"
RESTARTS = 3
SHUTDOWN_TIMEOUT_S = 5.0  # the node's default --shutdown-timeout
INVALID_ERROR = "rule 'imu': unknown converter 'imuu' (did you mean 'imu'?)"


def in_ros2(launcher: Rig, domain: int, name: str, argv: list[str]) -> Child:
    """A process in .venv-ros2's environment on `domain` (the rig's own environment stays the server's)."""
    saved = launcher.env
    launcher.env = {**ros2_env(domain), "PYTHONUNBUFFERED": "1"}
    try:
        return launcher.start(name, argv)
    finally:
        launcher.env = saved


def start_node(launcher: Rig, domain: int, ports: SimPorts, *args: str) -> Child:
    argv = [str(NODE), *ports.args(), "--simconfigpath", str(ROOT / "sim_config"), *args]
    return in_ros2(launcher, domain, "node_ros2", argv)


def start_watch(launcher: Rig, python: Path, domain: int, *items: str) -> Child:
    watch = in_ros2(launcher, domain, "watch_ros2", [str(python), "-u", str(WATCH), *items])
    wait_until(lambda: "READY" in watch.output(), 60, what="the watcher's subscriptions")
    return watch


def topic(kind_and_name: tuple[str, str]) -> str:
    return "=".join(kind_and_name)


def lines(child: Child, tag: str) -> list[str]:
    return [line[len(tag) + 1 :] for line in child.output().splitlines() if line.startswith(tag + " ")]


def arrivals(watch: Child, name: str) -> list[float]:
    """Wall-clock receive times of `name`'s messages (at most one each THROTTLE_S)."""
    return [float(t) for n, t in (line.split() for line in lines(watch, "MSG")) if n == name]


def arrived_after(watch: Child, name: str, t0: float) -> bool:
    return any(t > t0 for t in arrivals(watch, name))


def statuses(watch: Child) -> list[dict]:
    return [json.loads(line) for line in lines(watch, "STATUS")]


def graph(watch: Child) -> dict[str, list[str]]:
    """What the node publishes now, by topic (the newest GRAPH line)."""
    seen = lines(watch, "GRAPH")
    return json.loads(seen[-1]) if seen else {}


def tf_frames(watch: Child, name: str) -> list[str]:
    """The frames of the newest message on /tf or /tf_static with frames not seen in the one before."""
    seen = [line.split(" ", 1)[1] for line in lines(watch, "TF") if line.split(" ", 1)[0] == name]
    return json.loads(seen[-1]) if seen else []


def atomic_write(path: Path, text: str) -> None:
    """Write as editors do: a new file renamed over the old one."""
    temporary = path.with_suffix(".tmp")
    temporary.write_text(text)
    temporary.replace(path)


def stopped_cleanly(node: Child, sig: int, within: float) -> float:
    """Send `sig`; the node must exit with status 0 within `within` seconds, with no traceback and no
    process it started still running. How long it took."""
    tree = descendants({node.pid}) | {node.pid}
    sent = time.monotonic()
    node.popen.send_signal(sig)
    try:
        code = node.popen.wait(timeout=within)
    except subprocess.TimeoutExpired:
        pytest.fail(f"{signal.Signals(sig).name}: still running after {within} s:\n{node.output()[-3000:]}")
    took = time.monotonic() - sent
    assert code == 0, node.output()[-3000:]
    assert f"stopping ({signal.Signals(sig).name})" in node.output()
    assert "Traceback" not in node.output(), node.output()[-3000:]
    left = [pid for pid in tree if Path(f"/proc/{pid}").exists() and pid != node.pid]
    assert left == [], f"processes of the node left running: {left}"
    return took


def threads_and_files(pid: int) -> tuple[int, int]:
    return len(list(Path(f"/proc/{pid}/task").iterdir())), len(list(Path(f"/proc/{pid}/fd").iterdir()))


def test_the_ros2_node_comes_back_after_each_simulator_restart_with_its_subscribers_served(
    launcher: Rig, ros2_python: Path, ros_domain: int
) -> None:
    ports = SimPorts.free()
    server = launcher.simserver(ports=ports).process
    node = start_node(launcher, ros_domain, ports, "--scene", SCENE)
    # the image subscriber is there across the restarts: its lazy stream must be subscribed again each time
    watch = start_watch(
        launcher, ros2_python, ros_domain, topic(IMAGE), topic(POSE), topic(TF), f"status:{STATUS}"
    )
    wait_until(
        lambda: arrivals(watch, IMAGE[1]) and arrivals(watch, POSE[1]) and arrivals(watch, "/tf"),
        60,
        what=f"images, poses and /tf before the restart; node log:\n{node.output()[-2000:]}",
    )
    time.sleep(3.0)  # simulation time well past what the restarted server reaches before the node is back
    recoveries, counts = [], []
    for cycle in range(1, RESTARTS + 1):
        server.stop(signal.SIGKILL)
        killed = time.time()
        wait_until(
            lambda c=cycle: any(s["state"] == "stale" and s["sim_losses"] == c for s in statuses(watch)),
            10,
            what=f"restart {cycle}: the status to say stale",
        )
        server = launcher.simserver(ports=ports, wait=False).process

        def connected(c: int = cycle) -> bool:
            last = statuses(watch)[-1]
            return last["state"] == "connected" and last["reconnects"] == c

        wait_until(
            connected, 30, what=f"restart {cycle}: connected again; node log:\n{node.output()[-2000:]}"
        )
        back = time.time()
        for name in (POSE[1], IMAGE[1], "/tf"):
            wait_until(lambda n=name, b=back: arrived_after(watch, n, b), 30, what=f"restart {cycle}: {name}")
        recoveries.append(min(t for t in arrivals(watch, IMAGE[1]) if t > killed) - killed)
        time.sleep(0.3)
        counts.append(threads_and_files(node.pid))
    print(f"first image after each kill (s): {[round(r, 2) for r in recoveries]}; threads, files: {counts}")
    assert counts[-1][0] <= counts[0][0] + 1 and counts[-1][1] <= counts[0][1] + 2, "threads or files leak"
    late = start_watch(launcher, ros2_python, ros_domain, topic(DEPTH))  # a subscriber that comes afterwards
    wait_until(lambda: arrivals(late, DEPTH[1]), 30, what="depth images for a subscriber after the restarts")
    states = [s["state"] for s in statuses(watch)]
    assert states.index("stale") < len(states) - 1 - states[::-1].index("connected")
    assert statuses(watch)[-1]["scene"] == SCENE
    # the new simulator's clock started over: the node's own tf (goals in its frames) started over too
    wait_until(lambda: "tf buffer cleared" in node.output(), 10, what="the node's tf cleared")
    assert statuses(watch)[-1]["sim_time_jumps_back"] >= 1
    assert node.output().count("simulator back: ") == RESTARTS and node.alive()
    stopped_cleanly(node, signal.SIGINT, 10.0)


def test_an_edited_mapping_is_applied_to_the_ros2_graph_and_a_broken_edit_changes_nothing(
    launcher: Rig, ros2_python: Path, ros_domain: int, tmp_path: Path
) -> None:
    mapping = tmp_path / "live.yaml"
    mapping.write_text(START)
    server = launcher.simserver()
    node = start_node(launcher, ros_domain, server.ports, "--scene", SCENE, "--mapping", str(mapping))
    items = (topic(POSE), topic(IMAGE), topic(NEW_IMAGE), topic(POSE_COPY), f"graph:{NODE_NAME}")
    watch = start_watch(launcher, ros2_python, ros_domain, *items, f"status:{STATUS}")
    wait_until(lambda: arrivals(watch, IMAGE[1]), 60, what=f"images; node log:\n{node.output()[-2000:]}")
    assert {IMAGE[1], CHASE_IMAGE, ODOM} <= graph(watch).keys()
    assert NEW_IMAGE[1] not in graph(watch) and POSE_COPY[1] not in graph(watch)

    edited = time.time()
    atomic_write(mapping, EDIT)

    def applied() -> bool:
        now = graph(watch)
        return {NEW_IMAGE[1], POSE_COPY[1]} <= now.keys() and not {IMAGE[1], ODOM} & now.keys()

    wait_until(applied, 10, what="the added topics in the graph, the removed ones gone")
    took = time.time() - edited
    now = graph(watch)
    assert now[NEW_IMAGE[1]] == ["sensor_msgs/msg/Image"]
    assert now[POSE_COPY[1]] == ["geometry_msgs/msg/PoseStamped"]
    assert CHASE_IMAGE not in now  # the changed rule's match leaves the Chase camera out
    for name in (NEW_IMAGE[1], POSE_COPY[1]):
        wait_until(lambda n=name: arrivals(watch, n), 10, what=f"messages on the new {name}")
    time.sleep(0.5)
    poses = [t for t in arrivals(watch, POSE[1]) if t > edited - 0.5]
    gap = max(b - a for a, b in zip(poses, poses[1:]))
    print(f"applied in {took:.2f} s; largest gap between poses {gap * 1000:.0f} ms")
    assert gap < 0.5, "the pose stream paused while other bridges were reloaded"

    before, log_before = graph(watch), len(node.output())
    atomic_write(mapping, INVALID)
    located = f"{mapping}:{EDIT.count(chr(10)) + 1}:28: {INVALID_ERROR}"
    wait_until(lambda: located in node.output()[log_before:], 5, what="the located rejection in the log")
    assert "every bridge keeps running" in node.output()[log_before:]
    wait_until(
        lambda: any(s.get("mapping", {}).get("state") == "rejected" for s in statuses(watch)),
        5,
        what="the rejection on the status topic",
    )
    rejected = time.time()
    wait_until(lambda: arrived_after(watch, NEW_IMAGE[1], rejected), 10, what="images after the rejection")
    assert arrived_after(watch, POSE[1], rejected)
    assert graph(watch) == before
    stopped_cleanly(node, signal.SIGTERM, 10.0)


def test_a_second_scene_loaded_while_streaming_replaces_the_robots_topics_and_static_frames(
    launcher: Rig, ros2_python: Path, ros_domain: int
) -> None:
    server = launcher.simserver()
    node = start_node(launcher, ros_domain, server.ports, "--scene", SCENE)
    items = (topic(IMAGE), topic(TF_STATIC), f"graph:{NODE_NAME}")
    watch = start_watch(launcher, ros2_python, ros_domain, *items)
    lidar, tower = f"{DRONE}/lidar1/lidar", "/airsim_node/RadarTower1/radar1/radar_detections"
    wait_until(lambda: arrivals(watch, IMAGE[1]), 60, what=f"images; node log:\n{node.output()[-2000:]}")
    assert lidar in graph(watch) and tower not in graph(watch)
    assert "airsim_node/Drone1>airsim_node/Drone1/lidar1" in tf_frames(watch, "/tf_static")

    topics = {"tower": ("radar_msgs/RadarScan", tower)}
    argv = [str(ros2_python), str(LISTENER), "60", f"{topics['tower'][0]}={tower}"]
    argv.append(f"say:{LOAD_SCENE}=scene_radar_tower.jsonc")
    run = subprocess.run(argv, env=ros2_env(ros_domain), capture_output=True, text=True, timeout=120)
    assert run.returncode == 0, run.stderr
    assert tower in json.loads(run.stdout.strip().splitlines()[-1])["topics"], node.output()[-3000:]

    wait_until(lambda: lidar not in graph(watch), 10, what="the first scene's lidar publisher gone")
    assert tower in graph(watch) and IMAGE[1] in graph(watch)  # the new scene's Drone1 has the camera too
    static = tf_frames(watch, "/tf_static")
    assert "airsim_node/RadarTower1>airsim_node/RadarTower1/radar1" in static
    assert "airsim_node/Drone1>airsim_node/Drone1/lidar1" not in static
    # a subscriber that comes later gets the new scene's static frames (transient-local)
    late = start_watch(launcher, ros2_python, ros_domain, topic(TF_STATIC))
    wait_until(lambda: tf_frames(late, "/tf_static"), 20, what="/tf_static for a late subscriber")
    assert tf_frames(late, "/tf_static") == static
    loaded = time.time()
    wait_until(lambda: arrived_after(watch, IMAGE[1], loaded), 20, what="images in the new scene")
    stopped_cleanly(node, signal.SIGTERM, 10.0)


@pytest.mark.parametrize(
    ("moment", "sig"),
    [
        ("connecting", signal.SIGTERM),
        ("streaming", signal.SIGTERM),
        ("reloading", signal.SIGTERM),
        ("reloading", signal.SIGINT),
        ("frozen", signal.SIGTERM),
    ],
    ids=[
        "connecting-SIGTERM",
        "streaming-SIGTERM",
        "reloading-SIGTERM",
        "reloading-SIGINT",
        "frozen-SIGTERM",
    ],
)
def test_a_signal_stops_the_ros2_node_at_once_with_nothing_left_running(
    launcher: Rig, ros2_python: Path, ros_domain: int, tmp_path: Path, moment: str, sig: int
) -> None:
    mapping = tmp_path / "live.yaml"
    mapping.write_text(START)
    if moment == "connecting":  # nothing listens on those ports
        node = start_node(launcher, ros_domain, SimPorts.free(), "--scene", SCENE, "--mapping", str(mapping))
        wait_until(lambda: "waiting for it" in node.output(), 30, what="the node waiting for the simulator")
    else:
        server = launcher.simserver()
        node = start_node(launcher, ros_domain, server.ports, "--scene", SCENE, "--mapping", str(mapping))
        watch = start_watch(launcher, ros2_python, ros_domain, topic(IMAGE), topic(NEW_IMAGE))
        wait_until(lambda: arrivals(watch, IMAGE[1]), 60, what=f"images; node log:\n{node.output()[-2000:]}")
        if moment == "reloading":
            atomic_write(mapping, EDIT)  # the watcher finds it within its poll period, 0.25 s
            time.sleep(0.3)
        if moment == "frozen":  # the simulator answers nothing: shutdown's unsubscribe gets no reply
            server.process.popen.send_signal(signal.SIGSTOP)
            time.sleep(0.3)
    try:
        took = stopped_cleanly(node, sig, 10.0)
    finally:
        if moment == "frozen":
            server.process.popen.send_signal(signal.SIGCONT)
    print(f"{moment}: {signal.Signals(sig).name} stopped the node in {took:.2f} s")
    assert took < (SHUTDOWN_TIMEOUT_S + 1.0 if moment == "frozen" else 5.0)


def test_a_callback_that_raises_is_logged_and_the_nodes_executor_keeps_serving(
    ros2_python: Path, ros_domain: int
) -> None:
    run = subprocess.run(
        [str(ros2_python), str(HERE / "spin_ros2.py")],
        env=ros2_env(ros_domain),
        capture_output=True,
        text=True,
        timeout=60,
    )
    assert run.returncode == 0, run.stderr
    seen = json.loads(run.stdout.strip().splitlines()[-1])
    assert seen["spinning"] and seen["ticks"] > 10, (seen, run.stderr)  # it failed at the third
    assert "a ROS 2 callback failed; the node carries on" in run.stderr
    assert "RuntimeError: a callback fails" in run.stderr
