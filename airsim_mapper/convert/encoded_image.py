"""sim Image -> sensor_msgs/CompressedImage for image_transport's `compressed` and `compressedDepth` topics.

Each converts the frame as the `image` converter does (same encodings, bounds and stamp), then encodes the
pixels with `image_transport`. The engine runs them on their topic's worker, and only while the compressed
topic has a subscriber (the default mapping's rules are lazy), so an unwatched transport costs nothing.

Rule params, with compressed_image_transport's and compressed_depth_image_transport's defaults:
- `image_compressed`: `format` (`jpeg` or `png`), `jpeg_quality` (1-100, 80), `png_level` (1-9, 9); colour
  images and mono8 (JPEG) or mono8/16 (PNG).
- `image_compressed_depth`: `depth_max` (metres, 10), `depth_quantization` (metres, 100), `png_level`
  (1-9, 1); float depth images (32FC1 metres).
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import numpy as np
from sensor_msgs.msg import CompressedImage

from airsim_mapper.convert import image_transport as transport
from airsim_mapper.convert import sim_fields
from airsim_mapper.convert.compressed_image import BufferCompressedImage
from airsim_mapper.convert.context import ConvertContext
from airsim_mapper.convert.errors import OversizedData
from airsim_mapper.convert.image import image

CHANNELS = {"bgr8": 3, "mono8": 1}
DEPTH = "32FC1"


def _converted(msg: Mapping[str, Any], ctx: ConvertContext, name: str) -> Any:
    """The `image` converter's result, an oversized frame still OversizedData under this converter's name
    (so that the bridge counts it as oversized)."""
    try:
        return image(msg, ctx)
    except OversizedData as exc:
        raise OversizedData(f"{name}: {exc}") from None


def _pixels(out: Any) -> np.ndarray:
    """The converted image's pixels as an array (no copy): (height, width, 3) or (height, width)."""
    if out.encoding == DEPTH:
        return np.frombuffer(out.data, dtype="<f4").reshape(out.height, out.width)
    channels = CHANNELS[out.encoding]
    shape = (out.height, out.width, channels) if channels > 1 else (out.height, out.width)
    return np.frombuffer(out.data, dtype=np.uint8).reshape(shape)


@sim_fields.converter("image_compressed")
def image_compressed(msg: Mapping[str, Any], ctx: ConvertContext) -> CompressedImage | None:
    """sim Image -> CompressedImage in image_transport's `compressed` format (JPEG or PNG)."""
    out = _converted(msg, ctx, "image_compressed")
    if out is None:
        return None
    params = ctx.params
    payload = transport.compressed(
        _pixels(out),
        out.encoding,
        params.get("format", transport.JPEG),
        jpeg_quality=params.get("jpeg_quality", transport.JPEG_QUALITY[0]),
        png_level=params.get("png_level", transport.PNG_LEVEL[0]),
    )
    return BufferCompressedImage(header=out.header, format=payload.format, data=payload.data)


@sim_fields.converter("image_compressed_depth")
def image_compressed_depth(msg: Mapping[str, Any], ctx: ConvertContext) -> CompressedImage | None:
    """sim depth Image -> CompressedImage in image_transport's `compressedDepth` format."""
    out = _converted(msg, ctx, "image_compressed_depth")
    if out is None:
        return None
    if out.encoding != DEPTH:
        raise transport.EncodingFailed(f"compressedDepth takes a depth image, not {out.encoding}")
    params = ctx.params
    payload = transport.compressed_depth(
        _pixels(out),
        depth_max=params.get("depth_max", transport.DEPTH_MAX[0]),
        depth_quantization=params.get("depth_quantization", transport.DEPTH_QUANTIZATION[0]),
        png_level=params.get("png_level", transport.DEPTH_PNG_LEVEL[0]),
    )
    return BufferCompressedImage(header=out.header, format=payload.format, data=payload.data)
