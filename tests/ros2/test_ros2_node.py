"""The node on ROS 2: .venv-ros2's airsim-mapper-node bridges the headless server with the shipped default
mapping, and an rclpy listener in another process reads its pose, images, camera_info, lidar, radar, tf,
clock and diagnostics, and calls a service; SIGINT stops the node cleanly."""

from __future__ import annotations

import json
import math
import signal
import subprocess
from pathlib import Path

import pytest
from harness import Rig
from ros2kit import ROOT, ros2_env

pytestmark = pytest.mark.live  # starts the server, the node and a listener

NODE = ROOT / ".venv-ros2" / "bin" / "airsim-mapper-node"
LISTENER = Path(__file__).resolve().parent / "listen_ros2.py"
DRONE = "/airsim_node/Drone1"
TOPICS = {
    "pose": ("geometry_msgs/PoseStamped", f"{DRONE}/actual_pose"),
    "scene": ("sensor_msgs/Image", f"{DRONE}/DownCamera/scene_camera/image"),
    "depth": ("sensor_msgs/Image", f"{DRONE}/DownCamera/depth_planar_camera/image"),
    "info": ("sensor_msgs/CameraInfo", f"{DRONE}/DownCamera/scene_camera/camera_info"),
    "jpeg": ("sensor_msgs/CompressedImage", f"{DRONE}/DownCamera/scene_camera/image/compressed"),
    "depth_png": (
        "sensor_msgs/CompressedImage",
        f"{DRONE}/DownCamera/depth_planar_camera/image/compressedDepth",
    ),
    "lidar": ("sensor_msgs/PointCloud2", f"{DRONE}/lidar1/lidar"),
    "radar": ("radar_msgs/RadarScan", f"{DRONE}/radar1/radar_detections"),
    "tf": ("tf2_msgs/TFMessage", "/tf"),
    "tf_static": ("tf2_msgs/TFMessage", "/tf_static"),
    "clock": ("rosgraph_msgs/Clock", "/clock"),
    "diagnostics": ("diagnostic_msgs/DiagnosticArray", "/diagnostics"),
}
TAKEOFF = f"{DRONE}/takeoff"


def listen(python: Path, domain: int, seconds: float, *extra: str, topics: dict | None = None) -> dict:
    args = [f"{kind}={topic}" for kind, topic in (topics or TOPICS).values()]
    out = subprocess.run(
        [str(python), str(LISTENER), str(seconds), *args, *extra],
        env=ros2_env(domain),
        capture_output=True,
        text=True,
        timeout=seconds + 60,
    )
    assert out.returncode == 0, out.stderr
    return json.loads(out.stdout.strip().splitlines()[-1])


def test_the_ros2_node_bridges_the_default_mapping_and_stops_on_sigint(
    launcher: Rig, ros2_python: Path, ros_domain: int
) -> None:
    server = launcher.simserver()
    launcher.env = {**ros2_env(ros_domain), "PYTHONUNBUFFERED": "1"}  # the node's environment: .venv-ros2's
    argv = [str(NODE), *server.ports.args(), "--simconfigpath", str(ROOT / "sim_config")]
    node = launcher.start("node_ros2", [*argv, "--scene", "scene_drone_sensors.jsonc", "--ros", "2"])

    heard = listen(ros2_python, ros_domain, 60.0, f"call:{TAKEOFF}")
    topics = heard["topics"]
    missing = [name for name, (_kind, topic) in TOPICS.items() if topic not in topics]
    assert missing == [], f"{missing} never arrived; node log:\n{node.output()[-3000:]}"

    pose = topics[f"{DRONE}/actual_pose"]
    assert pose["frame_id"] == "map"
    assert math.isclose(sum(v * v for v in pose["orientation"]), 1.0, rel_tol=1e-6)

    scene = topics[TOPICS["scene"][1]]
    assert (scene["encoding"], scene["width"], scene["height"]) == ("bgr8", 320, 240)
    assert scene["step"] == 320 * 3 and scene["data_len"] == 320 * 240 * 3
    assert scene["frame_id"] == "airsim_node/Drone1/DownCamera/scene_camera_optical"
    depth = topics[TOPICS["depth"][1]]
    assert (depth["encoding"], depth["data_len"]) == ("32FC1", 320 * 240 * 4)

    jpeg, depth_png = topics[TOPICS["jpeg"][1]], topics[TOPICS["depth_png"][1]]
    assert jpeg["format"] == "bgr8; jpeg compressed bgr8" and 0 < jpeg["data_len"] < 320 * 240 * 3
    assert depth_png["format"] == "32FC1; compressedDepth png" and depth_png["data_len"] > 12 + 8
    info = topics[TOPICS["info"][1]]
    f = info["k"][0]
    assert info["k"] == [f, 0.0, 160.0, 0.0, f, 120.0, 0.0, 0.0, 1.0]
    assert info["p"] == [f, 0.0, 160.0, 0.0, 0.0, f, 120.0, 0.0, 0.0, 0.0, 1.0, 0.0]
    assert math.isclose(f, 160.0) and info["distortion_model"] == "plumb_bob" and info["d"] == [0.0] * 5

    lidar = topics[TOPICS["lidar"][1]]
    assert lidar["fields"] == ["x", "y", "z", "intensity", "segmentation"]
    assert (
        lidar["width"] > 0 and lidar["data_len"] == lidar["width"] * lidar["point_step"] == lidar["row_step"]
    )

    radar = topics[TOPICS["radar"][1]]
    assert radar["frame_id"] == "airsim_node/Drone1/radar1" and radar["returns"] >= 0

    assert "map>airsim_node/Drone1" in topics["/tf"]["frames"]
    static = topics["/tf_static"]["frames"]
    assert "airsim_node/Drone1>airsim_node/Drone1/DownCamera/scene_camera_optical" in static
    assert "airsim_node/Drone1>airsim_node/Drone1/lidar1" in static
    assert topics["/clock"]["clock"][0] * 10**9 + topics["/clock"]["clock"][1] > 0

    assert "projectairsim: simulator" in topics["/diagnostics"]["statuses"]

    assert heard["services"][TAKEOFF] == {"success": True, "message": ""}

    node.popen.send_signal(signal.SIGINT)
    assert node.popen.wait(timeout=30) == 0, node.output()[-3000:]
    assert "stopping (SIGINT)" in node.output()
    assert "Traceback" not in node.output()


