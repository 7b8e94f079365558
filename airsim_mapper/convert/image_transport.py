"""image_transport's `compressed` and `compressedDepth` payloads, as its stock plugins write them.

Pure functions of pixels (numpy arrays) to the `format` string and `data` bytes of a
sensor_msgs/CompressedImage, so that a subscriber with compressed_image_transport or
compressed_depth_image_transport decodes them unchanged:

- `compressed`, JPEG: `"<encoding>; jpeg compressed bgr8"` for a colour image (8-bit B, G, R), and
  `"<encoding>; jpeg compressed "` (the target left empty, the space kept) for a mono one; `data` is a
  baseline JFIF file.
- `compressed`, PNG: `"<encoding>; png compressed bgr<bits>"` for colour, `"<encoding>; png compressed "`
  for mono; `data` is a PNG file of 8 or 16 bits per sample.
- `compressedDepth`: `"32FC1; compressedDepth png"`, and `data` is the plugin's 12-byte `ConfigHeader`
  (little-endian int32 `format`, 0 for INV_DEPTH, then float32 `depthParam[0]` = A and `depthParam[1]` = B)
  followed by a 16-bit greyscale PNG of the quantised inverse depth: ``q = A / d + B`` for a depth d under
  `depth_max` with ``A = z0 * (z0 + 1)`` and ``B = 1 - A / depth_max`` (z0 being `depth_quantization`),
  0 for no reading (NaN, at or beyond `depth_max`, or not positive). The subscriber restores
  ``d = A / (q - B)`` and NaN for 0. q is truncated towards zero as the plugin's float to uint16
  conversion does, and clipped to 65535 for depths closer than ``A / (65535 - B)`` (0.15 m with the
  defaults), where the plugin's conversion would overflow.

JPEG is OpenCV's (`cv2.imencode`: libjpeg-turbo inside the opencv-python wheel the projectairsim client
already requires, the call the plugins make). PNG is written here with the standard library's zlib, every
row with filter type 0: a 16-bit depth frame in a quarter of the time libpng's adaptive filters take, at
the same zlib level. docs/performance.md has the measurements that chose them.
"""

from __future__ import annotations

import struct
import zlib
from dataclasses import dataclass

import numpy as np

from airsim_mapper.convert.errors import ConversionError

# compressed_image_transport's dynamic-reconfigure defaults and ranges (CompressedPublisher.cfg)
JPEG = "jpeg"
PNG = "png"
FORMATS = (JPEG, PNG)
JPEG_QUALITY = (80, 1, 100)  # default, min, max
PNG_LEVEL = (9, 1, 9)
# compressed_depth_image_transport's (CompressedDepthPublisher.cfg)
DEPTH_PNG_LEVEL = (1, 1, 9)
DEPTH_MAX = (10.0, 1.0, 100.0)  # metres
DEPTH_QUANTIZATION = (100.0, 1.0, 150.0)  # the depth at which one quantisation step is 1 m

PNG_SIGNATURE = b"\x89PNG\r\n\x1a\n"
PNG_LENGTH = struct.Struct(">I")  # a chunk's length, and its CRC after it
PNG_IHDR = struct.Struct(">IIBBBBB")  # width, height, bit depth, colour type, compression, filter, interlace
CONFIG_HEADER = struct.Struct("<iff")  # ConfigHeader: compressionFormat format; float depthParam[2]
INV_DEPTH = 0  # compressionFormat's INV_DEPTH
DEPTH_FORMAT = "32FC1; compressedDepth png"
# the encodings taken, as pixels already in the order the plugin converts to (B, G, R), with their bits
COLOUR_ENCODINGS = {"bgr8": 8, "bgr16": 16}
MONO_ENCODINGS = {"mono8": 8, "mono16": 16}


class EncodingFailed(ConversionError):
    """The encoder refused an image (an encoding the transport cannot carry, or a library failure)."""


@dataclass(frozen=True)
class Compressed:
    """A CompressedImage's payload: its `format` string and `data` bytes."""

    format: str
    data: bytes


def compressed_format(encoding: str, codec: str) -> str:
    """The `format` compressed_image_transport writes for an image of `encoding` sent as `codec`."""
    bits = COLOUR_ENCODINGS.get(encoding) or MONO_ENCODINGS.get(encoding)
    if bits is None or codec not in FORMATS or (codec == JPEG and bits != 8):
        raise EncodingFailed(f"image_transport's compressed transport cannot send {encoding} as {codec}")
    target = f"bgr{bits}" if encoding in COLOUR_ENCODINGS else ""
    return f"{encoding}; {codec} compressed {target}"


def _encoded(extension: str, pixels: np.ndarray, options: list[int]) -> bytes:
    import cv2

    try:
        ok, encoded = cv2.imencode(extension, pixels, options)
    except cv2.error as exc:
        raise EncodingFailed(f"{extension} encoding failed: {exc}") from exc
    if not ok:
        raise EncodingFailed(f"{extension} encoding of a {pixels.shape} {pixels.dtype} image failed")
    return encoded.tobytes()


