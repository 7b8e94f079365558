"""Checked access to fields of simulator messages (msgpack maps) and ROS messages.

Every helper raises ConversionError naming the field; `converter` is a safety net that turns any other
error a malformed message could still provoke into a ConversionError, so converters honour their contract.
"""

from __future__ import annotations

import functools
import math
from collections.abc import Callable, Mapping
from typing import Any, TypeVar

import numpy as np

from airsim_mapper.convert.errors import ConversionError

F = TypeVar("F", bound=Callable[..., Any])

_WRAPPED = (KeyError, TypeError, ValueError, IndexError, AttributeError, OverflowError)


def converter(name: str) -> Callable[[F], F]:
    """Decorate a converter so that only ConversionError escapes it (prefixed with the converter name)."""

    def wrap(fn: F) -> F:
        @functools.wraps(fn)
        def run(msg: Any, ctx: Any) -> Any:
            try:
                return fn(msg, ctx)
            except ConversionError as exc:
                text = str(exc)
                raise (exc if text.startswith(f"{name}:") else ConversionError(f"{name}: {text}")) from None
            except _WRAPPED as exc:
                raise ConversionError(f"{name}: malformed message ({type(exc).__name__}: {exc})") from exc

        return run  # type: ignore[return-value]

    return wrap


def as_map(value: Any, where: str) -> Mapping[str, Any]:
    if type(value) is dict:  # what msgpack gives; skips the slower abstract-class check
        return value
    if not isinstance(value, Mapping):
        raise ConversionError(f"{where} must be a map, got {type(value).__name__}")
    return value


def field(msg: Any, key: str, where: str = "message") -> Any:
    """``msg[key]`` of a map, or ConversionError naming the missing key."""
    msg = as_map(msg, where)
    if key not in msg:
        raise ConversionError(f"{where} has no {key!r}")
    return msg[key]


def _plain_float(value: Any, finite: bool) -> bool:
    """The common case, checked quickly: a Python float (finite unless told otherwise)."""
    return type(value) is float and (not finite or math.isfinite(value))


def number(value: Any, where: str, finite: bool = True) -> float:
    """A real number (int or float, not bool); finite unless told otherwise."""
    if _plain_float(value, finite):
        return value
    if isinstance(value, (bool, np.bool_)) or not isinstance(value, (int, float, np.integer, np.floating)):
        raise ConversionError(f"{where} must be a number, got {value!r}")
    result = float(value)
    if finite and not math.isfinite(result):
        raise ConversionError(f"{where} must be finite, got {result}")
    return result


def integer(value: Any, where: str) -> int:
    if isinstance(value, (bool, np.bool_)) or not isinstance(value, (int, np.integer)):
        raise ConversionError(f"{where} must be an integer, got {value!r}")
    return int(value)


def number_field(msg: Any, key: str, where: str = "message", finite: bool = True) -> float:
    value = field(msg, key, where)
    if _plain_float(value, finite):  # before building the field's name for an error
        return value
    return number(value, f"{where}.{key}" if where != "message" else key, finite)


def vector3(msg: Any, key: str, where: str = "message") -> np.ndarray:
    """A sim Vector3 ``{x, y, z}`` as a float array (finite)."""
    return np.array(vector3_floats(msg, key, where))


def vector3_floats(msg: Any, key: str, where: str = "message") -> tuple[float, float, float]:
    """A sim Vector3 ``{x, y, z}`` as three finite floats."""
    name = key if where == "message" else f"{where}.{key}"
    value = as_map(field(msg, key, where), name)
    return number_field(value, "x", name), number_field(value, "y", name), number_field(value, "z", name)


def quaternion(msg: Any, key: str, where: str = "message") -> np.ndarray:
    """A sim Quaternion ``{w, x, y, z}`` as a (w, x, y, z) float array; finite and non-zero."""
    return np.array(quaternion_floats(msg, key, where))


def quaternion_floats(msg: Any, key: str, where: str = "message") -> tuple[float, float, float, float]:
    """A sim Quaternion ``{w, x, y, z}`` as four finite floats (w, x, y, z), not all zero."""
    name = key if where == "message" else f"{where}.{key}"
    value = as_map(field(msg, key, where), name)
    w = number_field(value, "w", name)
    x = number_field(value, "x", name)
    y = number_field(value, "y", name)
    z = number_field(value, "z", name)
    if not (w or x or y or z):
        raise ConversionError(f"{name} is a zero quaternion")
    return w, x, y, z


def pose(msg: Any, key: str | None = None, where: str = "message") -> tuple[np.ndarray, np.ndarray]:
    """(position, quaternion) of a sim Pose ``{position, orientation}`` (``msg`` itself if key is None)."""
    position, q = pose_floats(msg, key, where)
    return np.array(position), np.array(q)


def pose_floats(
    msg: Any, key: str | None = None, where: str = "message"
) -> tuple[tuple[float, float, float], tuple[float, float, float, float]]:
    """`pose` as plain floats: ((x, y, z), (w, x, y, z))."""
    body = msg if key is None else as_map(field(msg, key, where), key)
    name = where if key is None else key
    return vector3_floats(body, "position", name), quaternion_floats(body, "orientation", name)


def is_camera_info(msg: Any) -> bool:
    """True for a sim CameraInfo message. The simulator publishes the disparity type's CameraInfo on the
    image topic itself (its info topic has the image's name), so image converters meet these."""
    return isinstance(msg, Mapping) and "intrinsic_camera_matrix" in msg and "data" not in msg
