"""sim Image -> sensor_msgs/Image.

Encodings: ``BGR`` -> bgr8 (the sim's buffer itself, no copy), ``PNG`` -> decoded bgr8, ``16FC1``
(float16 metres, the 1.1.0 depth format) -> 32FC1 metres, legacy ``16UC1`` (uint16 millimetres) -> 32FC1
metres, ``GRAY8`` -> mono8, and the git server's ``32FC1`` (pixels in ``data`` or ``data_float``) -> 32FC1.
``data`` may be bytes (topic form), another bytes-like object, or a list of ints (GetImages form).
float16 -> float32 uses OpenCV's SIMD conversion (bit-exact with numpy's astype, and faster).

Bounds, checked before any pixel is converted: an image with no pixels (0xN) is dropped; one over
``max_pixels`` (the rule's ``params.max_pixels``, default MAX_PIXELS) raises OversizedData, and so does
one whose converted pixels would take more than ``params.max_bytes`` (default MAX_BYTES): a 7000x7000
colour PNG of 155 kB is under the pixel cap, but decodes into 147 MB. A PNG's own
size is read from its IHDR header and must be the declared one, so a small compressed file cannot decode
into an image far larger than the message says.

The result is a `BufferImage`: a sensor_msgs/Image whose ``data`` may be any byte buffer (bytes, or a
memoryview of the received frame or of the converted pixels), written out as it is when published.
"""

from __future__ import annotations

import functools
import struct
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np
from sensor_msgs.msg import Image

from airsim_mapper.convert import sim_fields
from airsim_mapper.convert.buffer_data import BufferData, ros2_buffer_message
from airsim_mapper.convert.context import ConvertContext
from airsim_mapper.convert.errors import ConversionError, OversizedData
from airsim_mapper.convert.flavour import ROS2
from airsim_mapper.convert.stamps import sim_header


@dataclass(frozen=True)
class Encoding:
    ros: str  # ROS encoding produced
    in_bytes: int  # bytes per pixel in the sim data
    out_bytes: int  # bytes per pixel in the ROS data


ENCODINGS: dict[str, Encoding] = {
    "BGR": Encoding("bgr8", 3, 3),
    "PNG": Encoding("bgr8", 0, 3),
    "16FC1": Encoding("32FC1", 2, 4),
    "16UC1": Encoding("32FC1", 2, 4),
    "GRAY8": Encoding("mono8", 1, 1),
    "32FC1": Encoding("32FC1", 4, 4),
}
MM_PER_M = 1000.0
MAX_PIXELS = 50_000_000  # per image; an 8K frame has 33 million
MAX_BYTES = 100_000_000  # converted pixels per image; an 8K colour frame has 99.5 million
PNG_SIGNATURE = b"\x89PNG\r\n\x1a\n"
PNG_IHDR = struct.Struct(">I4sII")  # the first chunk: length, b"IHDR", width, height


if ROS2:
    BufferImage = ros2_buffer_message(Image)
else:

    class BufferImage(BufferData, Image):
        """sensor_msgs/Image whose ``data`` may be any byte buffer (`buffer_data`): the pixels are written as
        they are, or sent from where they are."""

        __slots__ = Image.__slots__  # genpy validates keyword fields against the class's own __slots__
        _slot_types = Image._slot_types
        _genpy_class = Image


def as_bytes_view(array: np.ndarray) -> memoryview:
    """The bytes of a numpy array as a flat memoryview, without a copy when it is contiguous."""
    return memoryview(np.ascontiguousarray(array)).cast("B")


Pixels = bytes | memoryview  # a flat byte buffer


def pixel_bytes(data: Any) -> Pixels:
    """The pixel payload as a flat byte buffer: bytes and contiguous memoryviews as they are (no copy);
    other bytes-likes copied once; a list of ints packed."""
    if isinstance(data, bytes):
        return data
    if isinstance(data, memoryview) and data.c_contiguous:
        return data.cast("B") if data.format != "B" or data.ndim != 1 else data
    if isinstance(data, (bytearray, memoryview)):
        return bytes(data)
    if isinstance(data, np.ndarray):
        return np.ascontiguousarray(data).tobytes()
    if isinstance(data, (list, tuple)):
        try:
            return bytes(data)
        except (TypeError, ValueError) as exc:
            raise ConversionError(f"image: data list must hold ints in 0..255 ({exc})") from exc
    raise ConversionError(f"image: data must be bytes or a list of ints, got {type(data).__name__}")


def _check_size(data: Pixels, height: int, width: int, encoding: str, per_pixel: int) -> None:
    expected = height * width * per_pixel
    if len(data) != expected:
        raise ConversionError(
            f"image: data has {len(data)} bytes, expected {expected} for {width}x{height} {encoding}"
        )


def png_size(data: Pixels) -> tuple[int, int]:
    """(width, height) from a PNG's IHDR header, without decoding anything."""
    head = bytes(data[: len(PNG_SIGNATURE) + PNG_IHDR.size])
    if not head.startswith(PNG_SIGNATURE):
        raise ConversionError("image: PNG data does not start with the PNG signature")
    if len(head) < len(PNG_SIGNATURE) + PNG_IHDR.size:
        raise ConversionError(f"image: PNG data is {len(data)} bytes, too short for its header")
    _length, kind, width, height = PNG_IHDR.unpack_from(head, len(PNG_SIGNATURE))
    if kind != b"IHDR":
        raise ConversionError(f"image: PNG's first chunk is {kind!r}, not IHDR")
    return width, height


