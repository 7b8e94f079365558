"""Topic catalogues written by hand from protocol.md §4: for the project's own scenes (sim_config/), and
for Project AirSim's example scenes (../shared/sim_config, checked where present)."""

from __future__ import annotations

from pathlib import Path

from harness import EXAMPLE_CONFIG, SIM_CONFIG

ROBOT_LEAVES = ("actual_pose", "desired_pose", "collision_info", "rotor_info")
# every image type but 5 has an `_info` topic: the real server registers type 5's info under the image's name
ALL_IMAGE_LEAVES = (
    "scene_camera",
    "scene_camera_info",
    "depth_planar_camera",
    "depth_planar_camera_info",
    "depth_camera",
    "depth_camera_info",
    "segmentation_camera",
    "segmentation_camera_info",
    "depth_vis_camera",
    "depth_vis_camera_info",
    "disparity_normalized_camera",
    "surface_normals_camera",
    "surface_normals_camera_info",
)


def robot(scene: str, name: str) -> set[str]:
    return {f"/Sim/{scene}/robots/{name}/{leaf}" for leaf in ROBOT_LEAVES}


def sensor(scene: str, name: str, sensor_id: str, *leaves: str) -> set[str]:
    return {f"/Sim/{scene}/robots/{name}/sensors/{sensor_id}/{leaf}" for leaf in leaves}


def instruments(scene: str, name: str) -> set[str]:
    """IMU1, GPS, Barometer, Magnetometer, DistanceSensor, Battery and Airspeed, one topic each."""
    return (
        sensor(scene, name, "IMU1", "imu_kinematics")
        | sensor(scene, name, "GPS", "gps")
        | sensor(scene, name, "Barometer", "barometer")
        | sensor(scene, name, "Magnetometer", "magnetometer")
        | sensor(scene, name, "DistanceSensor", "distance_sensor")
        | sensor(scene, name, "Battery", "battery")
        | sensor(scene, name, "Airspeed", "airspeed")
    )


# -- the project's robots (sim_config/robot_*.jsonc) --------------------------------------------------------


def basic_quadrotor(scene: str, name: str) -> set[str]:
    """robot_quadrotor_basic: Chase scene, DownCamera scene + depth perspective (depth planar is not
    captured), IMU1; its GPS is disabled."""
    return (
        robot(scene, name)
        | sensor(scene, name, "Chase", "scene_camera", "scene_camera_info")
        | sensor(
            scene,
            name,
            "DownCamera",
            "scene_camera",
            "scene_camera_info",
            "depth_camera",
            "depth_camera_info",
        )
        | sensor(scene, name, "IMU1", "imu_kinematics")
    )


def sensor_quadrotor(scene: str, name: str) -> set[str]:
    """robot_quadrotor_sensors: Chase scene, DownCamera all seven types, lidar1, radar1, every instrument."""
    return (
        robot(scene, name)
        | sensor(scene, name, "Chase", "scene_camera", "scene_camera_info")
        | sensor(scene, name, "DownCamera", *ALL_IMAGE_LEAVES)
        | sensor(scene, name, "lidar1", "lidar")
        | sensor(scene, name, "radar1", "radar_detections", "radar_tracks")
        | instruments(scene, name)
    )


def camera_quadrotor(scene: str, name: str) -> set[str]:
    """robot_quadrotor_camera: FrontCamera scene + depth planar, IMU1."""
    return (
        robot(scene, name)
        | sensor(
            scene,
            name,
            "FrontCamera",
            "scene_camera",
            "scene_camera_info",
            "depth_planar_camera",
            "depth_planar_camera_info",
        )
        | sensor(scene, name, "IMU1", "imu_kinematics")
    )


def survey_quadrotor(scene: str, name: str) -> set[str]:
    """robot_quadrotor_survey: lidar1 and every instrument, no camera."""
    return robot(scene, name) | sensor(scene, name, "lidar1", "lidar") | instruments(scene, name)


def radar_mast(scene: str, name: str) -> set[str]:
    """robot_radar_tower: radar1 only."""
    return robot(scene, name) | sensor(scene, name, "radar1", "radar_detections", "radar_tracks")


