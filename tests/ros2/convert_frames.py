"""Converts one fixed set of simulator frames with the converters of whichever ROS this interpreter has,
and prints each message as flavour-neutral JSON (run by .venv's Python for ROS1 and .venv-ros2's for ROS 2).

The neutral form: every field by its ROS 2 name (ROS1's CameraInfo `K`/`D`/`R`/`P` lower-cased), stamps and
durations as (sec, nanosec), no header `seq` (ROS 2 has none), byte arrays as lists of ints, float32 values
as float32 would carry them. Two equal dumps mean field-for-field equal ROS1 and ROS 2 messages.
"""

from __future__ import annotations

import json
import math
import sys
from typing import Any

import numpy as np

from airsim_mapper.convert import registry
from airsim_mapper.convert.context import ConvertContext

POSE = {
    "position": {"x": 1.5, "y": -2.0, "z": -4.0},
    "orientation": {"w": 0.5, "x": 0.5, "y": -0.5, "z": 0.5},
}
RNG = np.random.default_rng(7)
POINTS = RNG.normal(size=3 * 50).astype(np.float32)
BGR = bytes(RNG.integers(0, 256, 8 * 6 * 3, dtype=np.uint8))
DEPTH = RNG.random(8 * 6).astype(np.float16).tobytes()


def image(encoding: str, data: bytes) -> dict:
    return {"time_stamp": 1_000_000_123, "height": 6, "width": 8, "encoding": encoding, "data": data}


FRAMES: list[tuple[str, dict, dict]] = [
    ("pose", {"time_stamp": 12_345_678_901, **POSE}, {}),
    ("image", image("BGR", BGR), {}),
    ("image", image("16FC1", DEPTH), {}),
    ("camera_info", {"time_stamp": 3_000_000_001, "width": 640, "height": 480}, {"fov-degrees": 70.0}),
    (
        "pointcloud",
        {
            "time_stamp": 1_700_000_000_123_456_789,
            "point_cloud": POINTS,
            "intensity_cloud": RNG.random(50).astype(np.float32),
            "segmentation_cloud": RNG.integers(-5, 300, 50).astype(np.int32),
        },
        {},
    ),
    (
        "radar_scan",
        {
            "time_stamp": 5_000_000_000,
            "radar_detections": [
                {"range": 10.0, "azimuth": 0.1, "elevation": 0.2, "velocity": -1.5, "rcs_sqm": 1.0},
                {"range": 22.5, "azimuth": -0.3, "elevation": 0.0, "velocity": 3.0, "rcs_sqm": 4.0},
            ],
            "pose": POSE,
        },
        {},
    ),
    (
        "radar_tracks",
        {
            "time_stamp": 1,
            "radar_tracks": [
                {
                    "id": -7,
                    "azimuth_est": 0.2,
                    "elevation_est": 0.1,
                    "range_est": 10.2,
                    "position_est": {"x": 10.0, "y": 2.0, "z": -1.0},
                    "velocity_est": {"x": 1.0, "y": -1.0, "z": 0.5},
                    "accel_est": {"x": 0.0, "y": 0.1, "z": 0.2},
                    "rcs_sqm": 2.0,
                }
            ],
            "pose": POSE,
        },
        {},
    ),
    ("odometry", {"time_stamp": 2_000_000_000, **POSE}, {}),
    (
        "imu",
        {
            "time_stamp": 2_000_000_000,
            "orientation": {"w": 1.0, "x": 0.0, "y": 0.0, "z": 0.0},
            "angular_velocity": {"x": 0.1, "y": 0.2, "z": 0.3},
            "linear_acceleration": {"x": 0.0, "y": 0.5, "z": -9.8},
        },
        {},
    ),
    (
        "gps",
        {
            "time_stamp": 1,
            "time_utc_millis": 1_700_000_000_000,
            "latitude": 47.641468,
            "longitude": -122.140165,
            "altitude": 122.0,
            "epv": 0.2,
            "eph": 0.1,
            "position_cov_type": 0,
            "fix_type": 3,
            "velocity": {"x": 0.0, "y": 0.0, "z": 0.0},
        },
        {},
    ),
    ("barometer", {"time_stamp": 3, "altitude": 120.0, "pressure": 101.3, "qnh": 1013.25}, {}),
    (
        "magnetometer",
        {
            "time_stamp": 4,
            "magnetic_field_body": {"x": 0.2, "y": -0.05, "z": 0.4},
            "magnetic_field_covariance": [0.0] * 9,
        },
        {},
    ),
    ("distance", {"time_stamp": 9, "current_distance": 12.5}, {"min-distance": 0.5, "max-distance": 50.0}),
    (
        "battery",
        {
            "time_stamp": 5,
            "battery_pct_remaining": 83.0,
            "estimated_time_remaining": 1200,
            "battery_charge_state": "BATTERY_CHARGE_STATE_OK",
        },
        {},
    ),
    ("clock", {"time_stamp": 7_000_000_042}, {}),
]
FLOAT32 = {"float32", "float"}  # genpy's and rosidl's name of it


def fields(msg: Any) -> list[tuple[str, str]]:
    """(name, type) of each field: rosidl's `get_fields_and_field_types`, or genpy's slots."""
    if hasattr(msg, "get_fields_and_field_types"):
        return list(msg.get_fields_and_field_types().items())
    return [(name, kind) for name, kind in zip(msg.__slots__, msg._slot_types) if name != "seq"]


def plain(value: Any, kind: str = "") -> Any:
    """`value` as JSON of the neutral form."""
    if hasattr(value, "secs") and hasattr(value, "nsecs"):  # genpy Time or Duration
        return {"sec": value.secs, "nanosec": value.nsecs}
    if hasattr(value, "_slot_types") or hasattr(value, "get_fields_and_field_types"):
        return {name.lower(): plain(getattr(value, name), kind) for name, kind in fields(value)}
    if isinstance(value, (bytes, bytearray, memoryview)):
        return list(bytes(value))
    if isinstance(value, np.ndarray) or type(value).__name__ == "array":
        value = value.tolist()
    if isinstance(value, (list, tuple)):
        return [plain(v, kind) for v in value]
    if isinstance(value, float):
        if kind.removeprefix("sequence<").split("[")[0].rstrip(">") in FLOAT32:
            value = float(np.float32(value))
        return value if math.isfinite(value) else repr(value)
    return value


def main() -> int:
    out = []
    state: dict = {}
    for name, frame, source in FRAMES:
        ctx = ConvertContext(
            frame_id=f"frame/{name}", source=source, state=state if name == "odometry" else {}
        )
        message = registry.get(name)(frame, ctx)
        out.append(
            {"converter": name, "type": type(message).__name__.removeprefix("Buffer"), "msg": plain(message)}
        )
    print(json.dumps(out, sort_keys=True))
    return 0


if __name__ == "__main__":
    sys.exit(main())
