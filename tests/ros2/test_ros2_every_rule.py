"""Every rule of the shipped mappings over every sample scene, on ROS 2: one node per mapping and scene,
and one rclpy process that takes the whole expanded list. Each published topic delivers a message of its
type to a subscriber with the bridge's QoS, and the graph shows the publisher with that QoS; each
subscriber and service is there with its type, and each service answers a call (with success, or with the
simulator's refusal of a method its robot does not have). Every image has its type's encoding, the
capture setting's size and a matching step; every camera_info the intrinsics of the camera's fov and size.
Project AirSim's example scenes (`../shared/sim_config`) are checked as well where they are present."""

from __future__ import annotations

import json
import math
import signal
import subprocess
from pathlib import Path

import pytest
from harness import Rig
from ros2kit import ROOT, ros2_env
from simconfigs import EXAMPLE_SCENES, scenes_of

from airsim_mapper.common.image_types import DOCUMENTED_IMAGE_TYPES, FLOAT_IMAGE_TYPES
from airsim_mapper.convert import catalog
from airsim_mapper.convert.camera_info import DEFAULT_FOV_DEGREES
from airsim_mapper.mapping.expand import expand
from airsim_mapper.mapping.loader import load_mapping
from airsim_mapper.mapping.model import BridgeSpec, Qos
from airsim_mapper.mapping.qos import TF_QOS, TF_STATIC_QOS, node_topic_qos
from airsim_mapper.mapping.reserved import status_topic
from airsim_mapper.mapping.scene import read_scene

pytestmark = pytest.mark.live  # starts the server, the node and an rclpy process

NODE = ROOT / ".venv-ros2" / "bin" / "airsim-mapper-node"
SCRIPT = Path(__file__).resolve().parent / "rules_ros2.py"
NODE_NAME = "projectairsim"
MAPPINGS = ("default", "enu")
SCENES = sorted(path.name for path in (ROOT / "sim_config").glob("scene_*.jsonc"))
# The services are called one after the other, the flights first, in this order of their rules: a landing
# from the start height (4 m at 0.2 m/s), then take-offs from the ground (the other services disarm and
# reset the robots). A flight answers when the robot has arrived, 5-25 s: flights are called on one scene.
CALL_ORDER = {"land": -4, "land_all": -3, "takeoff": -2, "takeoff_all": -1}
FLIGHT_SCENE = "scene_drone_sensors.jsonc"
CASES = [
    pytest.param(mapping, *case.values, id=f"{mapping}-{case.id}")
    for mapping in MAPPINGS
    for case in scenes_of(SCENES, EXAMPLE_SCENES)
]


def settings(qos: Qos) -> list:
    return [qos.reliability, qos.durability, qos.depth, qos.history]


def expected_endpoints(bridges: list[BridgeSpec], flights: bool) -> dict:
    """What the node should offer: its publishers (the bridges' and its own) with type and QoS, its
    subscribers and services with their types; and the services to call (the flights only if `flights`)."""
    publishers = {
        b.ros: (b.ros_type, b.qos) for b in bridges if b.ros is not None and b.direction == "sim_to_ros"
    }
    events = {b.ros for b in bridges if b.ros in publishers and catalog.CONVERTERS[b.converter].events}
    publishers[status_topic(NODE_NAME)] = ("std_msgs/String", node_topic_qos(latch=True))
    publishers["/diagnostics"] = ("diagnostic_msgs/DiagnosticArray", node_topic_qos(latch=False))
    tfs = [b.tf for b in bridges if b.tf is not None]
    if any(not tf.static for tf in tfs):
        publishers["/tf"] = ("tf2_msgs/TFMessage", TF_QOS)
    if any(tf.static for tf in tfs):
        publishers["/tf_static"] = ("tf2_msgs/TFMessage", TF_STATIC_QOS)
    subscribers = {
        b.ros: (b.ros_type, b.qos) for b in bridges if b.direction == "ros_to_sim" and b.ros_kind == "topic"
    }
    calls = sorted((b for b in bridges if b.ros_kind == "service"), key=lambda b: CALL_ORDER.get(b.rule, 0))
    services = {b.ros: b.ros_type for b in calls}
    called = [b.ros for b in calls if flights or b.rule not in CALL_ORDER]
    return {
        "publishers": publishers,
        "events": events,
        "subscribers": subscribers,
        "services": services,
        "called": called,
    }


def image_problems(bridge: BridgeSpec, image: dict) -> list[str]:
    """How a received Image differs from what its capture setting asks for (empty: it does not)."""
    depth = bridge.source["image-type"] in FLOAT_IMAGE_TYPES
    width, height = bridge.source["width"], bridge.source["height"]
    wanted = {
        "encoding": "32FC1" if depth else "bgr8",
        "width": width,
        "height": height,
        "step": width * (4 if depth else 3),
        "data_len": width * (4 if depth else 3) * height,
        "frame_id": bridge.frame_id,
    }
    return [
        f"{bridge.ros}: {key} {image[key]!r}, not {value!r}"
        for key, value in wanted.items()
        if image[key] != value
    ]


