"""Rigid-body math shared by the bridge and the headless server (pure numpy, vectorised).

Conventions: quaternions are numpy arrays in (w, x, y, z) order and rotate body -> world; positions are
metres. The simulator's world frame is NED and its body frames are FRD.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import Any

import numpy as np

from airsim_mapper.common.errors import AirsimMapperError

IDENTITY_Q = np.array([1.0, 0.0, 0.0, 0.0])


class OriginError(AirsimMapperError, ValueError):
    """A config `origin` block could not be parsed."""


def quat_multiply(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Hamilton product a*b (apply b, then a). Broadcasts over leading axes."""
    a, b = np.asarray(a, dtype=float), np.asarray(b, dtype=float)
    if a.shape == b.shape == (4,):  # one pair (every pose message): floats beat numpy's per-call overhead
        return np.array(q_mul(a.tolist(), b.tolist()))
    aw, ax, ay, az = np.moveaxis(a, -1, 0)
    bw, bx, by, bz = np.moveaxis(b, -1, 0)
    return np.stack(
        [
            aw * bw - ax * bx - ay * by - az * bz,
            aw * bx + ax * bw + ay * bz - az * by,
            aw * by - ax * bz + ay * bw + az * bx,
            aw * bz + ax * by - ay * bx + az * bw,
        ],
        axis=-1,
    )


def quat_conjugate(q: np.ndarray) -> np.ndarray:
    q = np.asarray(q, dtype=float)
    return q * np.array([1.0, -1.0, -1.0, -1.0])


def quat_normalize(q: np.ndarray) -> np.ndarray:
    q = np.asarray(q, dtype=float)
    norm = np.linalg.norm(q, axis=-1, keepdims=True)
    return q / np.where(norm == 0.0, 1.0, norm)


