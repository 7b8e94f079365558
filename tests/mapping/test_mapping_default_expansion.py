"""The default mapping expands every scene to exactly the documented interface: the project's own scenes,
and Project AirSim's example scenes where present."""

from __future__ import annotations

from pathlib import Path

import pytest
from harness import EXAMPLE_CONFIG, ROOT, SIM_CONFIG
from simconfigs import EXAMPLE_SCENES, both_configs, scenes_of

from airsim_mapper.mapping.expand import expand
from airsim_mapper.mapping.loader import load_mapping
from airsim_mapper.mapping.model import TfSpec
from airsim_mapper.mapping.scene import read_scene

DEFAULT = ROOT / "mappings" / "default.yaml"
LOAD_SCENE = "/ProjectAirSim/node/projectairsim/load_scene"
STREAMING = ["/airsim_streaming_camera/image_raw", "/airsim_streaming_camera/switch_view"]
ALL_ROBOTS = [f"/airsim_node/{verb}_all" for verb in ("takeoff", "land", "hover", "arm", "disarm")]
SCENE_WIDE = ["/clock", "/airsim_node/pause", "/airsim_node/step", *ALL_ROBOTS]
ROBOT_SERVICES = (
    "takeoff",
    "land",
    "hover",
    "arm",
    "disarm",
    "enable_api_control",
    "disable_api_control",
    "reset",
)


def _robot_extras(robot: str) -> list[str]:
    """Odometry, collisions and the control services every robot gets."""
    base = f"/airsim_node/{robot}"
    return [f"{base}/odom", f"{base}/collision", *(f"{base}/{name}" for name in ROBOT_SERVICES)]


def _instruments(robot: str) -> list[str]:
    """The instruments of robot_quadrotor_sensors.jsonc and robot_quadrotor_survey.jsonc (project) and of
    robot_quadrotor_fastphysics_sensors.jsonc (example), one topic each."""
    base = f"/airsim_node/{robot}"
    return [
        f"{base}/IMU1/imu",
        f"{base}/GPS/gps",
        f"{base}/Barometer/barometer",
        f"{base}/Magnetometer/magnetometer",
        f"{base}/DistanceSensor/distance",
        f"{base}/Battery/battery",
        f"{base}/Airspeed/airspeed",
    ]


DEPTH_TYPES = ("depth_planar_camera", "depth_camera")  # float images: compressedDepth, not compressed


def _transport(image_topic: str) -> str:
    """image_transport's sibling topic of an image: compressedDepth for depth images, else compressed."""
    image_type = image_topic.rsplit("/", 2)[-2]
    return f"{image_topic}/{'compressedDepth' if image_type in DEPTH_TYPES else 'compressed'}"


# the example scene_drone_sensors.jsonc, written out in full from the documented topic list.
DRONE_SENSORS_TOPICS = [
    LOAD_SCENE,
    "/airsim_node/Drone1/actual_pose",
    "/airsim_node/Drone1/cmd_vel",
    "/airsim_node/Drone1/desired_pose",
    "/airsim_node/Drone1/Chase/desired_pose",
    "/airsim_node/Drone1/DownCamera/desired_pose",
    "/airsim_node/Drone1/Chase/camera_pose",
    "/airsim_node/Drone1/DownCamera/camera_pose",
    "/airsim_node/Drone1/Chase/scene_camera/image",
    "/airsim_node/Drone1/DownCamera/scene_camera/image",
    "/airsim_node/Drone1/DownCamera/depth_planar_camera/image",
    "/airsim_node/Drone1/DownCamera/depth_camera/image",
    "/airsim_node/Drone1/DownCamera/segmentation_camera/image",
    "/airsim_node/Drone1/DownCamera/depth_vis_camera/image",
    "/airsim_node/Drone1/DownCamera/disparity_normalized_camera/image",
    "/airsim_node/Drone1/DownCamera/surface_normals/image",
    "/airsim_node/Drone1/Chase/scene_camera/camera_info",
    "/airsim_node/Drone1/DownCamera/scene_camera/camera_info",
    "/airsim_node/Drone1/DownCamera/depth_planar_camera/camera_info",
    "/airsim_node/Drone1/DownCamera/depth_camera/camera_info",
    "/airsim_node/Drone1/DownCamera/segmentation_camera/camera_info",
    "/airsim_node/Drone1/DownCamera/depth_vis_camera/camera_info",
    "/airsim_node/Drone1/DownCamera/disparity_normalized_camera/camera_info",
    "/airsim_node/Drone1/DownCamera/surface_normals/camera_info",
    "/airsim_node/Drone1/Chase/scene_camera/image/compressed",
    "/airsim_node/Drone1/DownCamera/scene_camera/image/compressed",
    "/airsim_node/Drone1/DownCamera/depth_planar_camera/image/compressedDepth",
    "/airsim_node/Drone1/DownCamera/depth_camera/image/compressedDepth",
    "/airsim_node/Drone1/DownCamera/segmentation_camera/image/compressed",
    "/airsim_node/Drone1/DownCamera/depth_vis_camera/image/compressed",
    "/airsim_node/Drone1/DownCamera/disparity_normalized_camera/image/compressed",
    "/airsim_node/Drone1/DownCamera/surface_normals/image/compressed",
    "/airsim_node/Drone1/lidar1/lidar",
    *_robot_extras("Drone1"),
    *_instruments("Drone1"),
    *STREAMING,
]


