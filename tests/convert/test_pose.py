"""Robot and camera poses: NED pass-through, ENU conversion, mounts and commanded overrides."""

from __future__ import annotations

import math

import numpy as np
import pytest
import rospy
from geometry_msgs.msg import Point, Pose, PoseStamped, Quaternion

from airsim_mapper.common.geometry import quat_from_rpy, quat_to_matrix, rpy_from_quat
from airsim_mapper.convert.command import camera_desired_pose
from airsim_mapper.convert.context import ConvertContext
from airsim_mapper.convert.errors import ConversionError
from airsim_mapper.convert.pose import (
    camera_mount,
    camera_pose,
    camera_pose_key,
    camera_pose_override,
    robot_pose,
    sensor_pose,
)

H = math.sqrt(0.5)


def sim_pose(position=(1.0, 2.0, -3.0), q=(1.0, 0.0, 0.0, 0.0), stamp=2_500_000_000):
    w, x, y, z = q
    return {
        "time_stamp": stamp,
        "position": dict(zip("xyz", position)),
        "orientation": {"w": w, "x": x, "y": y, "z": z},
    }


def xyz(msg: PoseStamped) -> list[float]:
    p = msg.pose.position
    return [p.x, p.y, p.z]


def wxyz(msg: PoseStamped) -> list[float]:
    o = msg.pose.orientation
    return [o.w, o.x, o.y, o.z]


def test_ned_pose_passes_through_with_header(ned, roundtrip):
    msg = robot_pose(sim_pose(q=(H, 0.0, 0.0, H)), ned)
    assert xyz(msg) == [1.0, 2.0, -3.0]
    assert wxyz(msg) == [H, 0.0, 0.0, H]
    assert msg.header.frame_id == "map"
    assert msg.header.stamp == rospy.Time(2, 500_000_000)
    assert roundtrip(msg) == msg


def test_enu_pose_swaps_axes_and_turns_north_facing_into_yaw_90(enu):
    msg = robot_pose(sim_pose(), enu)
    assert xyz(msg) == [2.0, 1.0, 3.0]
    assert rpy_from_quat(np.array(wxyz(msg)))[2] == pytest.approx(math.pi / 2)


def test_ros_stamp_comes_from_now():
    ctx = ConvertContext(stamp="ros", now=lambda: rospy.Time(7, 0))
    assert robot_pose(sim_pose(), ctx).header.stamp == rospy.Time(7, 0)


def test_pose_without_orientation_is_rejected(ned):
    msg = sim_pose()
    del msg["orientation"]
    with pytest.raises(ConversionError, match=r"pose: message has no 'orientation'"):
        robot_pose(msg, ned)


def test_pose_with_nan_position_is_rejected(ned):
    msg = sim_pose(position=(float("nan"), 0.0, 0.0))
    with pytest.raises(ConversionError, match=r"pose: position.x must be finite, got nan"):
        robot_pose(msg, ned)


def test_pose_with_zero_quaternion_is_rejected(ned):
    with pytest.raises(ConversionError, match=r"pose: orientation is a zero quaternion"):
        robot_pose(sim_pose(q=(0.0, 0.0, 0.0, 0.0)), ned)


def camera_ctx(convention="ned", origin=None, mounts=None):
    return ConvertContext(
        frame_id="map",
        convention=convention,
        source={"camera_origin": origin or {"xyz": "1 0 0", "rpy-deg": "0 -90 0"}},
        variables={"robot_name": "Drone1", "camera_name": "DownCamera"},
        mounts={} if mounts is None else mounts,
    )


def test_camera_pose_composes_the_robot_pose_with_the_mount():
    robot_yawed_east = quat_from_rpy(0.0, 0.0, math.pi / 2)
    msg = camera_pose(sim_pose(position=(10.0, 0.0, -5.0), q=tuple(robot_yawed_east)), camera_ctx())
    # the mount is 1 m forward; the robot faces east, so the camera sits 1 m east of it
    assert xyz(msg) == pytest.approx([10.0, 1.0, -5.0])
    _, pitch, _ = rpy_from_quat(np.array(wxyz(msg)))
    assert pitch == pytest.approx(-math.pi / 2, abs=1e-6)


def test_camera_pose_without_a_mount_is_the_robot_pose():
    ctx = ConvertContext(variables={"robot_name": "Drone1", "camera_name": "Cam"})
    msg = camera_pose(sim_pose(), ctx)
    assert xyz(msg) == [1.0, 2.0, -3.0]
    assert wxyz(msg) == [1.0, 0.0, 0.0, 0.0]


def test_camera_pose_uses_a_commanded_override_instead_of_the_mount():
    mounts = {("camera_pose", "Drone1", "DownCamera"): (np.array([0.0, 0.0, 2.0]), np.array([1.0, 0, 0, 0]))}
    msg = camera_pose(sim_pose(position=(0.0, 0.0, 0.0)), camera_ctx(mounts=mounts))
    assert xyz(msg) == [0.0, 0.0, 2.0]
    assert wxyz(msg) == [1.0, 0.0, 0.0, 0.0]