def test_ros2_parameters_set_the_settings_a_namespace_moves_topics_and_frames_and_reload_is_served(
    launcher: Rig, ros2_python: Path, ros_domain: int
) -> None:
    server = launcher.simserver()
    launcher.env = {**ros2_env(ros_domain), "PYTHONUNBUFFERED": "1"}
    parameters = [f"topicsport:={server.ports.topics}", f"servicesport:={server.ports.services}"]
    parameters.append("scene:=scene_basic_drone.jsonc")
    argv = [str(NODE), "--simconfigpath", str(ROOT / "sim_config"), "--ros-args", "-r", "__ns:=/sim1"]
    node = launcher.start("node_ros2", [*argv, *(a for p in parameters for a in ("-p", p))])

    topics = {"pose": ("geometry_msgs/PoseStamped", "/sim1/airsim_node/Drone1/actual_pose")}
    reload = "/sim1/projectairsim/reload_mapping"
    answers = listen(ros2_python, ros_domain, 60.0, f"call:{reload}", topics=topics)
    heard = answers["topics"]
    assert heard["/sim1/airsim_node/Drone1/actual_pose"]["frame_id"] == "sim1/map", node.output()[-3000:]
    assert "setting scene = 'scene_basic_drone.jsonc' (parameter ~scene)" in node.output()
    assert answers["services"][reload]["success"] is True, answers  # the node's private service: live reload
    node.popen.send_signal(signal.SIGINT)
    assert node.popen.wait(timeout=30) == 0, node.output()[-3000:]


