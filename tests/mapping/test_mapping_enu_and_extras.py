"""The ENU mapping, the first_robot domain, and the sensor, clock and service rules of the default mapping."""

from __future__ import annotations

import functools
from pathlib import Path

import pytest
from harness import ROOT, SIM_CONFIG
from simconfigs import EXAMPLE_SCENES, scenes_of

from airsim_mapper.mapping.expand import expand
from airsim_mapper.mapping.loader import load_mapping, load_mapping_text
from airsim_mapper.mapping.scene import Scene, read_scene

DEFAULT = ROOT / "mappings" / "default.yaml"
ENU = ROOT / "mappings" / "enu.yaml"
SCENES = sorted(path.name for path in SIM_CONFIG.glob("scene_*.jsonc"))


@functools.cache
def read_once(sim_config: Path, name: str) -> Scene:
    """A scene, read once per test run (reading a scene costs about half a second)."""
    return read_scene(sim_config, name)


@pytest.fixture(scope="module")
def scenes() -> dict:
    """Every scene of the project's own sim_config/."""
    return {name: read_once(SIM_CONFIG, name) for name in SCENES}


@pytest.fixture(scope="module")
def default_mapping():
    return load_mapping(DEFAULT)


@pytest.fixture(scope="module")
def enu_mapping():
    return load_mapping(ENU)


def by_ros(mapping, scene) -> dict:
    bridges = expand(mapping, scene, "projectairsim")
    return {bridge.ros: bridge for bridge in bridges if bridge.ros is not None}


@pytest.mark.parametrize(
    ("sim_config", "scene_file"), scenes_of(SCENES, EXAMPLE_SCENES), indirect=["sim_config"]
)
def test_enu_mapping_has_the_default_mappings_ros_names_and_types_on_every_scene(
    default_mapping, enu_mapping, sim_config, scene_file
):
    scene = read_once(sim_config, scene_file)
    default, enu = by_ros(default_mapping, scene), by_ros(enu_mapping, scene)
    assert {name: b.ros_type for name, b in enu.items()} == {name: b.ros_type for name, b in default.items()}
    assert {b.convention for b in enu.values()} == {"enu"}


def test_enu_mapping_uses_rep103_frame_names(enu_mapping, scenes):
    bridges = expand(enu_mapping, scenes["scene_drone_sensors.jsonc"], "projectairsim")
    ros = {b.ros: b for b in bridges if b.ros is not None}
    robot = "/airsim_node/Drone1"
    assert ros[f"{robot}/actual_pose"].tf.child == "Drone1/base_link"
    assert ros[f"{robot}/DownCamera/depth_camera/image"].frame_id == "Drone1/DownCamera/depth_camera_optical"
    info = ros[f"{robot}/Chase/scene_camera/camera_info"]
    assert info.frame_id == "Drone1/Chase/scene_camera_optical"
    assert ros["/airsim_streaming_camera/image_raw"].frame_id == "Drone1/Chase/scene_camera_optical"
    assert ros[f"{robot}/lidar1/lidar"].frame_id == "Drone1/lidar1"
    assert ros[f"{robot}/IMU1/imu"].frame_id == "Drone1/base_link"
    assert dict(ros[f"{robot}/odom"].params) == {"child_frame_id": "Drone1/base_link"}
    tf_only = sorted((b.converter, b.tf.child) for b in bridges if b.ros is None and "Chase" in b.tf.child)
    assert tf_only == [
        ("camera_optical_pose", "Drone1/Chase/scene_camera_optical"),
        ("camera_pose", "Drone1/Chase/scene_camera"),
    ]


def test_clock_comes_once_per_scene_from_the_first_robots_pose(default_mapping, scenes):
    bridges = expand(default_mapping, scenes["scene_two_drones_mixed.jsonc"], "n")
    clocks = [b for b in bridges if b.ros == "/clock"]
    assert [(b.name, b.sim, b.ros_type, b.converter) for b in clocks] == [
        (
            "clock[SceneTwoDronesMixed]",
            "/Sim/SceneTwoDronesMixed/robots/Drone1/actual_pose",
            "rosgraph_msgs/Clock",
            "clock",
        )
    ]


def test_first_robot_rules_expand_to_nothing_in_a_scene_without_robots(write_scene):
    mapping = load_mapping_text(
        """
version: 1
rules:
  - name: clock
    for_each: first_robot
    direction: sim_to_ros
    sim: /Sim/<scene_name>/robots/<robot_name>/actual_pose
    ros: /clock
    type: rosgraph_msgs/Clock
    converter: clock
"""
    )
    empty = read_scene(write_scene({}), "scene.jsonc")
    two = read_scene(write_scene({"B": [], "A": []}, name="two.jsonc"), "two.jsonc")
    assert expand(mapping, empty, "n") == ()
    assert [b.variables["robot_name"] for b in expand(mapping, two, "n")] == ["B"]


def test_a_first_robot_rule_may_not_use_sensor_variables():
    text = """
version: 1
rules:
  - name: clock
    for_each: first_robot
    direction: sim_to_ros
    sim: /Sim/<scene_name>/robots/<robot_name>/sensors/<sensor_name>/x
    ros: /clock
    type: rosgraph_msgs/Clock
    converter: clock
"""
    with pytest.raises(
        Exception, match=r"unknown template variable <sensor_name> in sim for for_each first_robot"
    ):
        load_mapping_text(text)