def _basic_drone(robot: str) -> list[str]:
    """robot_quadrotor_basic.jsonc (project) and robot_quadrotor_fastphysics.jsonc (example): Chase (scene),
    DownCamera (scene, depth); no lidar or radar."""
    return [
        f"/airsim_node/{robot}/actual_pose",
        f"/airsim_node/{robot}/cmd_vel",
        f"/airsim_node/{robot}/desired_pose",
        f"/airsim_node/{robot}/Chase/desired_pose",
        f"/airsim_node/{robot}/DownCamera/desired_pose",
        f"/airsim_node/{robot}/Chase/camera_pose",
        f"/airsim_node/{robot}/DownCamera/camera_pose",
        f"/airsim_node/{robot}/Chase/scene_camera/image",
        f"/airsim_node/{robot}/DownCamera/scene_camera/image",
        f"/airsim_node/{robot}/DownCamera/depth_camera/image",
        f"/airsim_node/{robot}/Chase/scene_camera/camera_info",
        f"/airsim_node/{robot}/DownCamera/scene_camera/camera_info",
        f"/airsim_node/{robot}/DownCamera/depth_camera/camera_info",
        f"/airsim_node/{robot}/Chase/scene_camera/image/compressed",
        f"/airsim_node/{robot}/DownCamera/scene_camera/image/compressed",
        f"/airsim_node/{robot}/DownCamera/depth_camera/image/compressedDepth",
        f"/airsim_node/{robot}/IMU1/imu",
        *_robot_extras(robot),
    ]


def _robot(robot: str) -> list[str]:
    """The pose, command and service topics every robot gets."""
    base = f"/airsim_node/{robot}"
    return [f"{base}/actual_pose", f"{base}/cmd_vel", f"{base}/desired_pose", *_robot_extras(robot)]


def _camera(robot: str, camera: str, *image_types: str) -> list[str]:
    """A camera's pose topics, and an image, a camera_info and image_transport's sibling topic per
    capture-enabled image type."""
    base = f"/airsim_node/{robot}/{camera}"
    per_type = [
        f"{base}/{image_type}/{leaf}" for image_type in image_types for leaf in ("image", "camera_info")
    ]
    per_type += [_transport(f"{base}/{image_type}/image") for image_type in image_types]
    return [f"{base}/desired_pose", f"{base}/camera_pose", *per_type]


def _sensor_quadrotor(robot: str) -> list[str]:
    """robot_quadrotor_sensors.jsonc: Chase (scene), DownCamera (all seven types), lidar1, radar1, and every
    instrument."""
    all_types = (
        "scene_camera",
        "depth_planar_camera",
        "depth_camera",
        "segmentation_camera",
        "depth_vis_camera",
        "disparity_normalized_camera",
        "surface_normals",
    )
    return [
        *_robot(robot),
        *_camera(robot, "Chase", "scene_camera"),
        *_camera(robot, "DownCamera", *all_types),
        f"/airsim_node/{robot}/lidar1/lidar",
        f"/airsim_node/{robot}/radar1/radar_detections",
        f"/airsim_node/{robot}/radar1/radar_tracks",
        *_instruments(robot),
    ]


def _camera_quadrotor(robot: str) -> list[str]:
    """robot_quadrotor_camera.jsonc: FrontCamera (scene, depth planar) and IMU1."""
    camera = _camera(robot, "FrontCamera", "scene_camera", "depth_planar_camera")
    return [*_robot(robot), *camera, f"/airsim_node/{robot}/IMU1/imu"]


def _survey_quadrotor(robot: str) -> list[str]:
    """robot_quadrotor_survey.jsonc: lidar1 and every instrument; no camera."""
    return [*_robot(robot), f"/airsim_node/{robot}/lidar1/lidar", *_instruments(robot)]


def _radar_mast(robot: str) -> list[str]:
    """robot_radar_tower.jsonc: radar1 only."""
    radar = f"/airsim_node/{robot}/radar1"
    return [*_robot(robot), f"{radar}/radar_detections", f"{radar}/radar_tracks"]


