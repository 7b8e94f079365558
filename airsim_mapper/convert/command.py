"""ROS -> simulator converters: velocity commands, pose commands, service requests, scene loading.

- cmd_vel: geometry_msgs/Twist -> MoveByVelocityBodyFrame (or MoveByVelocity) params. params ``frame``
  says which frame the Twist's linear velocity is in, the robot's body (``body``, the default, for
  MoveByVelocityBodyFrame) or the world (``world``, for MoveByVelocity). With the ENU convention a body
  Twist is FLU (REP-103), so vy, vz are negated for FRD, and a world Twist is ENU, so vx and vy swap and
  vz is negated for NED; the yaw rate, about up rather than down, is negated in both.
  Limits (Options.limits): max_vertical_speed clips |vz|, then max_linear_speed bounds the norm of
  (vx, vy, vz) (scaled down, direction kept), max_yaw_rate clips the yaw rate; with on_violation
  "reject" any violation raises instead. Non-finite values are always rejected.
- desired_pose / camera_desired_pose: quaternions must be finite and non-zero; one whose norm lies
  outside [QUAT_NORM_MIN, QUAT_NORM_MAX] is rejected as not meant to be a rotation, otherwise it is
  normalised. The position must lie in limits.position_box (in the message's own convention), else it
  is clamped into the box or rejected. header.frame_id must be empty or in params ``accepted_frames``
  (default ["", params.target_frame] with a target frame, else ["", "map"]); a leading slash is ignored on
  both sides, as tf2 does ("/map" is "map"); the engine transforms a goal in any other tf frame into
  ``target_frame`` before it gets here.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping
from typing import Any

import numpy as np

from airsim_mapper.common.logs import shorten
from airsim_mapper.convert import frames, sim_fields
from airsim_mapper.convert.context import ConvertContext
from airsim_mapper.convert.entries.commands import VELOCITY_FRAMES
from airsim_mapper.convert.errors import ConversionError

BODY = next(iter(VELOCITY_FRAMES))  # cmd_vel's default frame
DEFAULT_DURATION_S = 3.0
QUAT_NORM_MIN = 0.5
QUAT_NORM_MAX = 2.0
DEFAULT_ACCEPTED_FRAMES = ("", "map")
CAMERA_POSE_FRAME_ID = "DEFAULT_ID"
MAX_SCENE_NAME = 4096  # characters: PATH_MAX
CLAMP = "clamp"
REJECT = "reject"


def _finite(value: Any, where: str) -> float:
    try:
        result = float(value)
    except (TypeError, ValueError) as exc:
        raise ConversionError(f"{where} must be a number, got {value!r}") from exc
    if not math.isfinite(result):
        raise ConversionError(f"{where} must be finite, got {result}")
    return result


def _xyz(obj: Any, where: str) -> np.ndarray:
    return np.array([_finite(getattr(obj, axis), f"{where}.{axis}") for axis in ("x", "y", "z")])


def apply_limits(
    velocity: np.ndarray,
    yaw_rate: float,
    limits: Any,
    name: str = "cmd_vel",
    on_clamp: Callable[[str], None] | None = None,
) -> tuple[np.ndarray, float]:
    """Bound (vx, vy, vz) and the yaw rate by a model.Limits (None = unbounded); `on_clamp` is told
    each limit that changed the command."""
    if limits is None:
        return velocity, yaw_rate
    clamped: list[str] = []
    mode = getattr(limits, "on_violation", CLAMP)
    if mode not in (CLAMP, REJECT):
        raise ConversionError(f"{name}: on_violation must be {CLAMP!r} or {REJECT!r}, got {mode!r}")
    velocity = velocity.copy()
    max_vz = limits.max_vertical_speed
    if max_vz is not None and abs(velocity[2]) > max_vz:
        if mode == REJECT:
            raise ConversionError(
                f"{name}: vertical speed {abs(velocity[2]):g} m/s exceeds max_vertical_speed {max_vz:g} m/s"
            )
        clamped.append(f"vertical speed {abs(velocity[2]):g} m/s to max_vertical_speed {max_vz:g}")
        velocity[2] = math.copysign(max_vz, velocity[2])
    max_speed = limits.max_linear_speed
    speed = math.hypot(*velocity)  # no overflow: np.linalg.norm squares 1e308 into inf
    if max_speed is not None and speed > max_speed:
        if mode == REJECT:
            raise ConversionError(
                f"{name}: linear speed {speed:g} m/s exceeds max_linear_speed {max_speed:g} m/s"
            )
        clamped.append(f"linear speed {speed:g} m/s to max_linear_speed {max_speed:g}")
        velocity *= max_speed / speed
    max_yaw = limits.max_yaw_rate
    if max_yaw is not None and abs(yaw_rate) > max_yaw:
        if mode == REJECT:
            raise ConversionError(
                f"{name}: yaw rate {abs(yaw_rate):g} rad/s exceeds max_yaw_rate {max_yaw:g} rad/s"
            )
        clamped.append(f"yaw rate {abs(yaw_rate):g} rad/s to max_yaw_rate {max_yaw:g}")
        yaw_rate = math.copysign(max_yaw, yaw_rate)
    if clamped and on_clamp is not None:
        on_clamp(f"{name}: clamped " + ", ".join(clamped))
    return velocity, yaw_rate


def apply_position_box(
    position: np.ndarray, limits: Any, name: str, on_clamp: Callable[[str], None] | None = None
) -> np.ndarray:
    """Keep a commanded position inside limits.position_box: clamp it there (telling `on_clamp`) or
    reject it."""
    box = getattr(limits, "position_box", None)
    if box is None:
        return position
    low, high = np.asarray(box.min, dtype=float), np.asarray(box.max, dtype=float)
    if np.all((low <= position) & (position <= high)):
        return position
    where = ", ".join(f"{v:g}" for v in position)
    box_text = f"[{', '.join(f'{v:g}' for v in low)}] .. [{', '.join(f'{v:g}' for v in high)}]"
    if getattr(limits, "on_violation", CLAMP) == REJECT:
        raise ConversionError(f"{name}: position ({where}) is outside the position box {box_text}")
    if on_clamp is not None:
        on_clamp(f"{name}: clamped position ({where}) into the position box {box_text}")
    return np.clip(position, low, high)


def require_finite(params: Any, where: str = "params") -> None:
    """Refuse a converted command holding a non-finite number anywhere (the last check before the
    simulator): whatever a converter computed, inf or NaN never leaves the bridge."""
    if isinstance(params, Mapping):
        for key, value in params.items():
            require_finite(value, f"{where}.{key}")
    elif isinstance(params, (list, tuple)):
        for index, value in enumerate(params):
            require_finite(value, f"{where}[{index}]")
    elif isinstance(params, (float, np.floating)) and not math.isfinite(params):
        raise ConversionError(f"{where} is {params}: a command must hold finite numbers only")


def _duration(ctx: ConvertContext) -> float:
    watchdog = getattr(ctx.options, "watchdog_s", None)
    value = ctx.params.get("duration", watchdog if watchdog is not None else DEFAULT_DURATION_S)
    duration = _finite(value, "cmd_vel: duration")
    if duration <= 0.0:
        raise ConversionError(f"cmd_vel: duration must be positive, got {duration:g}")
    return duration


@sim_fields.converter("cmd_vel")
def cmd_vel(msg: Any, ctx: ConvertContext) -> dict[str, Any]:
    """geometry_msgs/Twist -> {vx, vy, vz, duration, drivetrain: 0, yaw_is_rate: True, yaw}."""
    velocity = _xyz(msg.linear, "linear")
    yaw_rate = _finite(msg.angular.z, "angular.z")
    frame = ctx.params.get("frame", BODY)
    if frame not in VELOCITY_FRAMES:
        raise ConversionError(f"cmd_vel: params.frame must be one of {list(VELOCITY_FRAMES)}, got {frame!r}")
    if ctx.enu:
        velocity = frames.flu_to_frd(velocity) if frame == BODY else frames.enu_to_ned(velocity)
        yaw_rate = -yaw_rate
    limits = getattr(ctx.options, "limits", None)
    velocity, yaw_rate = apply_limits(velocity, yaw_rate, limits, on_clamp=ctx.clamped)
    vx, vy, vz = (float(v) for v in velocity)
    return {
        "vx": vx,
        "vy": vy,
        "vz": vz,
        "duration": _duration(ctx),
        "drivetrain": 0,
        "yaw_is_rate": True,
        "yaw": float(yaw_rate),
    }


def _check_frame(msg: Any, ctx: ConvertContext) -> None:
    frame_id = msg.header.frame_id
    target = ctx.params.get("target_frame")  # the engine transformed any other frame into it with tf
    accepted = ctx.params.get("accepted_frames", ("", target) if target else DEFAULT_ACCEPTED_FRAMES)
    if frame_id and frame_id.removeprefix("/") not in {str(name).removeprefix("/") for name in accepted}:
        raise ConversionError(
            f"header.frame_id {shorten(frame_id)!r} is not accepted; expected one of {sorted(set(accepted))}"
        )


def ros_quaternion(q: Any) -> np.ndarray:
    """A geometry_msgs/Quaternion as a normalised (w, x, y, z) array, validated."""
    wxyz = np.array([_finite(getattr(q, axis), f"orientation.{axis}") for axis in ("w", "x", "y", "z")])
    norm = float(np.linalg.norm(wxyz))
    if norm == 0.0:
        raise ConversionError("orientation is a zero quaternion")
    if not QUAT_NORM_MIN <= norm <= QUAT_NORM_MAX:
        raise ConversionError(
            f"orientation has norm {norm:g}, outside [{QUAT_NORM_MIN:g}, {QUAT_NORM_MAX:g}]: not a rotation"
        )
    return wxyz / norm


def _pose_in(msg: Any, ctx: ConvertContext, name: str) -> tuple[np.ndarray, np.ndarray]:
    _check_frame(msg, ctx)
    position = _xyz(msg.pose.position, "position")
    position = apply_position_box(position, getattr(ctx.options, "limits", None), name, ctx.clamped)
    return position, ros_quaternion(msg.pose.orientation)


def _xyz_map(v: np.ndarray) -> dict[str, float]:
    return {"x": float(v[0]), "y": float(v[1]), "z": float(v[2])}


def _wxyz_map(q: np.ndarray) -> dict[str, float]:
    return {"w": float(q[0]), "x": float(q[1]), "y": float(q[2]), "z": float(q[3])}


@sim_fields.converter("desired_pose")
def desired_pose(msg: Any, ctx: ConvertContext) -> dict[str, Any]:
    """geometry_msgs/PoseStamped (world) -> sim PoseStamped {time_stamp: 0, position, orientation} in NED."""
    position, q = _pose_in(msg, ctx, "desired_pose")
    if ctx.enu:
        position, q = frames.enu_to_ned(position), frames.enu_flu_to_ned_frd(q)
    return {"time_stamp": 0, "position": _xyz_map(position), "orientation": _wxyz_map(q)}


@sim_fields.converter("camera_desired_pose")
def camera_desired_pose(msg: Any, ctx: ConvertContext) -> dict[str, Any]:
    """PoseStamped relative to the robot body -> camera SetPose params (FRD; from FLU with ENU)."""
    position, q = _pose_in(msg, ctx, "camera_desired_pose")
    if ctx.enu:
        position, q = frames.flu_to_frd(position), frames.flu_to_frd_rotation(q)
    return {
        "pose": {
            "translation": _xyz_map(position),
            "rotation": _wxyz_map(q),
            "frame_id": CAMERA_POSE_FRAME_ID,
        },
        "wait_for_pose_update": True,
    }


def _args(ctx: ConvertContext, name: str) -> dict[str, Any]:
    args = ctx.params.get("args", {})
    if not isinstance(args, Mapping):
        raise ConversionError(f"{name}: params.args must be a map, got {type(args).__name__}")
    return dict(args)


@sim_fields.converter("trigger")
def trigger(msg: Any, ctx: ConvertContext) -> dict[str, Any]:
    """Any service request -> the rule's fixed sim params (a fresh copy of params.args)."""
    return _args(ctx, "trigger")