def test_a_lazy_image_stream_follows_its_ros2_subscribers_as_they_come_and_go(
    launcher: Rig, ros2_python: Path, ros_domain: int
) -> None:
    server = launcher.simserver()
    launcher.env = {**ros2_env(ros_domain), "PYTHONUNBUFFERED": "1"}
    argv = [str(NODE), *server.ports.args(), "--simconfigpath", str(ROOT / "sim_config")]
    node = launcher.start("node_ros2", [*argv, "--scene", "scene_drone_sensors.jsonc"])
    script = Path(__file__).resolve().parent / "lazy_ros2.py"
    status, image = "/airsim_mapper/projectairsim/status", TOPICS["scene"][1]
    out = subprocess.run(
        [str(ros2_python), str(script), status, image, "/DownCamera/scene_camera", "3"],
        env=ros2_env(ros_domain),
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert out.returncode == 0, out.stderr
    seen = json.loads(out.stdout.strip().splitlines()[-1])
    print(seen)
    assert seen["before"] is False, seen
    for cycle in seen["cycles"]:  # subscribed while a subscriber is there, each time
        assert cycle["images"] > 0, node.output()[-3000:]
        assert (cycle["during"], cycle["after"]) == (True, False), seen
    two = seen["two"]  # two subscribers, one leaves: the stream stays for the other, then goes with it
    assert min(two["images"]) > 0 and two["images_after_one_left"] > 3, seen
    assert (two["both"], two["one_left"], two["after"]) == (True, True, False), seen


def test_a_scene_named_on_load_scene_is_loaded_and_bridged(
    launcher: Rig, ros2_python: Path, ros_domain: int
) -> None:
    server = launcher.simserver()
    launcher.env = {**ros2_env(ros_domain), "PYTHONUNBUFFERED": "1"}
    argv = [str(NODE), *server.ports.args(), "--simconfigpath", str(ROOT / "sim_config")]
    node = launcher.start("node_ros2", argv)  # no scene: waits for one on load_scene
    load_scene = "/ProjectAirSim/node/projectairsim/load_scene"
    topics = {"pose": TOPICS["pose"]}
    heard = listen(ros2_python, ros_domain, 60.0, f"say:{load_scene}=scene_basic_drone.jsonc", topics=topics)
    assert TOPICS["pose"][1] in heard["topics"], node.output()[-3000:]
    assert "SceneBasicDrone" in node.output()


def test_a_name_ros2_refuses_stops_the_ros2_node_with_its_place(tmp_path: Path, ros_domain: int) -> None:
    mapping = tmp_path / "m.yaml"
    mapping.write_text(
        "version: 1\nrules:\n  - name: pose\n    for_each: robot\n    direction: sim_to_ros\n"
        "    converter: pose\n    sim: /Sim/<scene_name>/robots/<robot_name>/actual_pose\n"
        "    ros: /x/<robot_name>/0pose\n    type: geometry_msgs/PoseStamped\n"
    )
    argv = [str(NODE), "--mapping", str(mapping), "--scene", "scene_drone_sensors.jsonc"]
    argv += ["--simconfigpath", str(ROOT / "sim_config"), "--topicsport", "1", "--servicesport", "2"]
    run = subprocess.run(argv, env=ros2_env(ros_domain), capture_output=True, text=True, timeout=60)
    assert run.returncode == 1
    assert f"{mapping}:8:10: " in run.stderr  # located, and before any connection to the simulator


def test_qos_named_in_a_mapping_decides_which_subscribers_match(
    launcher: Rig, ros2_python: Path, ros_domain: int, tmp_path: Path
) -> None:
    mapping = tmp_path / "reliable_images.yaml"
    mapping.write_text("version: 1\nextends: default\nrules:\n  - {name: camera_image, qos: default}\n")
    server = launcher.simserver()
    launcher.env = {**ros2_env(ros_domain), "PYTHONUNBUFFERED": "1"}
    argv = [str(NODE), *server.ports.args(), "--simconfigpath", str(ROOT / "sim_config")]
    node = launcher.start(
        "node_ros2", [*argv, "--scene", "scene_drone_sensors.jsonc", "--mapping", str(mapping)]
    )
    image, lidar = TOPICS["scene"], TOPICS["lidar"]
    topics = {
        "image reliable": (image[0], f"{image[1]}@reliable"),  # the rule's qos: default (reliable)
        "image best effort": image,
        "lidar best effort": lidar,  # the catalogue's sensor_data (best effort)
        "lidar reliable": (lidar[0], f"{lidar[1]}@reliable"),  # does not match a best-effort publisher
    }
    heard = listen(ros2_python, ros_domain, 20.0, topics=topics)["topics"]
    assert {f"{image[1]}@reliable", image[1], lidar[1]} <= heard.keys(), node.output()[-3000:]
    assert f"{lidar[1]}@reliable" not in heard


def test_while_the_simulator_is_not_there_the_status_says_connecting(
    launcher: Rig, ros2_python: Path, ros_domain: int
) -> None:
    from harness import SimPorts

    launcher.env = {**ros2_env(ros_domain), "PYTHONUNBUFFERED": "1"}
    argv = [str(NODE), *SimPorts.free().args(), "--simconfigpath", str(ROOT / "sim_config")]
    node = launcher.start("node_ros2", argv)  # nothing listens on those ports
    topics = {"status": ("std_msgs/String", "/airsim_mapper/projectairsim/status")}
    heard = listen(ros2_python, ros_domain, 30.0, topics=topics)["topics"]
    assert "/airsim_mapper/projectairsim/status" in heard, node.output()[-3000:]
    status = json.loads(heard["/airsim_mapper/projectairsim/status"]["text"])
    assert status["state"] == "connecting" and status["attempts"] >= 1
    node.popen.send_signal(signal.SIGINT)
    assert node.popen.wait(timeout=30) == 0, node.output()[-3000:]