# the project's scenes (sim_config/); a scene without a streaming camera has no streaming bridges
PROJECT_EXPECTED = {
    "scene_basic_drone.jsonc": [LOAD_SCENE, *SCENE_WIDE, *_basic_drone("Drone1"), *STREAMING],
    "scene_drone_sensors.jsonc": [LOAD_SCENE, *SCENE_WIDE, *_sensor_quadrotor("Drone1"), *STREAMING],
    "scene_radar_tower.jsonc": [
        LOAD_SCENE,
        *SCENE_WIDE,
        *_basic_drone("Drone1"),
        *_radar_mast("RadarTower1"),
        *STREAMING,
    ],
    "scene_survey_drone.jsonc": [LOAD_SCENE, *SCENE_WIDE, *_survey_quadrotor("Drone1")],
    "scene_two_drones.jsonc": [
        LOAD_SCENE,
        *SCENE_WIDE,
        *_camera_quadrotor("Drone1"),
        *_camera_quadrotor("Drone2"),
        *STREAMING,
    ],
    "scene_two_drones_mixed.jsonc": [
        LOAD_SCENE,
        *SCENE_WIDE,
        *_basic_drone("Drone1"),
        *_sensor_quadrotor("Drone2"),
        *STREAMING,
    ],
}

# Project AirSim's example scenes (../shared/sim_config)
EXAMPLE_EXPECTED = {
    "scene_basic_drone.jsonc": [LOAD_SCENE, *SCENE_WIDE, *_basic_drone("Drone1"), *STREAMING],
    "scene_drone_sensors.jsonc": [*SCENE_WIDE, *DRONE_SENSORS_TOPICS],
    "scene_lidar_drone.jsonc": [
        LOAD_SCENE,
        *SCENE_WIDE,
        *_basic_drone("Drone1"),
        "/airsim_node/Drone1/lidar1/lidar",
        *STREAMING,
    ],
    "scene_radar_tower.jsonc": [
        LOAD_SCENE,
        *SCENE_WIDE,
        *_basic_drone("Drone1"),
        "/airsim_node/RadarTower1/actual_pose",
        "/airsim_node/RadarTower1/cmd_vel",
        "/airsim_node/RadarTower1/desired_pose",
        "/airsim_node/RadarTower1/radar1/radar_detections",
        "/airsim_node/RadarTower1/radar1/radar_tracks",
        *_robot_extras("RadarTower1"),
        *STREAMING,
    ],
    "scene_two_drones_sensors.jsonc": [
        LOAD_SCENE,
        *SCENE_WIDE,
        *_basic_drone("Drone1"),
        *[topic.replace("Drone1", "Drone2") for topic in DRONE_SENSORS_TOPICS[1:-2]],
        *STREAMING,
    ],
}


EXPECTED: dict[Path, dict[str, list[str]]] = {SIM_CONFIG: PROJECT_EXPECTED, EXAMPLE_CONFIG: EXAMPLE_EXPECTED}
RADAR_SCENE_ID = {SIM_CONFIG: "SceneRadarTower", EXAMPLE_CONFIG: "SceneRadarDrone"}


@pytest.fixture(scope="module")
def default_mapping():
    return load_mapping(DEFAULT)


@pytest.mark.parametrize("sim_config", both_configs(), indirect=True)
def test_every_scene_has_an_expected_topic_list(sim_config):
    assert sorted(path.name for path in sim_config.glob("scene_*.jsonc")) == sorted(EXPECTED[sim_config])


def test_the_compatibility_tests_cover_the_example_scenes_of_this_catalogue():
    assert sorted(EXAMPLE_SCENES) == sorted(EXAMPLE_EXPECTED)


@pytest.mark.parametrize(
    ("sim_config", "scene_file"), scenes_of(PROJECT_EXPECTED, EXAMPLE_EXPECTED), indirect=["sim_config"]
)
def test_default_mapping_expands_each_scene_to_exactly_the_documented_topics(
    default_mapping, sim_config, scene_file
):
    bridges = expand(default_mapping, read_scene(sim_config, scene_file), "projectairsim")
    topics = [bridge.ros for bridge in bridges if bridge.ros is not None]
    assert sorted(topics) == sorted(EXPECTED[sim_config][scene_file])
    assert len(topics) == len(set(topics))