def quat_to_matrix(q: np.ndarray) -> np.ndarray:
    """Rotation matrix (3x3) of a unit quaternion (w, x, y, z)."""
    w, x, y, z = quat_normalize(q)
    return np.array(
        [
            [1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
            [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
            [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)],
        ]
    )


def rotate(q: np.ndarray, v: np.ndarray) -> np.ndarray:
    """Rotate vectors v (..., 3) by the unit quaternion q."""
    return np.asarray(v, dtype=float) @ quat_to_matrix(q).T


def quat_from_rpy(roll: float, pitch: float, yaw: float) -> np.ndarray:
    """Quaternion of intrinsic Z-Y-X (yaw, then pitch, then roll) Euler angles, radians."""
    cr, sr = math.cos(roll / 2), math.sin(roll / 2)
    cp, sp = math.cos(pitch / 2), math.sin(pitch / 2)
    cy, sy = math.cos(yaw / 2), math.sin(yaw / 2)
    return np.array(
        [
            cr * cp * cy + sr * sp * sy,
            sr * cp * cy - cr * sp * sy,
            cr * sp * cy + sr * cp * sy,
            cr * cp * sy - sr * sp * cy,
        ]
    )


def rpy_from_quat(q: np.ndarray) -> tuple[float, float, float]:
    """(roll, pitch, yaw) in radians of a unit quaternion, the inverse of quat_from_rpy."""
    w, x, y, z = quat_normalize(q)
    roll = math.atan2(2 * (w * x + y * z), 1 - 2 * (x * x + y * y))
    pitch = math.asin(max(-1.0, min(1.0, 2 * (w * y - z * x))))
    yaw = math.atan2(2 * (w * z + x * y), 1 - 2 * (y * y + z * z))
    return roll, pitch, yaw


def yaw_of(q: np.ndarray) -> float:
    return rpy_from_quat(q)[2]


# --- single poses as plain floats -------------------------------------------------------------------
# The bridge converts one pose per message, 100 times a second per robot and several times per message
# (camera frames, odometry). numpy's per-call overhead on 3- and 4-vectors outweighs the arithmetic
# (docs/performance.md), so these take any sequences of floats and return tuples.

Vec3 = tuple[float, float, float]
Quat = tuple[float, float, float, float]


def q_normalized(q: Any) -> Quat:
    """A (w, x, y, z) quaternion scaled to unit length (a zero one is returned as it is)."""
    w, x, y, z = (float(v) for v in q)
    norm = math.sqrt(w * w + x * x + y * y + z * z) or 1.0
    return w / norm, x / norm, y / norm, z / norm


def q_mul(a: Any, b: Any) -> Quat:
    """Hamilton product a*b of two single quaternions (apply b, then a)."""
    aw, ax, ay, az = a
    bw, bx, by, bz = b
    return (
        aw * bw - ax * bx - ay * by - az * bz,
        aw * bx + ax * bw + ay * bz - az * by,
        aw * by - ax * bz + ay * bw + az * bx,
        aw * bz + ax * by - ay * bx + az * bw,
    )


def q_rotate(q: Quat, v: Any) -> Vec3:
    """The vector v rotated by the unit quaternion q."""
    w, ux, uy, uz = q
    vx, vy, vz = (float(c) for c in v)
    # v' = v + w t + u x t with t = 2 u x v (u = the quaternion's vector part)
    tx, ty, tz = 2 * (uy * vz - uz * vy), 2 * (uz * vx - ux * vz), 2 * (ux * vy - uy * vx)
    return (
        vx + w * tx + (uy * tz - uz * ty),
        vy + w * ty + (uz * tx - ux * tz),
        vz + w * tz + (ux * ty - uy * tx),
    )


def q_conjugate(q: Any) -> Quat:
    w, x, y, z = q
    return w, -x, -y, -z


def compose(parent_pos: Any, parent_q: Any, child_pos: Any, child_q: Any) -> tuple[np.ndarray, np.ndarray]:
    """World pose of a child given its pose relative to a parent: returns (position, quaternion)."""
    parent = q_normalized(parent_q)
    ox, oy, oz = (float(v) for v in parent_pos)
    rx, ry, rz = q_rotate(parent, child_pos)
    q = q_normalized(q_mul(parent, child_q))
    return np.array([ox + rx, oy + ry, oz + rz]), np.array(q)


def _three_floats(text: Any, key: str) -> tuple[float, float, float]:
    if not isinstance(text, str):
        raise OriginError(f"origin {key!r} must be a string of three numbers, got {text!r}")
    parts = text.split()
    if len(parts) != 3:
        raise OriginError(f"origin {key!r} must hold three numbers, got {text!r}")
    try:
        values = tuple(float(p) for p in parts)
    except ValueError as exc:
        raise OriginError(f"origin {key!r} must hold three numbers, got {text!r}") from exc
    if not all(math.isfinite(v) for v in values):
        raise OriginError(f"origin {key!r} must hold finite numbers, got {text!r}")
    return values  # type: ignore[return-value]


def parse_origin(origin: Mapping[str, Any] | None) -> tuple[np.ndarray, np.ndarray]:
    """Position and quaternion of a scene/robot config `origin` ({xyz, rpy | rpy-deg}); identity if absent.

    Raises OriginError for malformed values. (`geo-point` origins are handled by the caller.)
    """
    if not origin:
        return np.zeros(3), IDENTITY_Q.copy()
    if not isinstance(origin, Mapping):
        raise OriginError(f"origin must be a map of xyz and rpy or rpy-deg, got {origin!r}")
    position = np.array(_three_floats(origin["xyz"], "xyz")) if "xyz" in origin else np.zeros(3)
    if "rpy-deg" in origin:
        roll, pitch, yaw = (math.radians(v) for v in _three_floats(origin["rpy-deg"], "rpy-deg"))
    elif "rpy" in origin:
        roll, pitch, yaw = _three_floats(origin["rpy"], "rpy")
    else:
        roll = pitch = yaw = 0.0
    return position, quat_from_rpy(roll, pitch, yaw)