@sim_fields.converter("set_bool")
def set_bool(msg: Any, ctx: ConvertContext) -> dict[str, Any]:
    """std_srvs/SetBool request -> params.args plus {params.arg: request.data}."""
    arg = ctx.params.get("arg")
    if not isinstance(arg, str) or not arg:
        raise ConversionError("set_bool: params.arg must name the sim parameter that receives the bool")
    data = msg.data
    if not isinstance(data, (bool, np.bool_)):
        raise ConversionError(f"set_bool: data must be a bool, got {data!r}")
    params = _args(ctx, "set_bool")
    params[arg] = bool(data)
    return params


@sim_fields.converter("load_scene")
def load_scene(msg: Any, ctx: ConvertContext) -> dict[str, Any]:
    """std_msgs/String scene file name -> {"scene": name} (stripped; empty is an error, and so is a name
    longer than params ``max_length``, default MAX_SCENE_NAME: it is refused before it is logged)."""
    data = msg.data
    if not isinstance(data, str):
        raise ConversionError(f"load_scene: data must be a string, got {type(data).__name__}")
    limit = ctx.params.get("max_length", MAX_SCENE_NAME)
    if len(data) > limit:
        raise ConversionError(
            f"load_scene: the scene name {shorten(data)!r} is {len(data)} characters long; "
            f"at most {limit} are accepted"
        )
    scene = data.strip()
    if not scene:
        raise ConversionError("load_scene: the scene name is empty")
    return {"scene": scene}
