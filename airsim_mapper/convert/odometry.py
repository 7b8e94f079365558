"""Robot actual_pose -> nav_msgs/Odometry, the twist estimated from successive poses.

The simulator publishes no velocity stream, so the twist is a finite difference of the last two poses the
bridge converted (their sim stamps give dt), kept per bridge in ``ctx.shared``. Linear and angular
velocity are expressed in the child (body) frame, as nav_msgs/Odometry specifies: FRD with the NED
convention, FLU with ENU. The first pose, and a pose whose stamp does not advance (paused clock), repeat
the last twist (zero at first). Covariances are unknown (zeros).

params: ``child_frame_id`` (template over the bridge's variables, e.g. ``<robot_name>/base_link``).
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np
from geometry_msgs.msg import Twist, Vector3
from nav_msgs.msg import Odometry

from airsim_mapper.convert import frames, sim_fields
from airsim_mapper.convert.context import ConvertContext
from airsim_mapper.convert.errors import ConversionError
from airsim_mapper.convert.pose import ros_pose
from airsim_mapper.convert.stamps import header, sim_stamp
from airsim_mapper.geometry import quat_conjugate, quat_multiply, quat_normalize, quat_to_matrix
from airsim_mapper.mapping.template import TemplateError, render

ODOMETRY_KEY = "odometry"


@dataclass(frozen=True)
class PoseSample:
    """One converted pose: sim time (ns), world position and body attitude in the output convention."""

    t_ns: int
    position: np.ndarray
    q: np.ndarray
    linear: np.ndarray
    angular: np.ndarray


def rotation_vector(q: np.ndarray) -> np.ndarray:
    """The axis * angle (rad) of a (w, x, y, z) rotation, taking the short way round."""
    q = quat_normalize(q)
    if q[0] < 0.0:
        q = -q
    sin_half = float(np.linalg.norm(q[1:]))
    if sin_half < 1e-12:
        return 2.0 * q[1:]
    return q[1:] * (2.0 * np.arctan2(sin_half, q[0]) / sin_half)


def body_twist(previous: PoseSample, position: np.ndarray, q: np.ndarray, dt_s: float):
    """(linear, angular) body-frame velocity that takes `previous` to (position, q) in dt_s seconds."""
    world_velocity = (position - previous.position) / dt_s
    linear = quat_to_matrix(q).T @ world_velocity
    angular = rotation_vector(quat_multiply(quat_conjugate(previous.q), q)) / dt_s
    return linear, angular


def child_frame(ctx: ConvertContext) -> str:
    text = ctx.params.get("child_frame_id", "")
    if not isinstance(text, str):
        raise ConversionError(f"params.child_frame_id must be a string, got {text!r}")
    try:
        return render(text, ctx.variables)
    except TemplateError as exc:
        raise ConversionError(f"params.child_frame_id: {exc}") from None


@sim_fields.converter("odometry")
def odometry(msg: Mapping[str, Any], ctx: ConvertContext) -> Odometry:
    """sim PoseStamped (robot actual_pose) -> Odometry with the pose and a finite-difference twist."""
    position, q = sim_fields.pose(msg)
    t_ns = sim_stamp(msg).to_nsec()
    q = quat_normalize(q)
    if ctx.enu:
        position, q = frames.ned_to_enu(position), frames.ned_frd_to_enu_flu(q)
    child = child_frame(ctx)
    key = (ODOMETRY_KEY, ctx.variables.get("robot_name"), child, ctx.convention)
    previous: PoseSample | None = ctx.shared.get(key)
    linear, angular = np.zeros(3), np.zeros(3)
    if previous is not None:
        linear, angular = previous.linear, previous.angular
        if t_ns > previous.t_ns:
            linear, angular = body_twist(previous, position, q, (t_ns - previous.t_ns) / 1e9)
    ctx.shared[key] = PoseSample(t_ns, position, q, linear, angular)
    out = Odometry(header=header(msg, ctx), child_frame_id=child)
    out.pose.pose = ros_pose(position, q)
    out.twist.twist = Twist(Vector3(*map(float, linear)), Vector3(*map(float, angular)))
    return out
