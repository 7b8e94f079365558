"""Topic delivery to the real client: cached values on subscribe, pose rate, images, camera info, sensors."""

from __future__ import annotations

import math
import time
from dataclasses import dataclass
from typing import Any

import numpy as np
import pytest
from projectairsim import Drone
from projectairsim.types import Pose
from projectairsim.utils import unpack_image
from simconfigs import EXAMPLES, PROJECT, both_configs, config_dir

from airsim_mapper.common.geometry import quat_from_rpy
from simserver.clientkit import load_world, subscribe

CAMERA = "/Sim/SceneDroneSensors/robots/Drone1/sensors/DownCamera"
START = np.array([0.0, 0.0, -4.0])  # scene_drone_sensors.jsonc: Drone1 starts there, level


@dataclass(frozen=True)
class Mounts:
    """What the robot config of scene_drone_sensors.jsonc says about the sensors these tests look at."""

    down_origin: tuple[float, float, float]  # DownCamera's mount (FRD, m) ...
    down_rpy_deg: tuple[float, float, float]  # ... and attitude
    down_size: tuple[int, int]  # DownCamera's width and height, with a 90 degree view
    lidar_z: float  # lidar1's mount below the frame's origin (FRD z, m)

    @property
    def down_world(self) -> np.ndarray:
        return START + np.array(self.down_origin)


MOUNTS = {
    PROJECT: Mounts((0.2, 0.0, 0.1), (0.0, -45.0, 0.0), (320, 240), -0.2),  # robot_quadrotor_sensors
    EXAMPLES: Mounts((1.1, 2.2, -3.3), (5.73, -85.94, 11.46), (400, 225), 0.2),  # ..._fastphysics_sensors
}


@dataclass(frozen=True)
class SensorsDrone:
    world: Any
    drone: Any
    mounts: Mounts


@pytest.fixture(params=both_configs())
def sensors_drone(request: pytest.FixtureRequest, client) -> SensorsDrone:
    """Drone1 of scene_drone_sensors.jsonc: the project's, and the example's where present."""
    world = load_world(client, "scene_drone_sensors.jsonc", config_dir(request.param))
    return SensorsDrone(world, Drone(client, world, "Drone1"), MOUNTS[request.param])


def camera_pose(message: dict) -> tuple[list[float], list[float]]:
    position = [message["pos_x"], message["pos_y"], message["pos_z"]]
    return position, [message["rot_w"], message["rot_x"], message["rot_y"], message["rot_z"]]


def same_rotation(a, b) -> bool:
    return abs(abs(float(np.dot(a, b))) - 1.0) < 1e-5


def test_actual_pose_is_cached_at_scene_start_and_published_at_a_steady_rate(client, sensors_drone):
    world, drone = sensors_drone.world, sensors_drone.drone
    poses = subscribe(client, drone.robot_info["actual_pose"])
    first = poses.wait_for(1, timeout=1.0)[0]
    assert first["position"] == {"x": 0.0, "y": 0.0, "z": -4.0}
    time.sleep(1.0)
    stamps = [m["time_stamp"] for m in poses.messages]
    assert len(stamps) >= 60  # nominal 100 Hz, measured over 1 s on a shared, loaded machine
    assert stamps == sorted(stamps)
    assert stamps[-1] <= world.get_sim_time()


def test_camera_info_is_cached_at_scene_start_with_the_real_intrinsics(client, sensors_drone):
    info = subscribe(client, f"{CAMERA}/scene_camera_info").wait_for(1, timeout=2.0)[0]
    width, height = sensors_drone.mounts.down_size
    f = width / 2  # (width / 2) / tan(90 deg / 2)
    assert info["width"] == width and info["height"] == height
    assert info["intrinsic_camera_matrix"] == pytest.approx([f, 0, width / 2, 0, f, height / 2, 0, 0, 1])
    assert info["projection_matrix"] == [1.0, 0, 0, 0, 0, 1.0, 0, 0, 0, 0, 1.0, 0]
    assert "time_stamp" not in info


def test_subscribed_images_carry_the_camera_world_pose_and_the_sim_time(client, sensors_drone):
    world, mounts = sensors_drone.world, sensors_drone.mounts
    width, height = mounts.down_size
    images = subscribe(client, f"{CAMERA}/scene_camera").wait_for(2, timeout=5.0)
    message = images[-1]
    assert message["encoding"] == "BGR" and unpack_image(message).shape == (height, width, 3)
    position, rotation = camera_pose(message)
    assert position == pytest.approx(mounts.down_world, abs=1e-5)
    expected = quat_from_rpy(*(math.radians(v) for v in mounts.down_rpy_deg))
    assert same_rotation(rotation, expected)
    assert 0 < images[0]["time_stamp"] < images[1]["time_stamp"] <= world.get_sim_time()
    assert message["data_float"] == [] and message["annotations"] == []


def test_a_disparity_subscriber_receives_only_images_each_with_its_time_stamp(client, sensors_drone):
    inbox = subscribe(client, f"{CAMERA}/disparity_normalized_camera")
    messages = inbox.wait_for(4, timeout=10.0)
    assert all(m["encoding"] == "BGR" and isinstance(m["time_stamp"], int) for m in messages)
    assert not any("intrinsic_camera_matrix" in m for m in inbox.messages)  # no CameraInfo on an image topic


