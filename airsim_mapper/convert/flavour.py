"""The message generation the converters build: ROS1's genpy classes or ROS 2's rosidl classes.

Decided once, at import, by what this interpreter can import (the two flavours live in two venvs, and their
message packages share names). The converters build stamps, headers, CameraInfo's matrices, Durations and
``data`` byte fields through this module only, so they stay one catalogue for both.
"""

from __future__ import annotations

import importlib.util
from collections.abc import Sequence
from typing import Any

ROS2 = importlib.util.find_spec("genpy") is None and importlib.util.find_spec("rclpy") is not None

if ROS2:
    from builtin_interfaces.msg import Duration as _Duration
    from builtin_interfaces.msg import Time as _Time

    def ros_time(secs: int, nsecs: int) -> Any:
        """builtin_interfaces/Time of an already canonical (secs, 0 <= nsecs < 1e9) pair."""
        return _Time(sec=secs, nanosec=nsecs)

    def stamp_parts(stamp: Any) -> tuple[int, int]:
        return stamp.sec, stamp.nanosec

    def duration(seconds: float) -> Any:
        whole, fraction = divmod(round(seconds * 1e9), 1_000_000_000)
        return _Duration(sec=whole, nanosec=fraction)

    def camera_matrices(
        d: Sequence[float], k: Sequence[float], r: Sequence[float], p: Sequence[float]
    ) -> dict:
        """CameraInfo's matrices as constructor keywords (lower-case names in ROS 2)."""
        return {"d": list(d), "k": list(k), "r": list(r), "p": list(p)}

    def byte_data(data: Any) -> Any:
        """A ``uint8[]`` value rclpy takes with one memcpy: bytes (a memoryview or an ndarray would be
        copied element by element)."""
        return data if isinstance(data, (bytes, bytearray)) else bytes(data)

else:
    from genpy import Duration as _Duration
    from genpy import Time as _Time

    _new = object.__new__

    def ros_time(secs: int, nsecs: int) -> Any:
        """A genpy Time from an already canonical (secs, 0 <= nsecs < 1e9) pair."""
        stamp = _new(_Time)
        stamp.secs, stamp.nsecs = secs, nsecs
        return stamp

    def stamp_parts(stamp: Any) -> tuple[int, int]:
        return stamp.secs, stamp.nsecs

    def duration(seconds: float) -> Any:
        return _Duration.from_sec(seconds)

    def camera_matrices(
        d: Sequence[float], k: Sequence[float], r: Sequence[float], p: Sequence[float]
    ) -> dict:
        """CameraInfo's matrices as constructor keywords (upper-case names in ROS1)."""
        return {"D": list(d), "K": k, "R": r, "P": p}

    def byte_data(data: Any) -> Any:
        """ROS1's Buffer* messages keep any byte buffer as it is."""
        return data


Time = _Time
Duration = _Duration