@pytest.mark.parametrize("sim_config", both_configs(), indirect=True)
def test_default_mapping_gives_the_documented_types_frames_and_tf_for_drone_sensors(
    default_mapping, sim_config
):
    bridges = expand(default_mapping, read_scene(sim_config, "scene_drone_sensors.jsonc"), "projectairsim")
    by_ros = {bridge.ros: bridge for bridge in bridges}
    pose = by_ros["/airsim_node/Drone1/actual_pose"]
    assert (pose.ros_type, pose.frame_id, pose.options.latch, pose.options.lazy) == (
        "geometry_msgs/PoseStamped",
        "map",
        True,
        False,
    )
    assert (pose.tf.parent, pose.tf.child) == ("map", "airsim_node/Drone1")
    assert pose.sim == "/Sim/SceneDroneSensors/robots/Drone1/actual_pose"
    cmd = by_ros["/airsim_node/Drone1/cmd_vel"]
    assert (cmd.sim, cmd.options.watchdog_s, dict(cmd.params)) == (
        "/Sim/SceneDroneSensors/robots/Drone1/MoveByVelocityBodyFrame",
        3.0,
        {"frame": "body"},
    )
    normals = by_ros["/airsim_node/Drone1/DownCamera/surface_normals/image"]
    assert normals.sim == "/Sim/SceneDroneSensors/robots/Drone1/sensors/DownCamera/surface_normals_camera"
    assert normals.frame_id == "airsim_node/Drone1/DownCamera/surface_normals_optical"  # REP 103
    info = by_ros["/airsim_node/Drone1/DownCamera/disparity_normalized_camera/camera_info"]
    assert info.sim == "/Sim/SceneDroneSensors/robots/Drone1/sensors/DownCamera/disparity_normalized_camera"
    lidar = by_ros["/airsim_node/Drone1/lidar1/lidar"]
    assert (lidar.ros_type, lidar.frame_id, lidar.tf) == (
        "sensor_msgs/PointCloud2",
        "airsim_node/Drone1/lidar1",
        None,
    )
    # sensor frames come from the robot's pose and the sensor's mount, not with the (lazy) data
    frames = {b.tf.child: (b.sim, b.converter) for b in bridges if b.name.split("[")[0].endswith("_tf")}
    pose = ("/Sim/SceneDroneSensors/robots/Drone1/actual_pose", "sensor_pose")
    for sensor in ("lidar1", "DistanceSensor"):
        assert frames[f"airsim_node/Drone1/{sensor}"] == pose
    switch = by_ros["/airsim_streaming_camera/switch_view"]
    assert (switch.ros_kind, switch.sim) == ("service", "/Sim/SceneDroneSensors/SwitchStreamingView")
    load = by_ros[LOAD_SCENE]
    assert (load.sim, load.sim_kind, load.ros_type) == (None, "node", "std_msgs/String")
    assert {b.convention for b in bridges} == {"ned"}


@pytest.mark.parametrize("sim_config", both_configs(), indirect=True)
def test_default_mapping_broadcasts_one_camera_frame_per_capture_enabled_image_type(
    default_mapping, sim_config
):
    bridges = expand(default_mapping, read_scene(sim_config, "scene_basic_drone.jsonc"), "projectairsim")
    children = sorted(bridge.tf.child for bridge in bridges if bridge.ros is None)
    assert children == [  # the documented camera frame and its optical child
        "airsim_node/Drone1/Chase/scene_camera",
        "airsim_node/Drone1/Chase/scene_camera_optical",
        "airsim_node/Drone1/DownCamera/depth_camera",
        "airsim_node/Drone1/DownCamera/depth_camera_optical",
        "airsim_node/Drone1/DownCamera/scene_camera",
        "airsim_node/Drone1/DownCamera/scene_camera_optical",
    ]


@pytest.mark.parametrize("sim_config", both_configs(), indirect=True)
def test_radar_bridges_use_the_radar_frame_and_its_tf_comes_from_the_towers_pose(default_mapping, sim_config):
    bridges = expand(default_mapping, read_scene(sim_config, "scene_radar_tower.jsonc"), "projectairsim")
    radar = [b for b in bridges if b.variables.get("radar_name") == "radar1" and b.ros is not None]
    assert [(b.ros_type, b.frame_id) for b in radar] == [
        ("radar_msgs/RadarScan", "airsim_node/RadarTower1/radar1"),
        ("radar_msgs/RadarTracks", "airsim_node/RadarTower1/radar1"),
    ]
    assert (radar[0].tf, radar[1].tf) == (None, None)
    (frame,) = [b for b in bridges if b.name == "radar_tf[RadarTower1/radar1]"]
    assert (frame.sim, frame.converter, frame.tf) == (
        f"/Sim/{RADAR_SCENE_ID[sim_config]}/robots/RadarTower1/actual_pose",
        "sensor_pose",
        TfSpec("airsim_node/RadarTower1", "airsim_node/RadarTower1/radar1", static=True),
    )