def test_camera_pose_override_for_another_camera_is_ignored():
    mounts = {("camera_pose", "Drone1", "Other"): (np.zeros(3), np.array([1.0, 0, 0, 0]))}
    msg = camera_pose(sim_pose(position=(0.0, 0.0, 0.0)), camera_ctx(mounts=mounts))
    assert xyz(msg) == pytest.approx([1.0, 0.0, 0.0])


def test_camera_pose_in_enu_converts_the_composed_pose(roundtrip):
    msg = camera_pose(sim_pose(position=(0.0, 0.0, -5.0)), camera_ctx("enu"))
    assert xyz(msg) == pytest.approx([0.0, 1.0, 5.0])
    assert roundtrip(msg) == msg


def test_camera_pose_with_a_malformed_mount_is_rejected():
    with pytest.raises(ConversionError, match=r"camera_pose: camera_origin: origin 'xyz' must hold three"):
        camera_pose(sim_pose(), camera_ctx(origin={"xyz": "1 2"}))


def test_a_mount_that_is_not_a_map_of_strings_gets_the_same_precise_error():
    for origin, error in (
        ({"xyz": [1, 2, 3]}, r"origin 'xyz' must be a string of three numbers"),
        ("1 2 3", r"camera_origin: origin must be a map"),
    ):
        with pytest.raises(ConversionError, match=error):
            camera_pose(sim_pose(), camera_ctx(origin=origin))


def test_a_mount_is_parsed_once_and_its_shared_arrays_cannot_be_changed():
    first, second = camera_mount(camera_ctx()), camera_mount(camera_ctx())
    assert first[0] is second[0] and first[1] is second[1]
    with pytest.raises(ValueError):
        first[0][0] = 5.0


def test_a_camera_pose_command_feeds_the_published_camera_pose_in_both_conventions():
    for convention in ("ned", "enu"):
        mounts: dict = {}
        ctx = camera_ctx(convention, mounts=mounts)
        command = PoseStamped(
            pose=Pose(position=Point(0.5, 0.25, 0.1), orientation=Quaternion(0.0, 0.0, 0.0, 1.0))
        )
        params = camera_desired_pose(command, ctx)
        mounts[camera_pose_key("Drone1", "DownCamera")] = camera_pose_override(params)
        # a robot at the world origin with identity attitude in NED is the identity in NED, and faces
        # north (yaw +90) in ENU; the camera is offset along the robot's axes in the command's convention
        out = camera_pose(sim_pose(position=(0.0, 0.0, 0.0)), ctx)
        expected = [0.5, 0.25, 0.1] if convention == "ned" else [-0.25, 0.5, 0.1]
        assert xyz(out) == pytest.approx(expected)


def sensor_ctx(convention="ned", origin=None):
    return ConvertContext(frame_id="map", convention=convention, source={"id": "lidar1", "origin": origin})


def test_sensor_pose_moves_the_robot_pose_by_the_sensors_config_origin():
    robot_yawed_east = quat_from_rpy(0.0, 0.0, math.pi / 2)
    origin = {"xyz": "0.3 0 -0.2", "rpy-deg": "0 -90 0"}  # 0.3 m ahead, 0.2 m up, looking down
    msg = sensor_pose(
        sim_pose(position=(10.0, 0.0, -5.0), q=tuple(robot_yawed_east)), sensor_ctx(origin=origin)
    )
    assert xyz(msg) == pytest.approx([10.0, 0.3, -5.2])  # ahead is east
    beam = quat_to_matrix(np.array(wxyz(msg)))[:, 0]
    assert beam == pytest.approx([0.0, 0.0, 1.0], abs=1e-9)  # the sensor's x axis points down (NED)
    assert msg.header.stamp == rospy.Time(2, 500_000_000)


def test_sensor_pose_without_an_origin_is_the_robot_pose():
    msg = sensor_pose(sim_pose(q=(H, 0.0, 0.0, H)), sensor_ctx())
    assert xyz(msg) == [1.0, 2.0, -3.0]
    assert wxyz(msg) == pytest.approx([H, 0.0, 0.0, H])


def test_sensor_pose_in_enu_is_the_composed_pose_in_enu_flu(roundtrip):
    msg = sensor_pose(sim_pose(position=(0.0, 0.0, -5.0)), sensor_ctx("enu", {"xyz": "1 0 0"}))
    assert xyz(msg) == pytest.approx([0.0, 1.0, 5.0])  # 1 m north is y = 1 in ENU
    assert roundtrip(msg) == msg


def test_sensor_pose_with_a_malformed_origin_names_the_key():
    with pytest.raises(ConversionError, match=r"sensor_pose: origin: origin 'rpy' must hold three"):
        sensor_pose(sim_pose(), sensor_ctx(origin={"rpy": "0 1"}))
