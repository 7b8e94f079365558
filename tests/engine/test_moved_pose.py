"""moved_pose: a goal re-expressed in the transform's parent frame, its quaternion composed as given."""

from __future__ import annotations

import math

import numpy as np
from geometry_msgs.msg import PoseStamped, TransformStamped

from airsim_mapper.engine.ros_link import moved_pose


def transform(yaw: float, xyz: tuple[float, float, float]) -> TransformStamped:
    t = TransformStamped()
    t.header.frame_id, t.child_frame_id = "sim1/map", "sim1/airsim_node/Drone1"
    t.transform.translation.x, t.transform.translation.y, t.transform.translation.z = xyz
    t.transform.rotation.w, t.transform.rotation.z = math.cos(yaw / 2), math.sin(yaw / 2)
    return t


def pose(x: float, y: float, z: float, wxyz=(1.0, 0.0, 0.0, 0.0)) -> PoseStamped:
    msg = PoseStamped()
    msg.header.frame_id = "sim1/airsim_node/Drone1"
    msg.pose.position.x, msg.pose.position.y, msg.pose.position.z = x, y, z
    q = msg.pose.orientation
    q.w, q.x, q.y, q.z = wxyz
    return msg


def test_one_metre_ahead_of_a_robot_facing_east_is_one_metre_east_of_it() -> None:
    out = moved_pose(pose(1.0, 0.0, 0.0), transform(math.pi / 2, (1.0, 2.0, -5.0)))
    assert out.header.frame_id == "sim1/map"
    p, q = out.pose.position, out.pose.orientation
    assert np.allclose([p.x, p.y, p.z], [1.0, 3.0, -5.0])
    assert np.isclose(2 * math.atan2(q.z, q.w), math.pi / 2)


def test_invalid_quaternions_stay_invalid_for_the_converter_to_refuse() -> None:
    zero = moved_pose(pose(0, 0, 0, (0.0, 0.0, 0.0, 0.0)), transform(0.3, (0, 0, 0))).pose.orientation
    assert (zero.w, zero.x, zero.y, zero.z) == (0.0, 0.0, 0.0, 0.0)
    big = moved_pose(pose(0, 0, 0, (3.0, 0.0, 0.0, 0.0)), transform(0.3, (0, 0, 0))).pose.orientation
    assert np.isclose(math.dist((big.w, big.x, big.y, big.z), (0, 0, 0, 0)), 3.0)
    nan = moved_pose(pose(float("nan"), 0, 0), transform(0.3, (0, 0, 0))).pose.position
    assert math.isnan(nan.x)
