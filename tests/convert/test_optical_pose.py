"""camera_optical_pose: the camera's world pose turned into its optical frame (z forward, x right, y down)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from airsim_mapper.common.geometry import quat_from_rpy, quat_to_matrix
from airsim_mapper.convert.context import ConvertContext
from airsim_mapper.convert.errors import ConversionError
from airsim_mapper.convert.pose import camera_optical_pose, camera_pose


def robot_pose(position=(1.0, 2.0, -4.0), q=(1.0, 0.0, 0.0, 0.0)):
    w, x, y, z = (float(v) for v in q)
    return {
        "time_stamp": 7_000_000_000,
        "position": dict(zip("xyz", map(float, position))),
        "orientation": {"w": w, "x": x, "y": y, "z": z},
    }


def context(convention: str, origin=None) -> ConvertContext:
    return ConvertContext(
        frame_id="map",
        convention=convention,
        source={"camera_origin": origin or {"xyz": "0 0 0", "rpy-deg": "0 0 0"}},
        variables={"robot_name": "Drone1", "camera_name": "Cam"},
    )


def axes(msg) -> np.ndarray:
    """Columns: the optical x, y, z axes expressed in the world frame."""
    o = msg.pose.orientation
    return quat_to_matrix(np.array([o.w, o.x, o.y, o.z]))


def test_ned_optical_axes_are_right_down_forward_of_a_level_camera_facing_north():
    msg = camera_optical_pose(robot_pose(), context("ned"))
    x, y, z = axes(msg).T
    assert z == pytest.approx([1.0, 0.0, 0.0], abs=1e-12)  # forward = north
    assert x == pytest.approx([0.0, 1.0, 0.0], abs=1e-12)  # right = east
    assert y == pytest.approx([0.0, 0.0, 1.0], abs=1e-12)  # down


def test_enu_optical_axes_are_right_down_forward_in_east_north_up():
    msg = camera_optical_pose(robot_pose(), context("enu"))
    x, y, z = axes(msg).T
    assert z == pytest.approx([0.0, 1.0, 0.0], abs=1e-12)  # forward = north
    assert x == pytest.approx([1.0, 0.0, 0.0], abs=1e-12)  # right = east
    assert y == pytest.approx([0.0, 0.0, -1.0], abs=1e-12)  # down
    p = msg.pose.position
    assert (p.x, p.y, p.z) == pytest.approx((2.0, 1.0, 4.0))
    assert msg.header.frame_id == "map"
    assert msg.header.stamp.to_nsec() == 7_000_000_000


@pytest.mark.parametrize("convention", ["ned", "enu"])
def test_optical_z_follows_a_camera_pitched_down_on_a_yawed_robot(convention: str):
    robot_q = quat_from_rpy(0.0, 0.0, math.pi / 2)  # facing east
    ctx = context(convention, {"xyz": "0.2 0 0.1", "rpy-deg": "0 -45 0"})
    optical = camera_optical_pose(robot_pose(q=robot_q), ctx)
    body = camera_pose(robot_pose(q=robot_q), ctx)
    o = body.pose.orientation
    body_forward = quat_to_matrix(np.array([o.w, o.x, o.y, o.z]))[:, 0]
    assert axes(optical)[:, 2] == pytest.approx(body_forward, abs=1e-12)
    # pitch -45 degrees is nose down: the camera looks east and 45 degrees below the horizon
    east, down = ([0.0, 1.0, 0.0], [0.0, 0.0, 1.0]) if convention == "ned" else ([1.0, 0.0, 0.0], [0, 0, -1])
    assert axes(optical)[:, 2] == pytest.approx(np.add(east, down) * math.sqrt(0.5), abs=1e-12)
    assert (optical.pose.position.x, optical.pose.position.y, optical.pose.position.z) == pytest.approx(
        (body.pose.position.x, body.pose.position.y, body.pose.position.z)
    )


def test_optical_pose_of_a_malformed_mount_is_a_conversion_error():
    ctx = context("enu", {"xyz": "0 0", "rpy-deg": "0 0 0"})
    with pytest.raises(
        ConversionError, match="camera_optical_pose: camera_origin: origin 'xyz' must hold three"
    ):
        camera_optical_pose(robot_pose(), ctx)
