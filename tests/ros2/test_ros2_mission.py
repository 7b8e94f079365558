"""Mission scripts, logging and sim time on ROS 2: scripts/hello_ros2.py flies its mission while an rclpy
listener reads its bridge, and Ctrl-C or SIGTERM stops it cleanly; the client's log reaches /rosout with
ROS 2 severities and the node's name; with `use_sim_time` the node's stamps follow /clock."""

from __future__ import annotations

import json
import signal
import subprocess
import time
from pathlib import Path

import pytest
from harness import Rig, wait_until
from ros2kit import ROOT, ros2_env

pytestmark = pytest.mark.live  # starts the server, the script or the node, and rclpy listeners

HELLO = ROOT / "scripts" / "hello_ros2.py"
NODE = ROOT / ".venv-ros2" / "bin" / "airsim-mapper-node"
LISTENER = Path(__file__).resolve().parent / "listen_ros2.py"
RECORDER = Path(__file__).resolve().parent / "record_ros2.py"
DRONE = "/airsim_node/Drone1"
TOPICS = {
    "pose": ("geometry_msgs/PoseStamped", f"{DRONE}/actual_pose"),
    "scene": ("sensor_msgs/Image", f"{DRONE}/DownCamera/scene_camera/image"),
    "info": ("sensor_msgs/CameraInfo", f"{DRONE}/DownCamera/scene_camera/camera_info"),
}
INFO, WARN, ERROR, FATAL = 20, 30, 40, 50  # rcl_interfaces/msg/Log's levels
STOPPED_WITHIN_S = 5.0


def listen(python: Path, domain: int, seconds: float, topics: dict = TOPICS) -> dict:
    """listen_ros2.py's first message of each of `topics`."""
    args = [f"{kind}={topic}" for kind, topic in topics.values()]
    out = subprocess.run(
        [str(python), str(LISTENER), str(seconds), *args],
        env=ros2_env(domain),
        capture_output=True,
        text=True,
        timeout=seconds + 60,
    )
    assert out.returncode == 0, out.stderr
    return json.loads(out.stdout.strip().splitlines()[-1])["topics"]


def start_recorder(python: Path, domain: int, seconds: float, *args: str) -> subprocess.Popen:
    """record_ros2.py, returned once it is subscribed."""
    recorder = subprocess.Popen(
        [str(python), str(RECORDER), str(seconds), *args],
        env=ros2_env(domain),
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )
    assert recorder.stdout.readline().strip() == "ready", recorder.stderr.read()
    return recorder


def records(recorder: subprocess.Popen, timeout: float) -> dict[str, list[dict]]:
    out, err = recorder.communicate(timeout=timeout)
    assert recorder.returncode == 0, err
    return json.loads(out.strip().splitlines()[-1])


def session_left(leader: int) -> list[int]:
    """The processes still in the session `leader` started (its pid is the session's id)."""
    left = []
    for stat in Path("/proc").glob("[0-9]*/stat"):
        try:
            fields = stat.read_text().rsplit(")", 1)[1].split()
        except (OSError, IndexError):
            continue
        if int(fields[3]) == leader and fields[0] != "Z":
            left.append(int(stat.parent.name))
    return left