def encode_jpeg(pixels: np.ndarray, quality: int = JPEG_QUALITY[0]) -> bytes:
    """A baseline JPEG of an 8-bit image: (height, width, 3) in B, G, R order, or (height, width)."""
    import cv2

    return _encoded(".jpg", pixels, [cv2.IMWRITE_JPEG_QUALITY, quality])


def _chunk(kind: bytes, body: bytes) -> bytes:
    return PNG_LENGTH.pack(len(body)) + kind + body + PNG_LENGTH.pack(zlib.crc32(kind + body))


def encode_png(pixels: np.ndarray, level: int = PNG_LEVEL[0]) -> bytes:
    """A PNG of an 8- or 16-bit image, (height, width, 3) in B, G, R order (written as RGB, colour type 2)
    or (height, width) (greyscale, colour type 0); no interlace, filter type 0 on every row, the IDAT
    compressed at zlib `level`."""
    if pixels.dtype not in (np.uint8, np.uint16) or not (
        pixels.ndim == 2 or (pixels.ndim == 3 and pixels.shape[2] == 3)
    ):
        raise EncodingFailed(f"PNG takes 8- or 16-bit grey or BGR pixels, not {pixels.dtype} {pixels.shape}")
    height, width = pixels.shape[:2]
    if not height or not width:
        raise EncodingFailed(f"PNG of a {width}x{height} image: no pixels")
    samples = pixels[..., ::-1] if pixels.ndim == 3 else pixels  # B, G, R -> R, G, B
    big_endian = np.ascontiguousarray(samples, dtype=pixels.dtype.newbyteorder(">"))
    rows = np.empty((height, 1 + big_endian[0].nbytes), np.uint8)
    rows[:, 0] = 0  # filter type 0: each row as it is
    rows[:, 1:] = big_endian.view(np.uint8).reshape(height, -1)
    colour_type = 2 if pixels.ndim == 3 else 0
    ihdr = PNG_IHDR.pack(width, height, 8 * pixels.itemsize, colour_type, 0, 0, 0)
    idat = zlib.compress(rows.data, level)
    return PNG_SIGNATURE + _chunk(b"IHDR", ihdr) + _chunk(b"IDAT", idat) + _chunk(b"IEND", b"")


def compressed(
    pixels: np.ndarray,
    encoding: str,
    codec: str,
    jpeg_quality: int = JPEG_QUALITY[0],
    png_level: int = PNG_LEVEL[0],
) -> Compressed:
    """The `compressed` transport's payload of an image already in B, G, R order (or mono)."""
    form = compressed_format(encoding, codec)
    if codec == JPEG:
        return Compressed(form, encode_jpeg(pixels, jpeg_quality))
    return Compressed(form, encode_png(pixels, png_level))


def quantisation(depth_max: float, depth_quantization: float) -> tuple[float, float]:
    """(A, B) of the inverse-depth quantisation, as float32 values, as the plugin stores them."""
    z0 = np.float32(depth_quantization)
    a = np.float32(z0 * (z0 + np.float32(1.0)))
    b = np.float32(np.float32(1.0) - a / np.float32(depth_max))
    return float(a), float(b)


def quantised_inverse_depth(
    depth: np.ndarray, depth_max: float = DEPTH_MAX[0], depth_quantization: float = DEPTH_QUANTIZATION[0]
) -> tuple[np.ndarray, float, float]:
    """float32 metres -> (uint16 quantised inverse depth, A, B); 0 where there is no reading."""
    a, b = quantisation(depth_max, depth_quantization)
    depth = np.asarray(depth, dtype=np.float32)
    valid = (depth > 0) & (depth < np.float32(depth_max))  # NaN compares false: no reading
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        inverse = np.float32(a) / depth + np.float32(b)
    quantised = np.where(valid, np.clip(inverse, 0, 65535), 0).astype(np.uint16)
    return quantised, a, b


def restored_depth(quantised: np.ndarray, a: float, b: float) -> np.ndarray:
    """What compressed_depth_image_transport's subscriber makes of a quantised inverse depth: float32
    metres, NaN for 0."""
    q = quantised.astype(np.float32)
    with np.errstate(divide="ignore"):
        depth = np.float32(a) / (q - np.float32(b))
    return np.where(quantised > 0, depth, np.float32(np.nan)).astype(np.float32)


def compressed_depth(
    depth: np.ndarray,
    depth_max: float = DEPTH_MAX[0],
    depth_quantization: float = DEPTH_QUANTIZATION[0],
    png_level: int = DEPTH_PNG_LEVEL[0],
) -> Compressed:
    """The `compressedDepth` transport's payload of a 32FC1 depth image in metres."""
    if depth.dtype != np.float32 or depth.ndim != 2:
        raise EncodingFailed(f"compressedDepth takes a 32FC1 image, not {depth.dtype} of shape {depth.shape}")
    quantised, a, b = quantised_inverse_depth(depth, depth_max, depth_quantization)
    data = CONFIG_HEADER.pack(INV_DEPTH, a, b) + encode_png(quantised, png_level)
    return Compressed(DEPTH_FORMAT, data)
