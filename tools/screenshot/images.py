"""The X screen's pixels: Xvfb's XWD framebuffer read, a PNG written, and what there is to see."""

from __future__ import annotations

import struct
import zlib
from pathlib import Path

import numpy as np

from tools.screenshot.errors import ScreenshotError


def read_xwd(path: Path) -> np.ndarray:
    """(H, W, 3) uint8 RGB of a 24/32-bit TrueColor XWD file (what Xvfb -fbdir maps)."""
    raw = Path(path).read_bytes()
    if len(raw) < 100:
        raise ScreenshotError(f"{path}: not an XWD file ({len(raw)} bytes)")
    head = struct.unpack(">25I", raw[:100])
    header_size, version, pixmap_format, _depth, width, height = head[:6]
    byte_order, bits_per_pixel, bytes_per_line = head[7], head[11], head[12]
    masks, ncolors = head[14:17], head[19]
    if version != 7 or pixmap_format != 2 or bits_per_pixel != 32:
        raise ScreenshotError(
            f"{path}: unsupported XWD (version {version}, format {pixmap_format}, {bits_per_pixel} bpp)"
        )
    offset = header_size + 12 * ncolors
    if len(raw) < offset + height * bytes_per_line:
        raise ScreenshotError(f"{path}: truncated XWD")
    words = np.frombuffer(
        raw, dtype="<u4" if byte_order == 0 else ">u4", count=height * bytes_per_line // 4, offset=offset
    )
    pixels = words.reshape(height, bytes_per_line // 4)[:, :width]
    channels = []
    for mask in masks:
        shift = (mask & -mask).bit_length() - 1
        channels.append(((pixels & mask) >> shift).astype(np.uint8))
    return np.stack(channels, axis=-1)


def write_png(path: Path, rgb: np.ndarray) -> None:
    """Write an (H, W, 3) uint8 array as an 8-bit RGB PNG (zlib, no filter: small for flat UI images)."""
    height, width, _ = rgb.shape
    rows = np.concatenate(
        [np.zeros((height, 1), np.uint8), np.ascontiguousarray(rgb).reshape(height, -1)], axis=1
    )

    def chunk(kind: bytes, data: bytes) -> bytes:
        return struct.pack(">I", len(data)) + kind + data + struct.pack(">I", zlib.crc32(kind + data))

    header = struct.pack(">IIBBBBB", width, height, 8, 2, 0, 0, 0)
    body = chunk(b"IHDR", header) + chunk(b"IDAT", zlib.compress(rows.tobytes(), 9)) + chunk(b"IEND", b"")
    Path(path).write_bytes(b"\x89PNG\r\n\x1a\n" + body)


def image_stats(rgb: np.ndarray) -> dict[str, float]:
    """How much there is to see: pixel standard deviation and the number of distinct colours."""
    flat = rgb.reshape(-1, 3).astype(np.uint32)
    packed = (flat[:, 0] << 16) | (flat[:, 1] << 8) | flat[:, 2]
    return {"std": float(rgb.std()), "colours": int(np.unique(packed).size)}


def background_share(rgb: np.ndarray, colour: tuple[int, int, int]) -> float:
    """The share of the screen in `colour`: 0 until RViz has drawn its 3D view once."""
    return float(np.all(rgb == np.array(colour, dtype=rgb.dtype), axis=-1).mean())