@pytest.mark.parametrize("stop_signal", [signal.SIGINT, signal.SIGTERM], ids=["ctrl_c", "sigterm"])
def test_hello_ros2_flies_while_a_listener_reads_its_bridge_and_a_signal_stops_it_cleanly(
    launcher: Rig, ros2_python: Path, ros_domain: int, stop_signal: int
) -> None:
    server = launcher.simserver()
    launcher.env = {**ros2_env(ros_domain), "PYTHONUNBUFFERED": "1"}
    rosout = start_recorder(ros2_python, ros_domain, 90.0, "rcl_interfaces/Log=/rosout", "until:flying to")
    argv = [str(ros2_python), str(HELLO), *server.ports.args(), "--simconfigpath", str(ROOT / "sim_config")]
    mission = launcher.start("hello_ros2", argv)

    wait_until(lambda: "flying to" in mission.output(), 90, what="the mission's first leg")
    heard = listen(ros2_python, ros_domain, 30.0)
    assert heard.keys() == {topic for _kind, topic in TOPICS.values()}, mission.output()[-3000:]
    pose = heard[f"{DRONE}/actual_pose"]
    assert pose["frame_id"] == "map" and abs(pose["position"][2]) > 1.0  # taken off: the mission flies
    scene = heard[TOPICS["scene"][1]]
    assert (scene["encoding"], scene["data_len"]) == ("bgr8", 320 * 240 * 3)
    assert mission.alive()

    # The wrapper's node carries the client's log, the bridge's and the script's, with their severities.
    logged = records(rosout, 60)["/rosout"]
    client = [r for r in logged if r["text"] == "Connection opened."]
    assert client and client[0]["level"] == INFO and client[0]["name"] == "projectairsim", logged[:20]
    assert any(r["text"].startswith("flying to") and r["level"] == INFO for r in logged)

    started = time.monotonic()
    mission.popen.send_signal(stop_signal)
    assert mission.popen.wait(timeout=30) == 0, mission.output()[-3000:]
    assert time.monotonic() - started < STOPPED_WITHIN_S, mission.output()[-3000:]
    output = mission.output()
    assert "stopping the mission" in output and "Disconnected." in output, output[-3000:]
    assert "Traceback" not in output, output[-3000:]
    assert session_left(mission.pid) == []  # no thread or child process keeps anything running


def test_the_ros2_nodes_client_log_reaches_rosout_with_its_level_and_the_nodes_name(
    launcher: Rig, ros2_python: Path, ros_domain: int
) -> None:
    server = launcher.simserver()
    launcher.env = {**ros2_env(ros_domain), "PYTHONUNBUFFERED": "1"}
    rosout = start_recorder(ros2_python, ros_domain, 60.0, "rcl_interfaces/Log=/rosout", "until:bridged in")
    argv = [str(NODE), *server.ports.args(), "--simconfigpath", str(ROOT / "sim_config")]
    argv += ["--scene", "scene_basic_drone.jsonc", "--ros-args", "-r", "__node:=bridge_under_test"]
    node = launcher.start("node_ros2", argv)

    logged = records(rosout, 90)["/rosout"]
    texts = {r["text"]: r for r in logged}
    assert "Connection opened." in texts, node.output()[-3000:]  # the projectairsim client's own line
    for line in ("Connection opened.", "setting scene = 'scene_basic_drone.jsonc' (command line)"):
        assert (texts[line]["level"], texts[line]["name"]) == (INFO, "bridge_under_test"), texts[line]
    assert node.output().count("Connection opened.") == 1  # on the console once, through rclpy's logger
    node.popen.send_signal(signal.SIGINT)
    assert node.popen.wait(timeout=30) == 0, node.output()[-3000:]