def test_get_images_returns_the_list_form_that_the_client_decodes(sensors_drone):
    world, drone = sensors_drone.world, sensors_drone.drone
    width, height = sensors_drone.mounts.down_size
    before = world.get_sim_time()
    images = drone.get_images("DownCamera", [0, 1, 2, 3, 6])
    assert sorted(images) == [0, 1, 2, 3, 6]
    assert isinstance(images[0]["data"], list)
    assert unpack_image(images[0]).shape == (height, width, 3)
    depth = unpack_image(images[1])
    assert depth.dtype == np.float16 and depth.shape == (height, width)
    assert images[1]["encoding"] == "16FC1"
    assert np.isfinite(depth).any()
    assert unpack_image(images[3]).shape == (height, width, 3)
    assert all(img["time_stamp"] >= before for img in images.values())


def test_get_images_skips_image_types_the_camera_does_not_capture(client):
    world = load_world(client, "scene_basic_drone.jsonc")
    drone = Drone(client, world, "Drone1")
    assert sorted(drone.get_images("DownCamera", [0, 1, 4])) == [0]
    assert drone.get_images("DownCamera", []) == {}


def test_camera_set_pose_moves_the_camera_relative_to_the_robot(sensors_drone):
    drone = sensors_drone.drone
    pose = Pose(
        {
            "translation": {"x": 0.5, "y": 0.0, "z": -1.0},
            "rotation": {"w": 1.0, "x": 0.0, "y": 0.0, "z": 0.0},
            "frame_id": "DEFAULT_ID",
        }
    )
    assert drone.set_camera_pose("DownCamera", pose, True) is True
    moved = drone.get_images("DownCamera", [0])[0]
    assert camera_pose(moved) == (pytest.approx([0.5, 0.0, -5.0]), pytest.approx([1.0, 0.0, 0.0, 0.0]))
    assert client_request_reset(drone) is True
    back = drone.get_images("DownCamera", [0])[0]
    assert camera_pose(back)[0] == pytest.approx(sensors_drone.mounts.down_world, abs=1e-5)


def client_request_reset(drone) -> bool:
    return drone.client.request(
        {"method": f"{CAMERA}/ResetCameraPose", "params": {"wait_for_pose_update": True}, "version": 1.0}
    )


def test_unsubscribe_stops_delivery(client, sensors_drone):
    drone = sensors_drone.drone
    topic = drone.robot_info["actual_pose"]
    poses = subscribe(client, topic)
    poses.wait_for(5, timeout=2.0)
    client.unsubscribe([topic])
    time.sleep(0.1)
    count = len(poses.messages)
    time.sleep(0.3)
    assert len(poses.messages) == count


def test_lidar_scans_arrive_with_the_lidar_world_pose(client, sensors_drone):
    scan = subscribe(client, "/Sim/SceneDroneSensors/robots/Drone1/sensors/lidar1/lidar").wait_for(
        1, timeout=5.0
    )[0]
    assert len(scan["point_cloud"]) == 3 * len(scan["laser_index_cloud"]) > 0
    assert len(scan["segmentation_cloud"]) == len(scan["intensity_cloud"]) == len(scan["laser_index_cloud"])
    lidar_z = START[2] + sensors_drone.mounts.lidar_z
    assert scan["pose"]["position"] == pytest.approx({"x": 0.0, "y": 0.0, "z": lidar_z})
    assert scan["time_stamp"] > 0


def test_instrument_topics_and_getters_serve_the_sensor_messages(client, sensors_drone):
    drone = sensors_drone.drone
    imu = drone.get_imu_data("IMU1")
    assert imu["time_stamp"] > 0
    barometer = subscribe(client, drone.sensors["Barometer"]["barometer"]).wait_for(1, timeout=2.0)[0]
    assert barometer["time_stamp"] >= 0
    for sensor_id, leaf in [("GPS", "gps"), ("Magnetometer", "magnetometer"), ("Battery", "battery")]:
        assert (
            subscribe(client, drone.sensors[sensor_id][leaf]).wait_for(1, timeout=2.0)[0]["time_stamp"] >= 0
        )


def test_radar_detections_and_tracks_arrive_with_the_radar_pose(client):
    world = load_world(client, "scene_radar_tower.jsonc")
    tower = Drone(client, world, "RadarTower1")
    detections = subscribe(client, tower.sensors["radar1"]["radar_detections"]).wait_for(2, timeout=5.0)
    tracks = subscribe(client, tower.sensors["radar1"]["radar_tracks"]).wait_for(1, timeout=5.0)
    assert isinstance(detections[-1]["radar_detections"], list)
    assert isinstance(tracks[-1]["radar_tracks"], list)
    # the mast at (20, 8, -3) faces east; its radar is mounted 0.5 m in front of it
    assert detections[-1]["pose"]["position"] == pytest.approx({"x": 20.0, "y": 8.5, "z": -3.0}, abs=1e-5)