def test_default_mapping_publishes_every_instrument_with_its_type_and_frame(default_mapping, scenes):
    ros = by_ros(default_mapping, scenes["scene_drone_sensors.jsonc"])
    robot = "/airsim_node/Drone1"
    sensors = "/Sim/SceneDroneSensors/robots/Drone1/sensors"
    expected = {
        f"{robot}/IMU1/imu": ("sensor_msgs/Imu", f"{sensors}/IMU1/imu_kinematics", "airsim_node/Drone1"),
        f"{robot}/GPS/gps": ("sensor_msgs/NavSatFix", f"{sensors}/GPS/gps", "airsim_node/Drone1"),
        f"{robot}/Barometer/barometer": (
            "sensor_msgs/FluidPressure",
            f"{sensors}/Barometer/barometer",
            "airsim_node/Drone1",
        ),
        f"{robot}/Magnetometer/magnetometer": (
            "sensor_msgs/MagneticField",
            f"{sensors}/Magnetometer/magnetometer",
            "airsim_node/Drone1",
        ),
        f"{robot}/DistanceSensor/distance": (
            "sensor_msgs/Range",
            f"{sensors}/DistanceSensor/distance_sensor",
            "airsim_node/Drone1/DistanceSensor",
        ),
        f"{robot}/Battery/battery": (
            "sensor_msgs/BatteryState",
            f"{sensors}/Battery/battery",
            "airsim_node/Drone1",
        ),
        f"{robot}/Airspeed/airspeed": (
            "sensor_msgs/FluidPressure",
            f"{sensors}/Airspeed/airspeed",
            "airsim_node/Drone1",
        ),
        f"{robot}/odom": ("nav_msgs/Odometry", "/Sim/SceneDroneSensors/robots/Drone1/actual_pose", "map"),
        f"{robot}/collision": (
            "geometry_msgs/PointStamped",
            "/Sim/SceneDroneSensors/robots/Drone1/collision_info",
            "map",
        ),
    }
    assert {name: (ros[name].ros_type, ros[name].sim, ros[name].frame_id) for name in expected} == expected
    (frame,) = [
        b
        for b in expand(default_mapping, scenes["scene_drone_sensors.jsonc"], "projectairsim")
        if b.rule == "distance_tf"
    ]
    assert (frame.tf.child, frame.converter) == ("airsim_node/Drone1/DistanceSensor", "sensor_pose")


def test_default_mapping_maps_each_control_service_to_its_simulator_method(default_mapping, scenes):
    ros = by_ros(default_mapping, scenes["scene_drone_sensors.jsonc"])
    robot, sim = "/airsim_node/Drone1", "/Sim/SceneDroneSensors/robots/Drone1"
    rows = {
        name: (b.ros_kind, b.ros_type, b.sim, b.converter, dict(b.params))
        for name, b in ros.items()
        if b.ros_kind == "service" and name != "/airsim_streaming_camera/switch_view"
    }
    assert rows == {
        f"{robot}/takeoff": (
            "service",
            "std_srvs/Trigger",
            f"{sim}/Takeoff",
            "trigger",
            {"args": {"timeout_sec": 20}},
        ),
        f"{robot}/land": (
            "service",
            "std_srvs/Trigger",
            f"{sim}/Land",
            "trigger",
            {"args": {"timeout_sec": 60}},
        ),
        f"{robot}/hover": ("service", "std_srvs/Trigger", f"{sim}/Hover", "trigger", {}),
        f"{robot}/arm": ("service", "std_srvs/Trigger", f"{sim}/Arm", "trigger", {}),
        f"{robot}/disarm": ("service", "std_srvs/Trigger", f"{sim}/Disarm", "trigger", {}),
        f"{robot}/enable_api_control": (
            "service",
            "std_srvs/Trigger",
            f"{sim}/EnableApiControl",
            "trigger",
            {},
        ),
        f"{robot}/disable_api_control": (
            "service",
            "std_srvs/Trigger",
            f"{sim}/DisableApiControl",
            "trigger",
            {},
        ),
        f"{robot}/reset": ("service", "std_srvs/Trigger", f"{sim}/SetPose", "reset_pose", {}),
        "/airsim_node/pause": (
            "service",
            "std_srvs/SetBool",
            "/Sim/SceneDroneSensors/Pause",
            "set_bool",
            {"arg": "do_pause"},
        ),
        "/airsim_node/step": (
            "service",
            "std_srvs/Trigger",
            "/Sim/SceneDroneSensors/ContinueForSingleStep",
            "trigger",
            {"args": {"wait_until_complete": True}},
        ),
        **{
            f"/airsim_node/{verb}_all": (
                "service",
                "std_srvs/Trigger",
                "/Sim/SceneDroneSensors/robots",
                "trigger_all",
                {"method": method, **({"args": args} if args else {})},
            )
            for verb, method, args in (
                ("takeoff", "Takeoff", {"timeout_sec": 20}),
                ("land", "Land", {"timeout_sec": 60}),
                ("hover", "Hover", {}),
                ("arm", "Arm", {}),
                ("disarm", "Disarm", {}),
            )
        },
    }
