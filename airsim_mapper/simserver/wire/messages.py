"""Builders for the message and service-result shapes of protocol.md §3.5 and §5 (plain dicts)."""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np

from airsim_mapper.simserver.errors import SimServerError
from airsim_mapper.simserver.motion.motion import Kinematic


class MessageError(SimServerError, ValueError):
    """A pose or kinematics value sent by the client does not have the expected shape."""


def vector3(v: np.ndarray) -> dict[str, float]:
    return {"x": float(v[0]), "y": float(v[1]), "z": float(v[2])}


def quaternion(q: np.ndarray) -> dict[str, float]:
    return {"w": float(q[0]), "x": float(q[1]), "y": float(q[2]), "z": float(q[3])}


def pose(position: np.ndarray, orientation: np.ndarray) -> dict[str, Any]:
    return {"position": vector3(position), "orientation": quaternion(orientation)}


def pose_stamped_dict(
    t_ns: int, position: Sequence[float] | np.ndarray, orientation: Sequence[float] | np.ndarray
) -> dict[str, Any]:
    """The wire dict of a PoseStamped (§5.1): actual_pose / desired_pose."""
    return {"time_stamp": int(t_ns), "position": vector3(position), "orientation": quaternion(orientation)}


def transform(position: np.ndarray, orientation: np.ndarray, frame_id: str = "DEFAULT_ID") -> dict[str, Any]:
    """Transform result of GetGroundTruthPose."""
    return {"frame_id": frame_id, "translation": vector3(position), "rotation": quaternion(orientation)}


def kinematics(t_ns: int, kin: Kinematic) -> dict[str, Any]:
    """Service form of Kinematics (§5.2): no `kinematics` wrapper."""
    return {
        "time_stamp": int(t_ns),
        "pose": pose(kin.position, kin.orientation),
        "twist": {"linear": vector3(kin.linear_velocity), "angular": vector3(kin.angular_velocity)},
        "accels": {"linear": vector3(kin.linear_acceleration), "angular": vector3(kin.angular_acceleration)},
    }


def _floats(mapping: Any, keys: str, what: str) -> np.ndarray:
    if not isinstance(mapping, Mapping):
        raise MessageError(f"{what} must be an object with keys {', '.join(keys)}, got {mapping!r}")
    try:
        values = np.array([float(mapping[k]) for k in keys])
    except KeyError as exc:
        raise MessageError(f"{what} has no '{exc.args[0]}'") from exc
    except (TypeError, ValueError) as exc:
        raise MessageError(f"{what} must hold numbers: {exc}") from exc
    if not np.all(np.isfinite(values)):
        raise MessageError(f"{what} must hold finite numbers")
    return values


def parse_vector3(value: Any, what: str) -> np.ndarray:
    return _floats(value, "xyz", what)


def parse_quaternion(value: Any, what: str) -> np.ndarray:
    q = _floats(value, "wxyz", what)
    norm = float(np.linalg.norm(q))
    if norm < 1e-9:
        raise MessageError(f"{what} must not be a zero quaternion")
    return q / norm


def parse_transform(value: Any) -> tuple[np.ndarray, np.ndarray]:
    """(position, orientation) of a Transform param {frame_id, translation, rotation}."""
    if not isinstance(value, Mapping):
        raise MessageError(f"pose must be an object with frame_id, translation and rotation, got {value!r}")
    if "frame_id" not in value:
        raise MessageError("pose has no 'frame_id'")
    return parse_vector3(value.get("translation"), "pose translation"), parse_quaternion(
        value.get("rotation"), "pose rotation"
    )


def parse_pose_stamped(value: Any) -> tuple[np.ndarray, np.ndarray]:
    """(position, orientation) of a PoseStamped message (desired_pose)."""
    if not isinstance(value, Mapping):
        raise MessageError(f"PoseStamped must be an object, got {value!r}")
    return parse_vector3(value.get("position"), "position"), parse_quaternion(
        value.get("orientation"), "orientation"
    )


def parse_kinematics(value: Any) -> Kinematic:
    """A Kinematic from the service form {time_stamp, pose, twist, accels}."""
    if not isinstance(value, Mapping):
        raise MessageError(f"kinematics must be an object, got {value!r}")
    try:
        return Kinematic(
            parse_vector3(value["pose"]["position"], "kinematics pose position"),
            parse_quaternion(value["pose"]["orientation"], "kinematics pose orientation"),
            parse_vector3(value["twist"]["linear"], "kinematics twist linear"),
            parse_vector3(value["twist"]["angular"], "kinematics twist angular"),
            parse_vector3(value["accels"]["linear"], "kinematics accels linear"),
            parse_vector3(value["accels"]["angular"], "kinematics accels angular"),
        )
    except (KeyError, TypeError) as exc:
        raise MessageError(f"kinematics is missing {exc}") from exc


def collision_info(t_ns: int, contact: Any) -> dict[str, Any]:
    """CollisionInfo (§5.3) from a world Contact."""
    return {
        "time_stamp": int(t_ns),
        "object_name": contact.object_name,
        "segmentation_id": int(contact.segmentation_id),
        "position": vector3(contact.position),
        "impact_point": vector3(contact.impact_point),
        "normal": vector3(contact.normal),
        "penetration_depth": float(contact.penetration_depth),
    }


def image(
    t_ns: int,
    encoding: str,
    width: int,
    height: int,
    data: Any,
    position: np.ndarray,
    orientation: np.ndarray,
    annotations: list[dict[str, Any]] | None = None,
) -> dict[str, Any]:
    """Image (§5.4) with the camera's world pose; `data` is bytes (topic) or a Raw list (GetImages)."""
    return {
        "time_stamp": int(t_ns),
        "height": int(height),
        "width": int(width),
        "encoding": encoding,
        "big_endian": False,
        "step": 1,
        "data": data,
        "data_float": [],
        "pos_x": float(position[0]),
        "pos_y": float(position[1]),
        "pos_z": float(position[2]),
        "rot_w": float(orientation[0]),
        "rot_x": float(orientation[1]),
        "rot_y": float(orientation[2]),
        "rot_z": float(orientation[3]),
        "annotations": annotations if annotations is not None else [],
    }