def _decode_png(data: Pixels, height: int, width: int) -> Pixels:
    import cv2

    if not data:
        raise ConversionError("image: PNG data is empty")
    header_width, header_height = png_size(data)
    if (header_height, header_width) != (height, width):
        raise ConversionError(
            f"image: PNG header says {header_width}x{header_height}, the message {width}x{height}; "
            "not decoded"
        )
    try:
        decoded = cv2.imdecode(np.frombuffer(data, dtype=np.uint8), cv2.IMREAD_COLOR)
    except cv2.error as exc:
        raise ConversionError(f"image: PNG data could not be decoded ({exc})") from exc
    if decoded is None:
        raise ConversionError("image: PNG data could not be decoded")
    if decoded.shape[:2] != (height, width):
        raise ConversionError(
            f"image: PNG decodes to {decoded.shape[1]}x{decoded.shape[0]}, expected {width}x{height}"
        )
    return as_bytes_view(decoded)


@functools.lru_cache(maxsize=1)
def _half_to_float() -> Callable[[np.ndarray], np.ndarray] | None:
    """OpenCV's SIMD float16 -> float32 conversion (bit-exact with numpy's astype, faster), if available."""
    try:
        import cv2
    except ImportError:  # pragma: no cover - cv2 comes with projectairsim
        return None
    return getattr(cv2, "convertFp16", None)


def half_to_float32(data: Pixels, height: int, width: int, order: str = "<") -> np.ndarray:
    """float16 pixels -> little-endian float32 (inf and NaN kept), vectorised."""
    convert = _half_to_float()
    if convert is None or height * width == 0:
        return np.frombuffer(data, dtype=f"{order}f2").astype("<f4")
    halves = np.frombuffer(data, dtype=f"{order}u2")
    if order != "<":
        halves = halves.astype("<u2")
    return convert(halves.view("<i2").reshape(height, width)).astype("<f4", copy=False)


def _float_pixels(encoding: str, data: Pixels, height: int, width: int, order: str) -> np.ndarray:
    if encoding == "16FC1":
        return half_to_float32(data, height, width, order)
    if encoding == "16UC1":
        return np.frombuffer(data, dtype=f"{order}u2").astype("<f4") / np.float32(MM_PER_M)
    return np.frombuffer(data, dtype=f"{order}f4").astype("<f4", copy=False)


def _payload(msg: Mapping[str, Any], encoding: str) -> Pixels:
    data = sim_fields.field(msg, "data", "image")
    data_float = msg.get("data_float")  # a list, or a numpy array on the fast path
    if encoding == "32FC1" and not len(data) and data_float is not None and len(data_float):
        values = np.asarray(data_float, dtype="<f4")
        if values.ndim != 1:
            raise ConversionError("image: data_float must be a flat list of numbers")
        return as_bytes_view(values)
    return pixel_bytes(data)


@sim_fields.converter("image")
def image(msg: Mapping[str, Any], ctx: ConvertContext) -> Image:
    """sim Image -> sensor_msgs/Image (see the module docstring for encodings); None for the CameraInfo
    the simulator sends on the disparity image topic."""
    if sim_fields.is_camera_info(msg):
        return None
    encoding = sim_fields.field(msg, "encoding", "image")
    spec = ENCODINGS.get(encoding) if isinstance(encoding, str) else None
    if spec is None:
        raise ConversionError(f"image: unknown encoding {encoding!r}; expected one of {sorted(ENCODINGS)}")
    height = sim_fields.integer(sim_fields.field(msg, "height", "image"), "image: height")
    width = sim_fields.integer(sim_fields.field(msg, "width", "image"), "image: width")
    if height < 0 or width < 0:
        raise ConversionError(f"image: size {width}x{height} must not be negative")
    if height == 0 or width == 0:
        raise ConversionError(f"image: size {width}x{height} has no pixels")
    limit = ctx.params.get("max_pixels", MAX_PIXELS)
    if height * width > limit:
        raise OversizedData(f"image: {width}x{height} is over the limit of {limit} pixels (max_pixels)")
    byte_limit = ctx.params.get("max_bytes", MAX_BYTES)
    if height * width * spec.out_bytes > byte_limit:
        raise OversizedData(
            f"image: {width}x{height} {spec.ros} takes {height * width * spec.out_bytes} bytes, over the "
            f"limit of {byte_limit} (max_bytes)"
        )
    order = ">" if msg.get("big_endian", False) else "<"
    data = _payload(msg, encoding)
    if encoding == "PNG":
        data = _decode_png(data, height, width)
    else:
        _check_size(data, height, width, encoding, spec.in_bytes)
        if spec.ros == "32FC1":
            data = as_bytes_view(_float_pixels(encoding, data, height, width, order))
    return BufferImage(
        header=sim_header(msg, ctx),
        height=height,
        width=width,
        encoding=spec.ros,
        is_bigendian=0,
        step=width * spec.out_bytes,
        data=data,
    )
