"""Frame conventions: NED <-> ENU (world) and FRD <-> FLU (body), and camera optical frames.

The simulator's world frame is NED and its body/sensor frames are FRD; REP-103 wants ENU and FLU. Both
changes are 180 degree rotations (so each is its own inverse):

- world NED -> ENU: (x, y, z) -> (y, x, -z), the rotation Q_NED_TO_ENU;
- body FRD -> FLU: (x, y, z) -> (x, -y, -z), the rotation Q_FLU_TO_FRD (the same both ways).

An attitude (body -> world) changes as ``q_enu_flu = Q_NED_TO_ENU * q_ned_frd * Q_FLU_TO_FRD``.
Quaternions are numpy arrays (w, x, y, z); points and vectors are (..., 3) arrays. Everything is vectorised.
Quaternion results are returned with w >= 0.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from airsim_mapper.common.geometry import Quat, Vec3, q_mul, quat_conjugate, quat_multiply
from airsim_mapper.convert.errors import ConversionError

_H = math.sqrt(0.5)

# Rotations that re-express coordinates of one convention in the other.
Q_NED_TO_ENU = np.array([0.0, _H, _H, 0.0])
Q_ENU_TO_NED = quat_conjugate(Q_NED_TO_ENU)
Q_FLU_TO_FRD = np.array([0.0, 1.0, 0.0, 0.0])
Q_FRD_TO_FLU = quat_conjugate(Q_FLU_TO_FRD)
R_NED_TO_ENU = np.array([[0.0, 1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, -1.0]])
R_FRD_TO_FLU = np.diag([1.0, -1.0, -1.0])

# Orientation of a camera optical frame (x right, y down, z forward) relative to the camera body frame.
Q_FRD_OPTICAL = np.array([0.5, 0.5, 0.5, 0.5])
Q_FLU_OPTICAL = np.array([0.5, -0.5, 0.5, -0.5])

_Q_NED_TO_ENU: Quat = tuple(Q_NED_TO_ENU.tolist())  # type: ignore[assignment]
_Q_FLU_TO_FRD: Quat = tuple(Q_FLU_TO_FRD.tolist())  # type: ignore[assignment]
_SWAP = np.array([1, 0, 2])
_NED_ENU_SIGN = np.array([1.0, 1.0, -1.0])
_FRD_FLU_SIGN = np.array([1.0, -1.0, -1.0])


def canonical(q: np.ndarray) -> np.ndarray:
    """The same rotation with w >= 0 (broadcasts over leading axes)."""
    q = np.asarray(q, dtype=float)
    if q.ndim == 1:
        return -q if q[0] < 0.0 else q
    return np.where(q[..., :1] < 0.0, -q, q)


def ned_to_enu(points: np.ndarray) -> np.ndarray:
    """World points or vectors NED -> ENU: (x, y, z) -> (y, x, -z)."""
    return np.asarray(points, dtype=float)[..., _SWAP] * _NED_ENU_SIGN


def ned_to_enu_floats(point: Any) -> Vec3:
    """`ned_to_enu` of one point given as three floats (a pose message's position, or a 3-vector)."""
    x, y, z = point
    return y, x, z * -1.0


def enu_to_ned(points: np.ndarray) -> np.ndarray:
    """World points or vectors ENU -> NED (the same swap; it is its own inverse)."""
    return ned_to_enu(points)


def frd_to_flu(points: np.ndarray) -> np.ndarray:
    """Body points or vectors FRD -> FLU: (x, y, z) -> (x, -y, -z)."""
    return np.asarray(points, dtype=float) * _FRD_FLU_SIGN


def flu_to_frd(points: np.ndarray) -> np.ndarray:
    """Body points or vectors FLU -> FRD (its own inverse)."""
    return frd_to_flu(points)


def ned_frd_to_enu_flu(q_ned_frd: np.ndarray) -> np.ndarray:
    """Attitude of an FRD body in NED -> attitude of the FLU body in ENU."""
    return canonical(quat_multiply(quat_multiply(Q_NED_TO_ENU, q_ned_frd), Q_FLU_TO_FRD))


def ned_frd_to_enu_flu_floats(q_ned_frd: Any) -> Quat:
    """`ned_frd_to_enu_flu` of one (w, x, y, z) attitude given as floats: the same products, bit for bit."""
    w, x, y, z = q_mul(q_mul(_Q_NED_TO_ENU, q_ned_frd), _Q_FLU_TO_FRD)
    return (-w, -x, -y, -z) if w < 0.0 else (w, x, y, z)


def enu_flu_to_ned_frd(q_enu_flu: np.ndarray) -> np.ndarray:
    """Attitude of an FLU body in ENU -> attitude of the FRD body in NED."""
    return canonical(quat_multiply(quat_multiply(Q_ENU_TO_NED, q_enu_flu), Q_FRD_TO_FLU))


def frd_to_flu_rotation(q_frd: np.ndarray) -> np.ndarray:
    """A rotation between two FRD frames (e.g. a sensor mount) re-expressed between the FLU frames."""
    return canonical(quat_multiply(quat_multiply(Q_FRD_TO_FLU, q_frd), Q_FLU_TO_FRD))


def flu_to_frd_rotation(q_flu: np.ndarray) -> np.ndarray:
    """A rotation between two FLU frames re-expressed between the FRD frames."""
    return canonical(quat_multiply(quat_multiply(Q_FLU_TO_FRD, q_flu), Q_FRD_TO_FLU))


def body_to_optical(q_body: np.ndarray, convention: str = "ned") -> np.ndarray:
    """Attitude of a camera's optical frame given the camera body attitude (FRD for "ned", FLU for "enu")."""
    mount = Q_FLU_OPTICAL if convention == "enu" else Q_FRD_OPTICAL
    return canonical(quat_multiply(q_body, mount))


def rotate_covariance(cov: np.ndarray, rotation: np.ndarray) -> np.ndarray:
    """Re-express a 3x3 or 6x6 covariance (flat 9/36 or square) in a rotated frame: R C R^T.

    A 6x6 covariance (position + rotation, as in geometry_msgs) uses the block-diagonal (R, R).
    The result has the input's shape.
    """
    cov = np.asarray(cov, dtype=float)
    flat = cov.ndim == 1
    size = math.isqrt(cov.size)
    if size * size != cov.size or size not in (3, 6):
        raise ConversionError(f"covariance must have 9 or 36 elements, got {cov.size}")
    square = cov.reshape(size, size)
    r = np.asarray(rotation, dtype=float)
    if size == 6:
        r = np.block([[r, np.zeros((3, 3))], [np.zeros((3, 3)), r]])
    out = r @ square @ r.T
    return out.reshape(-1) if flat else out


def ned_to_enu_covariance(cov: np.ndarray) -> np.ndarray:
    """World covariance NED -> ENU (3x3 or 6x6, flat or square)."""
    return rotate_covariance(cov, R_NED_TO_ENU)


def frd_to_flu_covariance(cov: np.ndarray) -> np.ndarray:
    """Body covariance FRD -> FLU (3x3 or 6x6, flat or square)."""
    return rotate_covariance(cov, R_FRD_TO_FLU)
