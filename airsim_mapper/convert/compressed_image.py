"""sim Image (PNG) -> sensor_msgs/CompressedImage: the simulator's PNG bytes as they are.

For image_transport's `compressed` transport (`<image topic>/compressed`): rosbag records small images and
a remote viewer decodes them itself, while the bridge never decodes or encodes a pixel. The format string
is the one compressed_image_transport writes and reads, "bgr8; png compressed bgr8": the PNG decodes
(cv2.imdecode) to bgr8 and needs no colour conversion.

The simulator sends PNG only for a colour capture setting with `"compress": true`. Anything else (raw
`BGR` pixels, depth's `16FC1`) is refused with a ConversionError that says so, counted in the bridge's
errors: encoding here would cost the CPU this converter exists to save, and the `image` converter already
publishes raw pixels. The PNG's size is read from its IHDR header and must be the declared one, and an
image over `max_pixels` (the rule's `params.max_pixels`) is refused as oversized, as `image` does.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

from sensor_msgs.msg import CompressedImage

from airsim_mapper.convert import sim_fields
from airsim_mapper.convert.buffer_data import BufferData, ros2_buffer_message
from airsim_mapper.convert.context import ConvertContext
from airsim_mapper.convert.errors import ConversionError, OversizedData
from airsim_mapper.convert.flavour import ROS2
from airsim_mapper.convert.image import MAX_PIXELS, pixel_bytes, png_size
from airsim_mapper.convert.stamps import sim_header

FORMAT = "bgr8; png compressed bgr8"  # compressed_image_transport's "<encoding>; png compressed <target>"
COMPRESSED = "PNG"  # the simulator's encoding of a compressed colour image


if ROS2:
    BufferCompressedImage = ros2_buffer_message(CompressedImage)
else:

    class BufferCompressedImage(BufferData, CompressedImage):
        """sensor_msgs/CompressedImage whose ``data`` may be any byte buffer (`buffer_data`)."""

        __slots__ = CompressedImage.__slots__
        _slot_types = CompressedImage._slot_types
        _genpy_class = CompressedImage


@sim_fields.converter("compressed_image")
def compressed_image(msg: Mapping[str, Any], ctx: ConvertContext) -> CompressedImage | None:
    """sim Image with PNG data -> CompressedImage carrying those bytes; None for the CameraInfo the
    simulator sends on the disparity image topic."""
    if sim_fields.is_camera_info(msg):
        return None
    encoding = sim_fields.field(msg, "encoding", "image")
    if encoding != COMPRESSED:
        raise ConversionError(
            f'the simulator sent {encoding!r} pixels, not PNG: set "compress": true in this image type\'s '
            "capture settings (colour images only: depth cannot be compressed), or use the image converter"
        )
    height = sim_fields.integer(sim_fields.field(msg, "height", "image"), "compressed_image: height")
    width = sim_fields.integer(sim_fields.field(msg, "width", "image"), "compressed_image: width")
    if height <= 0 or width <= 0:
        raise ConversionError(f"compressed_image: size {width}x{height} has no pixels")
    limit = ctx.params.get("max_pixels", MAX_PIXELS)
    if height * width > limit:
        raise OversizedData(
            f"compressed_image: {width}x{height} is over the limit of {limit} pixels (max_pixels)"
        )
    data = pixel_bytes(sim_fields.field(msg, "data", "image"))
    if not len(data):
        raise ConversionError(
            "compressed_image: the PNG data is empty (the simulator sends none for this capture setting)"
        )
    header_width, header_height = png_size(data)
    if (header_width, header_height) != (width, height):
        raise ConversionError(
            f"the PNG header says {header_width}x{header_height}, the message {width}x{height}"
        )
    return BufferCompressedImage(header=sim_header(msg, ctx), format=FORMAT, data=data)
