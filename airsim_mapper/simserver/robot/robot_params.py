"""Checks of a robot service's parameters, shared by its service handlers.

The kinematic state stays finite: numbers must be finite, speeds, yaw rates and positions are bounded
(SPEED_LIMIT_MPS, YAW_RATE_LIMIT, POSITION_LIMIT_M: far beyond any robot, but far from overflowing), and
a command that would leave those bounds is refused with a parameter error (code 2) before it starts.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from airsim_mapper.simserver.motion.motion_commands import YawMode
from airsim_mapper.simserver.wire.services import ServiceError

SPEED_LIMIT_MPS = 1e5
YAW_RATE_LIMIT = 1e4  # rad/s
POSITION_LIMIT_M = 1e8  # |x|, |y|, |z| of any position, commanded or reached


def parameter_error(key: str, message: str) -> ServiceError:
    return ServiceError(f"Parameter '{key}' {message}", code=2.0)


def number(params: dict[str, Any], key: str) -> float:
    value = params[key]
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise parameter_error(key, f"must be a number, got {value!r}")
    return float(value)


def finite(params: dict[str, Any], key: str, limit: float = math.inf) -> float:
    """A finite number parameter, at most `limit` in magnitude."""
    value = number(params, key)
    if not math.isfinite(value):
        raise parameter_error(key, f"must be finite, got {value}")
    if abs(value) > limit:
        raise parameter_error(key, f"must be within +-{limit:g}, got {value:g}")
    return value


def timeout(params: dict[str, Any]) -> float:
    value = number(params, "timeout_sec")
    return value if value > 0 and math.isfinite(value) else math.inf


def yaw_mode(params: dict[str, Any]) -> YawMode:
    is_rate = bool(params["yaw_is_rate"])
    yaw = finite(params, "yaw", YAW_RATE_LIMIT if is_rate else math.inf)
    return YawMode(is_rate, yaw, int(params["drivetrain"]))


def within_world(key: str, position: np.ndarray) -> np.ndarray:
    """`position`, if every coordinate is finite and within POSITION_LIMIT_M; else a parameter error."""
    with np.errstate(over="ignore", invalid="ignore"):
        inside = np.all(np.abs(position) <= POSITION_LIMIT_M)
    if not inside:
        where = ", ".join(f"{v:g}" for v in position)
        raise parameter_error(key, f"leads to ({where}), outside the +-{POSITION_LIMIT_M:g} m world")
    return position


def check_speed(key: str, velocity: np.ndarray) -> np.ndarray:
    with np.errstate(over="ignore", invalid="ignore"):
        speed = float(np.linalg.norm(velocity))
    if not speed <= SPEED_LIMIT_MPS:
        raise parameter_error(key, f"asks for {speed:g} m/s; at most {SPEED_LIMIT_MPS:g} m/s")
    return velocity
