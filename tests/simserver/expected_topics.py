"""Topic catalogues written by hand from protocol.md §4 for the scenes in ../shared/sim_config."""

from __future__ import annotations

ROBOT_LEAVES = ("actual_pose", "desired_pose", "collision_info", "rotor_info")


def robot(scene: str, name: str) -> set[str]:
    return {f"/Sim/{scene}/robots/{name}/{leaf}" for leaf in ROBOT_LEAVES}


def sensor(scene: str, name: str, sensor_id: str, *leaves: str) -> set[str]:
    return {f"/Sim/{scene}/robots/{name}/sensors/{sensor_id}/{leaf}" for leaf in leaves}


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
    down = (
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
    return (
        robot(scene, name)
        | sensor(scene, name, "Chase", "scene_camera", "scene_camera_info")
        | sensor(scene, name, "DownCamera", *down)
        | sensor(scene, name, "IMU1", "imu_kinematics")
        | sensor(scene, name, "lidar1", "lidar")
        | sensor(scene, name, "DistanceSensor", "distance_sensor")
        | sensor(scene, name, "GPS", "gps")
        | sensor(scene, name, "Barometer", "barometer")
        | sensor(scene, name, "Magnetometer", "magnetometer")
        | sensor(scene, name, "Airspeed", "airspeed")
        | sensor(scene, name, "Battery", "battery")
    )


def lidar_drone(scene: str, name: str) -> set[str]:
    """robot_quadrotor_fastphysics_lidar: the basic drone's topics plus lidar1 (its GPS is disabled)."""
    return basic_drone(scene, name) | sensor(scene, name, "lidar1", "lidar")


def radar_tower(scene: str, name: str) -> set[str]:
    return robot(scene, name) | sensor(scene, name, "radar1", "radar_detections", "radar_tracks")


EXPECTED = {
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
ROBOTS = {
    "scene_basic_drone.jsonc": ["Drone1"],
    "scene_drone_sensors.jsonc": ["Drone1"],
    "scene_lidar_drone.jsonc": ["Drone1"],
    "scene_radar_tower.jsonc": ["Drone1", "RadarTower1"],
    "scene_two_drones_sensors.jsonc": ["Drone1", "Drone2"],
}