def test_with_use_sim_time_the_ros2_nodes_stamps_follow_clock_and_stand_still_while_the_sim_is_paused(
    launcher: Rig, ros2_python: Path, ros_domain: int
) -> None:
    server = launcher.simserver()
    launcher.env = {**ros2_env(ros_domain), "PYTHONUNBUFFERED": "1"}
    argv = [str(NODE), *server.ports.args(), "--simconfigpath", str(ROOT / "sim_config")]
    argv += ["--scene", "scene_basic_drone.jsonc", "--ros-args", "-p", "use_sim_time:=true"]
    node = launcher.start("node_ros2", argv)
    wait_until(lambda: "bridged in" in node.output(), 60, what="the scene bridged")

    topics = ("rosgraph_msgs/Clock=/clock", "diagnostic_msgs/DiagnosticArray=/diagnostics")
    recorder = start_recorder(ros2_python, ros_domain, 9.0, *topics)
    time.sleep(4.0)
    sim = server.services_client()
    try:
        paused_at = time.time_ns()
        sim.request({"method": "/Sim/SceneBasicDrone/Pause", "params": {"do_pause": True}, "version": 1.0})
    finally:
        sim.disconnect()
    seen = records(recorder, 60)
    clock, diagnostics = seen["/clock"], seen["/diagnostics"]
    assert len(clock) > 50 and len(diagnostics) >= 6, node.output()[-3000:]

    # Sim time, not the wall clock: the scene's clock started at 0 when it was loaded, seconds ago.
    wall_ns = time.time_ns()
    assert all(0 < d["stamp_ns"] < 600 * 10**9 for d in diagnostics), diagnostics
    assert all(abs(d["stamp_ns"] - d["arrived_ns"]) > wall_ns // 2 for d in diagnostics)
    # While the simulator is paused /clock stops, and the stamps stand still at its last tick; the reports
    # still come once a second (the node's periods are wall time, as on ROS1, so that a paused or lost
    # simulator is still reported).
    last_tick = max(c["clock_ns"] for c in clock)
    quiet = [d for d in diagnostics if d["arrived_ns"] > paused_at + 1.5 * 10**9]
    assert len(quiet) >= 2, diagnostics
    (stood_at,) = {d["stamp_ns"] for d in quiet}
    assert abs(stood_at - last_tick) <= 50_000_000, (quiet, last_tick)  # a /clock tick this recorder missed
    running = [d for d in diagnostics if d["arrived_ns"] < paused_at]
    assert len({d["stamp_ns"] for d in running}) == len(running) >= 2  # sim time ran before the pause
    node.popen.send_signal(signal.SIGINT)
    assert node.popen.wait(timeout=30) == 0, node.output()[-3000:]


OWN_NODE_SCRIPT = """
import signal, sys
import rclpy
from airsim_mapper.wrapper import ProjectAirSimWrapper

signal.pthread_sigmask(signal.SIG_BLOCK, {signal.SIGINT})  # for sigwait, in every thread to come
rclpy.init()
wrapper = ProjectAirSimWrapper(
    topicsport=int(sys.argv[1]), servicesport=int(sys.argv[2]), sim_config_path=sys.argv[3],
    scene="scene_basic_drone.jsonc", node_name="mission_node",
)
print("bridging as", wrapper.ros_node.name, flush=True)
signal.sigwait({signal.SIGINT})
rclpy.shutdown()  # the wrapper shuts down with rclpy's context
print("closed" if wrapper.engine.state == "stopped" else f"still {wrapper.engine.state}", flush=True)
"""


def test_a_wrapper_given_no_node_makes_its_own_client_and_node_and_ends_with_rclpys_shutdown(
    launcher: Rig, ros2_python: Path, ros_domain: int, tmp_path: Path
) -> None:
    server = launcher.simserver()
    launcher.env = {**ros2_env(ros_domain), "PYTHONUNBUFFERED": "1"}
    script = tmp_path / "own_node.py"
    script.write_text(OWN_NODE_SCRIPT)
    ports = [str(server.ports.topics), str(server.ports.services), str(ROOT / "sim_config")]
    mission = launcher.start("own_node", [str(ros2_python), str(script), *ports], cwd=ROOT)
    wait_until(lambda: "bridging as /mission_node" in mission.output(), 60, what="the wrapper")
    heard = listen(ros2_python, ros_domain, 30.0, topics={"pose": TOPICS["pose"]})
    assert f"{DRONE}/actual_pose" in heard, mission.output()[-3000:]
    mission.popen.send_signal(signal.SIGINT)
    assert mission.popen.wait(timeout=30) == 0, mission.output()[-3000:]
    assert "closed" in mission.output() and "Traceback" not in mission.output(), mission.output()[-3000:]