def camera_info_problems(bridge: BridgeSpec, info: dict) -> list[str]:
    """How a received CameraInfo differs from the pinhole model of its camera's fov and size."""
    width, height = bridge.source["width"], bridge.source["height"]
    f = (width / 2) / math.tan(math.radians(bridge.source.get("fov-degrees", DEFAULT_FOV_DEGREES)) / 2)
    cx, cy = width / 2, height / 2
    wanted = {
        "width": width,
        "height": height,
        "k": [f, 0.0, cx, 0.0, f, cy, 0.0, 0.0, 1.0],
        "p": [f, 0.0, cx, 0.0, 0.0, f, cy, 0.0, 0.0, 0.0, 1.0, 0.0],
        "frame_id": bridge.frame_id,
    }
    return [
        f"{bridge.ros}: {key} {info[key]!r}, not {value!r}"
        for key, value in wanted.items()
        if not (info[key] == pytest.approx(value) if key in ("k", "p") else info[key] == value)
    ]


def camera_problems(bridges: list[BridgeSpec], topics: dict) -> list[str]:
    checks = {"camera_image": image_problems, "camera_info": camera_info_problems}
    return [
        problem
        for bridge in bridges
        if bridge.rule in checks and bridge.ros in topics
        for problem in checks[bridge.rule](bridge, topics[bridge.ros])
    ]


def test_the_flight_scene_has_a_camera_of_each_of_the_seven_image_types():
    scene = read_scene(ROOT / "sim_config", FLIGHT_SCENE)
    bridges = expand(load_mapping(ROOT / "mappings" / "default.yaml"), scene, NODE_NAME)
    images = {b.variables["image_type"] for b in bridges if b.rule == "camera_image"}
    assert images == set(DOCUMENTED_IMAGE_TYPES.values())


def probe(python: Path, domain: int, expected: dict, seconds: float) -> dict:
    request = {
        "seconds": seconds,
        "node": f"/{NODE_NAME}",
        "publishers": [
            {"topic": topic, "type": ros_type, "qos": settings(qos), "events": topic in expected["events"]}
            for topic, (ros_type, qos) in expected["publishers"].items()
        ],
        "subscribers": [{"name": name, "type": t} for name, (t, _qos) in expected["subscribers"].items()],
        "services": [{"name": name, "type": expected["services"][name]} for name in expected["called"]],
    }
    out = subprocess.run(
        [str(python), str(SCRIPT)],
        input=json.dumps(request),
        env=ros2_env(domain),
        capture_output=True,
        text=True,
        timeout=seconds + 120,
    )
    assert out.returncode == 0, out.stderr
    return json.loads(out.stdout.strip().splitlines()[-1])


@pytest.mark.parametrize(("mapping", "sim_config", "scene_file"), CASES, indirect=["sim_config"])
def test_every_rule_of_the_mapping_delivers_its_type_with_its_qos_on_ros2(
    launcher: Rig, ros2_python: Path, ros_domain: int, mapping: str, sim_config: Path, scene_file: str
) -> None:
    mapping_file = ROOT / "mappings" / f"{mapping}.yaml"
    bridges = expand(load_mapping(mapping_file), read_scene(sim_config, scene_file), NODE_NAME)
    expected = expected_endpoints(
        bridges, flights=(sim_config, scene_file) == (ROOT / "sim_config", FLIGHT_SCENE)
    )
    server = launcher.simserver()
    launcher.env = {**ros2_env(ros_domain), "PYTHONUNBUFFERED": "1"}
    argv = [str(NODE), *server.ports.args(), "--simconfigpath", str(sim_config), "--scene", scene_file]
    node = launcher.start("node_ros2", [*argv, "--mapping", str(mapping_file), "--no-watch"])
    seen = probe(ros2_python, ros_domain, expected, 90.0)
    log = node.output()[-3000:]

    publishers = expected["publishers"]
    silent = sorted(set(publishers) - expected["events"] - set(seen["topics"]))
    assert silent == [], f"{silent} delivered nothing; node log:\n{log}"
    for topic, (ros_type, qos) in publishers.items():
        if topic in seen["topics"]:
            assert seen["topics"][topic]["type"] == ros_type.rpartition("/")[2], topic
        offered = [{"type": ros_type, "qos": [qos.reliability, qos.durability]}]
        assert seen["graph"]["publishers"][topic] == offered, topic
    assert camera_problems(bridges, seen["topics"]) == []
    for name, (ros_type, qos) in expected["subscribers"].items():
        wanted = [{"type": ros_type, "qos": [qos.reliability, qos.durability]}]
        assert seen["graph"]["subscribers"][name] == wanted, name
    for name, ros_type in expected["services"].items():
        assert seen["graph"]["services"].get(name) == [ros_type], name
    for name in expected["called"]:
        answer = seen["answers"][name]
        assert answer is not None, f"{name} did not answer in {seen['took'][name]} s; node log:\n{log}"
        # the simulator's refusal, passed on, is an answer too (a radar tower does not hover)
        assert answer["success"] is True or "is not supported" in answer["message"], (name, answer)

    node.popen.send_signal(signal.SIGINT)
    assert node.popen.wait(timeout=30) == 0, node.output()[-3000:]