PROJECT_EXPECTED = {
    "scene_basic_drone.jsonc": ("SceneBasicDrone", basic_quadrotor("SceneBasicDrone", "Drone1")),
    "scene_drone_sensors.jsonc": ("SceneDroneSensors", sensor_quadrotor("SceneDroneSensors", "Drone1")),
    "scene_radar_tower.jsonc": (
        "SceneRadarTower",
        basic_quadrotor("SceneRadarTower", "Drone1") | radar_mast("SceneRadarTower", "RadarTower1"),
    ),
    "scene_survey_drone.jsonc": ("SceneSurveyDrone", survey_quadrotor("SceneSurveyDrone", "Drone1")),
    "scene_two_drones.jsonc": (
        "SceneTwoDrones",
        camera_quadrotor("SceneTwoDrones", "Drone1") | camera_quadrotor("SceneTwoDrones", "Drone2"),
    ),
    "scene_two_drones_mixed.jsonc": (
        "SceneTwoDronesMixed",
        basic_quadrotor("SceneTwoDronesMixed", "Drone1") | sensor_quadrotor("SceneTwoDronesMixed", "Drone2"),
    ),
}
PROJECT_ROBOTS = {
    "scene_basic_drone.jsonc": ["Drone1"],
    "scene_drone_sensors.jsonc": ["Drone1"],
    "scene_radar_tower.jsonc": ["Drone1", "RadarTower1"],
    "scene_survey_drone.jsonc": ["Drone1"],
    "scene_two_drones.jsonc": ["Drone1", "Drone2"],
    "scene_two_drones_mixed.jsonc": ["Drone1", "Drone2"],
}


# -- Project AirSim's example robots (../shared/sim_config) -------------------------------------------------


def basic_drone(scene: str, name: str) -> set[str]:
    """robot_quadrotor_fastphysics: Chase scene, DownCamera scene + depth perspective, IMU1."""
    return (
        robot(scene, name)
        | sensor(scene, name, "Chase", "scene_camera", "scene_camera_info")
        | sensor(
            scene,
            name,
            "DownCamera",
            "scene_camera",
            "scene_camera_info",
            "depth_camera",
            "depth_camera_info",
        )
        | sensor(scene, name, "IMU1", "imu_kinematics")
    )


def sensors_drone(scene: str, name: str) -> set[str]:
    """robot_quadrotor_fastphysics_sensors: all image types (5 has no _info topic), all instruments."""
    return (
        robot(scene, name)
        | sensor(scene, name, "Chase", "scene_camera", "scene_camera_info")
        | sensor(scene, name, "DownCamera", *ALL_IMAGE_LEAVES)
        | sensor(scene, name, "lidar1", "lidar")
        | instruments(scene, name)
    )


def lidar_drone(scene: str, name: str) -> set[str]:
    """robot_quadrotor_fastphysics_lidar: the basic drone's topics plus lidar1 (its GPS is disabled)."""
    return basic_drone(scene, name) | sensor(scene, name, "lidar1", "lidar")


def radar_tower(scene: str, name: str) -> set[str]:
    return robot(scene, name) | sensor(scene, name, "radar1", "radar_detections", "radar_tracks")


EXAMPLE_EXPECTED = {
    "scene_basic_drone.jsonc": ("SceneBasicDrone", basic_drone("SceneBasicDrone", "Drone1")),
    "scene_drone_sensors.jsonc": ("SceneDroneSensors", sensors_drone("SceneDroneSensors", "Drone1")),
    "scene_lidar_drone.jsonc": ("SceneLidarDrone", lidar_drone("SceneLidarDrone", "Drone1")),
    "scene_radar_tower.jsonc": (
        "SceneRadarDrone",
        basic_drone("SceneRadarDrone", "Drone1") | radar_tower("SceneRadarDrone", "RadarTower1"),
    ),
    "scene_two_drones_sensors.jsonc": (
        "SceneTwoDrones",
        basic_drone("SceneTwoDrones", "Drone1") | sensors_drone("SceneTwoDrones", "Drone2"),
    ),
}
EXAMPLE_ROBOTS = {
    "scene_basic_drone.jsonc": ["Drone1"],
    "scene_drone_sensors.jsonc": ["Drone1"],
    "scene_lidar_drone.jsonc": ["Drone1"],
    "scene_radar_tower.jsonc": ["Drone1", "RadarTower1"],
    "scene_two_drones_sensors.jsonc": ["Drone1", "Drone2"],
}

# by config directory: what a test parametrized with `simconfigs.scenes_of` looks up
EXPECTED: dict[Path, dict[str, tuple[str, set[str]]]] = {
    SIM_CONFIG: PROJECT_EXPECTED,
    EXAMPLE_CONFIG: EXAMPLE_EXPECTED,
}
ROBOTS: dict[Path, dict[str, list[str]]] = {SIM_CONFIG: PROJECT_ROBOTS, EXAMPLE_CONFIG: EXAMPLE_ROBOTS}
