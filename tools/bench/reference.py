"""The existing bridge's algorithms, rewritten from their description (prior-art.md part 1, §2.4-§2.7, §5).

They are the yardstick of the benchmark, not something to use: per-point tuples and `struct.pack_into` for
lidar (the [MS] NWU flip, then ROS1 `create_cloud_xyz32`), a per-pixel loop for 32FC1 depth ([IA]), the
bytes passed through for BGR images, and `math.log10` per radar detection. Every function takes the message
dict the 1.1.0 client delivers (lists, not arrays) and returns the ROS message the old bridge published.
"""

from __future__ import annotations

import ctypes
import math
import struct
from collections.abc import Mapping
from typing import Any

import numpy as np
import rospy
from radar_msgs.msg import RadarReturn, RadarScan
from sensor_msgs.msg import Image, PointCloud2, PointField
from std_msgs.msg import Header

XYZ_FIELDS = (("x", 0), ("y", 4), ("z", 8))


def _header(msg: Mapping[str, Any], frame_id: str) -> Header:
    stamp_ns = int(msg["time_stamp"])
    return Header(stamp=rospy.Time(stamp_ns // 1_000_000_000, stamp_ns % 1_000_000_000), frame_id=frame_id)


def lidar_to_cloud(msg: Mapping[str, Any], frame_id: str = "lidar") -> PointCloud2:
    """[MS] lidar: a tuple list comprehension with the NWU flip, then create_cloud_xyz32's pack_into loop."""
    flat = msg["point_cloud"]
    points = [(flat[i], -flat[i + 1], -flat[i + 2]) for i in range(0, len(flat), 3)]
    fields = [
        PointField(name=name, offset=offset, datatype=PointField.FLOAT32, count=1)
        for name, offset in XYZ_FIELDS
    ]
    cloud_struct = struct.Struct("<fff")
    buffer = ctypes.create_string_buffer(cloud_struct.size * len(points))
    pack_into, offset = cloud_struct.pack_into, 0
    for point in points:
        pack_into(buffer, offset, *point)
        offset += cloud_struct.size
    return PointCloud2(
        header=_header(msg, frame_id),
        height=1,
        width=len(points),
        is_dense=False,
        is_bigendian=False,
        fields=fields,
        point_step=cloud_struct.size,
        row_step=cloud_struct.size * len(points),
        data=buffer.raw,
    )


def depth_32fc1_to_image(msg: Mapping[str, Any], frame_id: str = "camera") -> Image:
    """[IA] depth: every float of `data_float` turned into its 4 bytes one pixel at a time."""
    data: list[int] = []
    for value in msg["data_float"]:
        data.extend(np.frombuffer(np.float32(value).tobytes(), dtype=np.uint8))
    height = int(msg["height"])
    pixels = np.array(data, dtype=np.uint8)
    return Image(
        header=_header(msg, frame_id),
        height=height,
        width=int(msg["width"]),
        encoding="32FC1",
        is_bigendian=0,
        step=len(pixels) // max(height, 1),
        data=pixels.tobytes(),
    )


def bgr_to_image(msg: Mapping[str, Any], frame_id: str = "camera") -> Image:
    """[MS]/[IA] BGR: the sim's bytes passed through (already copy-free in the old bridge)."""
    return Image(
        header=_header(msg, frame_id),
        height=int(msg["height"]),
        width=int(msg["width"]),
        encoding="bgr8",
        is_bigendian=0,
        step=3 * int(msg["width"]),
        data=msg["data"],
    )


def radar_to_scan(msg: Mapping[str, Any], frame_id: str = "radar") -> RadarScan:
    """[MS] radar: one RadarReturn per detection, amplitude from math.log10 (raises on rcs or range 0)."""
    returns = []
    for detection in msg["radar_detections"]:
        r, rcs = detection["range"], detection["rcs_sqm"]
        amplitude = 10 * math.log10(rcs * 1000 / (16 * math.pi**2 * r**4) * 0.7 * 15)
        returns.append(
            RadarReturn(
                range=r,
                azimuth=detection["azimuth"],
                elevation=detection["elevation"],
                doppler_velocity=detection["velocity"],
                amplitude=amplitude,
            )
        )
    return RadarScan(header=_header(msg, frame_id), returns=returns)
