"""sim Lidar -> sensor_msgs/PointCloud2 with x, y, z, intensity (float32) and segmentation (int32).

All fields are packed as ONE numpy structured array (point_step 20, little-endian); the message's data is a
view of its bytes (`BufferPointCloud2`), written or sent from where they are. Inputs may be Python lists (what
the 1.1.0 client delivers), numpy arrays, or raw little-endian bytes. ``intensity_cloud`` /
``segmentation_cloud`` default to zeros when absent (older servers); when present they must have one value per
point. Points are in the sensor frame: FRD, or FLU (y and z negated) with the ENU convention.
"""

from __future__ import annotations

import array
from collections.abc import Mapping
from typing import Any

import numpy as np
from sensor_msgs.msg import PointCloud2, PointField

from airsim_mapper.convert import sim_fields
from airsim_mapper.convert.buffer_data import BufferData, ros2_buffer_message
from airsim_mapper.convert.context import ConvertContext
from airsim_mapper.convert.errors import ConversionError
from airsim_mapper.convert.flavour import ROS2
from airsim_mapper.convert.stamps import sim_header

POINT_DTYPE = np.dtype(
    [("x", "<f4"), ("y", "<f4"), ("z", "<f4"), ("intensity", "<f4"), ("segmentation", "<i4")]
)
_ROS_TYPES = {np.dtype("<f4"): PointField.FLOAT32, np.dtype("<i4"): PointField.INT32}
_ARRAY_CODES = {"<f4": ("f", np.float32), "<i4": ("i", np.intc)}  # array.array packs lists faster


if ROS2:
    BufferPointCloud2 = ros2_buffer_message(PointCloud2)
else:

    class BufferPointCloud2(BufferData, PointCloud2):
        """sensor_msgs/PointCloud2 whose ``data`` may be any byte buffer (`buffer_data`); ``is_dense`` (one
        byte) follows it."""

        __slots__ = PointCloud2.__slots__
        _slot_types = PointCloud2._slot_types
        _genpy_class = PointCloud2
        _after_data = 1


def point_fields() -> list[PointField]:
    """Fresh PointField descriptions of POINT_DTYPE."""
    return [
        PointField(name=name, offset=POINT_DTYPE.fields[name][1], datatype=_ROS_TYPES[dt], count=1)
        for name, dt in ((n, POINT_DTYPE.fields[n][0]) for n in POINT_DTYPE.names)
    ]


def as_array(values: Any, dtype: str, where: str) -> np.ndarray:
    """A flat array of ``dtype`` from a list, an array or raw little-endian bytes."""
    if isinstance(values, (bytes, bytearray, memoryview)):
        size = np.dtype(dtype).itemsize
        if len(values) % size:
            raise ConversionError(f"pointcloud: {where} has {len(values)} bytes, not a multiple of {size}")
        return np.frombuffer(values, dtype=dtype)
    if isinstance(values, list) and dtype in _ARRAY_CODES:
        code, native = _ARRAY_CODES[dtype]
        try:
            return np.frombuffer(array.array(code, values), dtype=native).astype(dtype, copy=False)
        except (TypeError, OverflowError):
            pass  # not plain numbers: let numpy convert or explain below
    if isinstance(values, (str, Mapping)) or np.ndim(values) != 1:
        raise ConversionError(f"pointcloud: {where} must be a flat list of numbers")
    try:
        return np.asarray(values, dtype=dtype)
    except (TypeError, ValueError) as exc:
        raise ConversionError(f"pointcloud: {where} must hold numbers ({exc})") from exc


def _optional(msg: Mapping[str, Any], key: str, dtype: str, count: int) -> np.ndarray | int:
    if key not in msg:
        return 0
    values = as_array(msg[key], dtype, key)
    if len(values) != count:
        raise ConversionError(f"pointcloud: {key} has {len(values)} values, expected {count} (one per point)")
    return values


@sim_fields.converter("pointcloud")
def pointcloud(msg: Mapping[str, Any], ctx: ConvertContext) -> PointCloud2:
    """sim Lidar message -> PointCloud2 (height 1, width N)."""
    flat = as_array(sim_fields.field(msg, "point_cloud", "lidar"), "<f4", "point_cloud")
    if len(flat) % 3:
        raise ConversionError(f"pointcloud: point_cloud has {len(flat)} values, not a multiple of 3")
    xyz = flat.reshape(-1, 3)
    count = len(xyz)
    cloud = np.empty(count, dtype=POINT_DTYPE)
    cloud["x"] = xyz[:, 0]
    if ctx.enu:
        np.negative(xyz[:, 1], out=cloud["y"])
        np.negative(xyz[:, 2], out=cloud["z"])
    else:
        cloud["y"] = xyz[:, 1]
        cloud["z"] = xyz[:, 2]
    cloud["intensity"] = _optional(msg, "intensity_cloud", "<f4", count)
    cloud["segmentation"] = _optional(msg, "segmentation_cloud", "<i4", count)
    return BufferPointCloud2(
        header=sim_header(msg, ctx),
        height=1,
        width=count,
        fields=point_fields(),
        is_bigendian=False,
        point_step=POINT_DTYPE.itemsize,
        row_step=POINT_DTYPE.itemsize * count,
        data=memoryview(cloud.view(np.uint8)),
        is_dense=bool(np.isfinite(flat).all()),
    )
