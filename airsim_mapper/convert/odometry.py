"""Robot actual_pose -> nav_msgs/Odometry, the twist estimated from successive poses.

The simulator publishes no velocity stream, so the twist is a finite difference of the last two poses the
bridge converted (their sim stamps give dt), kept in the bridge's own ``ctx.state``. Linear and angular
velocity are expressed in the child (body) frame, as nav_msgs/Odometry specifies: FRD with the NED
convention, FLU with ENU. The first pose, and a pose whose stamp does not advance (paused clock), repeat
the last twist (zero at first). Covariances are unknown (zeros).

params: ``child_frame_id`` (a template in the mapping, e.g. ``<robot_name>/base_link``, rendered when the
rule is expanded).
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

from geometry_msgs.msg import Twist, Vector3
from nav_msgs.msg import Odometry

from airsim_mapper.common.geometry import Quat, Vec3, q_conjugate, q_mul, q_normalized, q_rotate
from airsim_mapper.convert import frames, sim_fields
from airsim_mapper.convert.context import ConvertContext
from airsim_mapper.convert.errors import ConversionError
from airsim_mapper.convert.flavour import stamp_parts
from airsim_mapper.convert.pose import ros_pose
from airsim_mapper.convert.stamps import sim_header, sim_stamp

ODOMETRY_KEY = "odometry"


@dataclass(frozen=True)
class PoseSample:
    """One converted pose: sim time (ns), world position and body attitude in the output convention."""

    t_ns: int
    position: Vec3
    q: Quat
    linear: Vec3
    angular: Vec3


ZERO: Vec3 = (0.0, 0.0, 0.0)


def rotation_vector(q: Any) -> Vec3:
    """The axis * angle (rad) of a (w, x, y, z) rotation, taking the short way round."""
    w, x, y, z = q_normalized(q)
    if w < 0.0:
        w, x, y, z = -w, -x, -y, -z
    sin_half = math.sqrt(x * x + y * y + z * z)
    if sin_half < 1e-12:
        return 2.0 * x, 2.0 * y, 2.0 * z
    scale = 2.0 * math.atan2(sin_half, w) / sin_half
    return x * scale, y * scale, z * scale


def body_twist(previous: PoseSample, position: Vec3, q: Quat, dt_s: float) -> tuple[Vec3, Vec3]:
    """(linear, angular) body-frame velocity that takes `previous` to (position, q) in dt_s seconds."""
    world_velocity = [(now - then) / dt_s for now, then in zip(position, previous.position)]
    linear = q_rotate(q_conjugate(q), world_velocity)
    ax, ay, az = rotation_vector(q_mul(q_conjugate(previous.q), q))
    return linear, (ax / dt_s, ay / dt_s, az / dt_s)


def child_frame(ctx: ConvertContext) -> str:
    text = ctx.params.get("child_frame_id", "")
    if not isinstance(text, str):
        raise ConversionError(f"params.child_frame_id must be a string, got {text!r}")
    return text


def vector(xyz: tuple[float, ...]) -> Vector3:
    x, y, z = xyz
    return Vector3(x=float(x), y=float(y), z=float(z))


@sim_fields.converter("odometry")
def odometry(msg: Mapping[str, Any], ctx: ConvertContext) -> Odometry:
    """sim PoseStamped (robot actual_pose) -> Odometry with the pose and a finite-difference twist."""
    position, q = sim_fields.pose(msg)
    secs, nsecs = stamp_parts(sim_stamp(msg))
    t_ns = secs * 1_000_000_000 + nsecs
    if ctx.enu:
        position, q = frames.ned_to_enu(position), frames.ned_frd_to_enu_flu(q)
    position, q = tuple(map(float, position)), q_normalized(q)
    child = child_frame(ctx)
    previous: PoseSample | None = ctx.state.get(ODOMETRY_KEY)
    linear, angular = ZERO, ZERO
    if previous is not None:
        linear, angular = previous.linear, previous.angular
        if t_ns > previous.t_ns:
            linear, angular = body_twist(previous, position, q, (t_ns - previous.t_ns) / 1e9)
    ctx.state[ODOMETRY_KEY] = PoseSample(t_ns, position, q, linear, angular)
    out = Odometry(header=sim_header(msg, ctx), child_frame_id=child)
    out.pose.pose = ros_pose(position, q)
    out.twist.twist = Twist(linear=vector(linear), angular=vector(angular))
    return out
