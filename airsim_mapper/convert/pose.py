"""Robot and camera poses: sim PoseStamped -> geometry_msgs/PoseStamped (NED, or ENU/FLU per REP-103)."""

from __future__ import annotations

import functools
from collections.abc import Mapping
from typing import Any

import numpy as np
from geometry_msgs.msg import Pose, PoseStamped

from airsim_mapper.common.geometry import OriginError, compose, parse_origin
from airsim_mapper.convert import frames, messages, sim_fields
from airsim_mapper.convert.context import ConvertContext
from airsim_mapper.convert.errors import ConversionError
from airsim_mapper.convert.stamps import sim_header

CAMERA_POSE_KEY = "camera_pose"


def ros_pose(position: Any, q_wxyz: Any) -> Pose:
    """geometry_msgs/Pose of a position and a (w, x, y, z) quaternion (arrays or float sequences)."""
    x, y, z = map(float, position)
    w, qx, qy, qz = map(float, q_wxyz)
    return messages.pose(x, y, z, w, qx, qy, qz)


def world_pose(position: Any, q_ned_frd: Any, ctx: ConvertContext) -> Pose:
    """A world NED/FRD pose (arrays or float sequences) as a ROS Pose in the context's convention."""
    if ctx.enu:
        return ros_pose(frames.ned_to_enu_floats(position), frames.ned_frd_to_enu_flu_floats(q_ned_frd))
    return ros_pose(position, q_ned_frd)


@sim_fields.converter("pose")
def robot_pose(msg: Mapping[str, Any], ctx: ConvertContext) -> PoseStamped:
    """sim PoseStamped {time_stamp, position, orientation} -> geometry_msgs/PoseStamped."""
    position, q = sim_fields.pose_floats(msg)
    return messages.pose_stamped(sim_header(msg, ctx), world_pose(position, q, ctx))


def camera_pose_key(robot_name: str | None, camera_name: str | None) -> tuple[str, Any, Any]:
    """The ctx.mounts key under which the engine keeps a camera's commanded pose."""
    return (CAMERA_POSE_KEY, robot_name, camera_name)


def camera_pose_override(set_pose_params: Mapping[str, Any]) -> tuple[np.ndarray, np.ndarray]:
    """(position, q_wxyz) relative to the robot (FRD) from camera_desired_pose's SetPose params.

    The engine keeps this in ctx.mounts[camera_pose_key(robot, camera)] after a successful SetPose.
    """
    pose = set_pose_params["pose"]
    t, r = pose["translation"], pose["rotation"]
    return np.array([t["x"], t["y"], t["z"]], dtype=float), np.array(
        [r["w"], r["x"], r["y"], r["z"]], dtype=float
    )


def camera_mount(ctx: ConvertContext) -> tuple[np.ndarray, np.ndarray]:
    """The camera's pose relative to its robot (NED/FRD): a commanded override, else the config origin."""
    key = camera_pose_key(ctx.variables.get("robot_name"), ctx.variables.get("camera_name"))
    override = ctx.mounts.get(key)
    if override is not None:
        position, q = override
        return np.asarray(position, dtype=float), np.asarray(q, dtype=float)
    return config_mount(ctx, "camera_origin")


def config_mount(ctx: ConvertContext, key: str) -> tuple[np.ndarray, np.ndarray]:
    """The pose relative to the robot (NED/FRD) given by the origin under `key` in the rule's source."""
    try:
        return mount_origin(ctx.source.get(key))
    except (OriginError, TypeError, AttributeError) as exc:
        raise ConversionError(f"{key}: {exc}") from exc


def mount_origin(origin: Any) -> tuple[np.ndarray, np.ndarray]:
    """`parse_origin`, cached for a map of hashable values; anything else parsed as it is, for its error."""
    try:
        items = tuple(origin.items())
        hash(items)
    except (AttributeError, TypeError):
        return parse_origin(origin)
    return parsed_origin(items)


@functools.lru_cache(maxsize=256)
def parsed_origin(items: tuple) -> tuple[np.ndarray, np.ndarray]:
    """`parse_origin` of an origin's items, parsed once per distinct origin."""
    position, q = parse_origin(dict(items))
    position.flags.writeable = q.flags.writeable = False  # shared between calls
    return position, q


def mounted(msg: Mapping[str, Any], mount: tuple[np.ndarray, np.ndarray]) -> tuple[np.ndarray, np.ndarray]:
    """World NED/FRD (position, q) of a mount on the robot whose sim PoseStamped is `msg`."""
    robot_position, robot_q = sim_fields.pose(msg)
    return compose(robot_position, robot_q, *mount)


@sim_fields.converter("camera_pose")
def camera_pose(msg: Mapping[str, Any], ctx: ConvertContext) -> PoseStamped:
    """The ROBOT's sim PoseStamped composed with the camera mount -> the camera's world PoseStamped."""
    position, q = mounted(msg, camera_mount(ctx))
    return PoseStamped(header=sim_header(msg, ctx), pose=world_pose(position, q, ctx))


@sim_fields.converter("sensor_pose")
def sensor_pose(msg: Mapping[str, Any], ctx: ConvertContext) -> PoseStamped:
    """The ROBOT's sim PoseStamped composed with the sensor's config origin -> the sensor's world PoseStamped.

    For a lidar, radar or distance sensor, whose mount is fixed: its frame is then in tf from the robot's
    pose, whether or not anyone subscribes to its data.
    """
    position, q = mounted(msg, config_mount(ctx, "origin"))
    return PoseStamped(header=sim_header(msg, ctx), pose=world_pose(position, q, ctx))


@sim_fields.converter("camera_optical_pose")
def camera_optical_pose(msg: Mapping[str, Any], ctx: ConvertContext) -> PoseStamped:
    """As camera_pose, then turned into the camera's optical frame (z forward, x right, y down)."""
    position, q = mounted(msg, camera_mount(ctx))
    if ctx.enu:
        position, q = frames.ned_to_enu(position), frames.ned_frd_to_enu_flu(q)
    return PoseStamped(
        header=sim_header(msg, ctx), pose=ros_pose(position, frames.body_to_optical(q, ctx.convention))
    )
