"""odometry: actual_pose -> nav_msgs/Odometry with a body-frame twist from successive poses."""

from __future__ import annotations

import math

import pytest

from airsim_mapper.common.geometry import quat_from_rpy
from airsim_mapper.convert.context import ConvertContext
from airsim_mapper.convert.errors import ConversionError
from airsim_mapper.convert.odometry import odometry, rotation_vector


def sim_pose(t_s: float, position, yaw: float = 0.0):
    w, x, y, z = (float(v) for v in quat_from_rpy(0.0, 0.0, yaw))
    return {
        "time_stamp": round(t_s * 1e9),
        "position": dict(zip("xyz", map(float, position))),
        "orientation": {"w": w, "x": x, "y": y, "z": z},
    }


def context(convention: str, state=None, child="Drone1/base_link") -> ConvertContext:
    return ConvertContext(
        frame_id="map",
        convention=convention,
        params={"child_frame_id": child},
        variables={"robot_name": "Drone1"},
        state={} if state is None else state,
    )


def twist(msg) -> tuple[list[float], list[float]]:
    lin, ang = msg.twist.twist.linear, msg.twist.twist.angular
    return [lin.x, lin.y, lin.z], [ang.x, ang.y, ang.z]


def test_first_pose_has_zero_twist_the_pose_and_the_child_frame(roundtrip):
    msg = roundtrip(odometry(sim_pose(1.0, (1.0, 2.0, -4.0)), context("enu")))
    assert (msg.header.frame_id, msg.child_frame_id) == ("map", "Drone1/base_link")
    assert msg.header.stamp.to_nsec() == 1_000_000_000
    p = msg.pose.pose.position
    assert (p.x, p.y, p.z) == pytest.approx((2.0, 1.0, 4.0))  # ENU
    assert twist(msg) == ([0.0, 0.0, 0.0], [0.0, 0.0, 0.0])


@pytest.mark.parametrize(("convention", "linear"), [("ned", [0.0, -10.0, 0.0]), ("enu", [0.0, 10.0, 0.0])])
def test_linear_twist_is_the_body_frame_velocity_between_two_poses(convention, linear):
    ctx = context(convention)
    odometry(sim_pose(1.0, (0.0, 0.0, -4.0), yaw=math.pi / 2), ctx)  # facing east
    msg = odometry(sim_pose(1.1, (1.0, 0.0, -4.0), yaw=math.pi / 2), ctx)  # moved 1 m north in 0.1 s
    assert twist(msg)[0] == pytest.approx(linear, abs=1e-9)  # north is to the robot's left


@pytest.mark.parametrize(("convention", "yaw_rate"), [("ned", 1.0), ("enu", -1.0)])
def test_angular_twist_is_the_body_rate_between_two_poses(convention, yaw_rate):
    ctx = context(convention)
    odometry(sim_pose(1.0, (0.0, 0.0, -4.0), yaw=0.5), ctx)
    msg = odometry(sim_pose(1.1, (0.0, 0.0, -4.0), yaw=0.6), ctx)  # turned right (NED yaw grows)
    assert twist(msg) == (pytest.approx([0.0, 0.0, 0.0], abs=1e-9), pytest.approx([0.0, 0.0, yaw_rate]))


def test_a_pose_with_the_same_stamp_keeps_the_last_twist():
    ctx = context("ned")
    odometry(sim_pose(1.0, (0.0, 0.0, 0.0)), ctx)
    moving = odometry(sim_pose(1.5, (0.0, 0.0, -1.0)), ctx)
    paused = odometry(sim_pose(1.5, (0.0, 0.0, -1.0)), ctx)
    assert twist(moving)[0] == pytest.approx([0.0, 0.0, -2.0])
    assert twist(paused) == twist(moving)


def test_each_bridge_keeps_its_own_history():
    odometry(sim_pose(1.0, (0.0, 0.0, 0.0)), context("ned"))
    other = ConvertContext(
        convention="ned", params={"child_frame_id": "r2"}, variables={"robot_name": "Drone2"}
    )
    assert twist(odometry(sim_pose(2.0, (5.0, 0.0, 0.0)), other))[0] == [0.0, 0.0, 0.0]


def test_rotation_vector_takes_the_short_way_and_handles_identity():
    assert rotation_vector(quat_from_rpy(0.0, 0.0, 0.3)) == pytest.approx([0.0, 0.0, 0.3])
    assert rotation_vector(-quat_from_rpy(0.0, 0.0, 0.3)) == pytest.approx([0.0, 0.0, 0.3])
    assert rotation_vector([1.0, 0.0, 0.0, 0.0]) == pytest.approx([0.0, 0.0, 0.0])


def test_child_frame_that_is_not_a_string_is_a_conversion_error():
    with pytest.raises(ConversionError, match=r"odometry: params.child_frame_id must be a string, got 3"):
        odometry(sim_pose(1.0, (0, 0, 0)), context("ned", child=3))


def test_a_pose_without_orientation_is_a_conversion_error():
    msg = sim_pose(1.0, (0, 0, 0))
    del msg["orientation"]
    with pytest.raises(ConversionError, match="odometry: message has no 'orientation'"):
        odometry(msg, context("ned"))
