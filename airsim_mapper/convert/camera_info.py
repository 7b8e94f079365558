"""sim Image (size, stamp) + capture setting (fov) -> sensor_msgs/CameraInfo with a pinhole model.

``f = (width/2) / tan(fov/2)`` for both axes (the simulator's model, horizontal fov), principal point at
the image centre, no distortion (plumb_bob with five zeros), R identity and P = [K | 0] (the simulator's own
CameraInfo has an identity P, which is wrong). Matrices are cached per (width, height, fov).
"""

from __future__ import annotations

import functools
import math
from collections.abc import Mapping
from typing import Any

from sensor_msgs.msg import CameraInfo

from airsim_mapper.convert import sim_fields
from airsim_mapper.convert.context import ConvertContext
from airsim_mapper.convert.errors import ConversionError
from airsim_mapper.convert.flavour import camera_matrices
from airsim_mapper.convert.stamps import sim_header

DEFAULT_FOV_DEGREES = 90.0
DISTORTION_MODEL = "plumb_bob"
Intrinsics = tuple[tuple[float, ...], tuple[float, ...], tuple[float, ...], tuple[float, ...]]


UINT32_MAX = 2**32 - 1  # CameraInfo's width and height are uint32


@functools.lru_cache(maxsize=64)
def intrinsics(width: int, height: int, fov_degrees: float) -> Intrinsics:
    """(D, K, R, P) as immutable tuples for an image size and horizontal field of view."""
    if not 0.0 < fov_degrees < 180.0:
        raise ConversionError(f"camera_info: fov-degrees must be in (0, 180), got {fov_degrees}")
    f = (width / 2.0) / math.tan(math.radians(fov_degrees) / 2.0)
    cx, cy = width / 2.0, height / 2.0
    d = (0.0,) * 5
    k = (f, 0.0, cx, 0.0, f, cy, 0.0, 0.0, 1.0)
    r = (1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0)
    p = (f, 0.0, cx, 0.0, 0.0, f, cy, 0.0, 0.0, 0.0, 1.0, 0.0)
    return d, k, r, p


@sim_fields.converter("camera_info")
def camera_info(msg: Mapping[str, Any], ctx: ConvertContext) -> CameraInfo:
    """CameraInfo for the image ``msg`` (width, height, time_stamp) and ctx.source's ``fov-degrees``.

    The simulator's own CameraInfo on the disparity image topic (see sim_fields.is_camera_info) is skipped:
    it has no stamp, and the next image brings the same information."""
    if sim_fields.is_camera_info(msg):
        return None
    width = sim_fields.integer(sim_fields.field(msg, "width", "image"), "camera_info: width")
    height = sim_fields.integer(sim_fields.field(msg, "height", "image"), "camera_info: height")
    if not (0 < width <= UINT32_MAX and 0 < height <= UINT32_MAX):
        raise ConversionError(f"camera_info: size {width}x{height} must be positive and fit a uint32")
    fov = sim_fields.number(ctx.source.get("fov-degrees", DEFAULT_FOV_DEGREES), "camera_info: fov-degrees")
    d, k, r, p = intrinsics(width, height, fov)
    return CameraInfo(
        header=sim_header(msg, ctx),
        height=height,
        width=width,
        distortion_model=DISTORTION_MODEL,
        **camera_matrices(d, k, r, p),
    )
