"""image_transport's compressed and compressedDepth payloads, decoded back and checked byte for byte
against the layout compressed_image_transport and compressed_depth_image_transport write and read."""

from __future__ import annotations

import struct
import zlib

import cv2
import numpy as np
import pytest

from airsim_mapper.convert import image_transport as it


def colour(height: int = 48, width: int = 64) -> np.ndarray:
    rows, cols = np.mgrid[0:height, 0:width]
    return np.stack([rows * 5 % 256, cols * 4 % 256, (rows + cols) % 256], axis=-1).astype(np.uint8)


def psnr(a: np.ndarray, b: np.ndarray) -> float:
    mse = np.mean((a.astype(np.float64) - b.astype(np.float64)) ** 2)
    return float("inf") if mse == 0 else 10 * np.log10(255.0**2 / mse)


def chunks(png: bytes) -> list[tuple[bytes, bytes]]:
    """A PNG's chunks as (type, body), each CRC checked."""
    assert png[:8] == b"\x89PNG\r\n\x1a\n"
    found, at = [], 8
    while at < len(png):
        (length,) = struct.unpack_from(">I", png, at)
        kind, body = png[at + 4 : at + 8], png[at + 8 : at + 8 + length]
        (crc,) = struct.unpack_from(">I", png, at + 8 + length)
        assert crc == zlib.crc32(kind + body)
        found.append((kind, body))
        at += 12 + length
    return found


@pytest.mark.parametrize(
    ("encoding", "codec", "expected"),
    [
        ("bgr8", "jpeg", "bgr8; jpeg compressed bgr8"),
        ("mono8", "jpeg", "mono8; jpeg compressed "),
        ("bgr8", "png", "bgr8; png compressed bgr8"),
        ("bgr16", "png", "bgr16; png compressed bgr16"),
        ("mono16", "png", "mono16; png compressed "),
    ],
)
def test_the_format_string_is_the_compressed_plugins(encoding, codec, expected):
    assert it.compressed_format(encoding, codec) == expected


@pytest.mark.parametrize(
    ("encoding", "codec"), [("32FC1", "jpeg"), ("32FC1", "png"), ("mono16", "jpeg"), ("bgr8", "webp")]
)
def test_an_encoding_the_transport_cannot_carry_is_refused(encoding, codec):
    with pytest.raises(it.EncodingFailed, match=encoding):
        it.compressed_format(encoding, codec)


def test_jpeg_is_a_jfif_file_that_decodes_to_the_frame():
    frame = colour()
    payload = it.compressed(frame, "bgr8", "jpeg", jpeg_quality=90)
    assert payload.format == "bgr8; jpeg compressed bgr8"
    assert payload.data[:3] == b"\xff\xd8\xff" and payload.data[-2:] == b"\xff\xd9"
    decoded = cv2.imdecode(np.frombuffer(payload.data, np.uint8), cv2.IMREAD_COLOR)
    assert decoded.shape == frame.shape
    assert psnr(decoded, frame) > 30


def test_a_lower_jpeg_quality_gives_fewer_bytes():
    frame = colour(96, 128)
    assert len(it.encode_jpeg(frame, 20)) < len(it.encode_jpeg(frame, 95))


@pytest.mark.parametrize(
    ("pixels", "depth", "colour_type"),
    [
        (colour(), 8, 2),
        (colour()[..., 0].copy(), 8, 0),
        ((colour()[..., 1].astype(np.uint16) * 257), 16, 0),
        (colour().astype(np.uint16) * 250, 16, 2),
    ],
)
def test_png_layout_and_exact_round_trip(pixels, depth, colour_type):
    png = it.encode_png(pixels, level=6)
    found = chunks(png)
    assert [kind for kind, _ in found] == [b"IHDR", b"IDAT", b"IEND"]
    height, width = pixels.shape[:2]
    assert found[0][1] == struct.pack(">IIBBBBB", width, height, depth, colour_type, 0, 0, 0)
    raw = zlib.decompress(found[1][1])
    rows = np.frombuffer(raw, np.uint8).reshape(height, -1)
    assert (rows[:, 0] == 0).all()  # filter type 0 on every row
    decoded = cv2.imdecode(np.frombuffer(png, np.uint8), cv2.IMREAD_UNCHANGED)
    assert decoded.dtype == pixels.dtype
    np.testing.assert_array_equal(decoded, pixels)  # B, G, R back from the file's R, G, B


def test_png_refuses_float_pixels():
    with pytest.raises(it.EncodingFailed, match="float32"):
        it.encode_png(np.zeros((2, 2), np.float32))


def depth_image() -> np.ndarray:
    depth = np.linspace(0.2, 12.0, 40 * 30, dtype=np.float32).reshape(30, 40)
    depth[0, 0] = np.nan
    depth[0, 1] = np.inf
    depth[0, 2] = 10.0  # at depth_max: no reading
    depth[0, 3] = 0.0
    return depth


def test_compressed_depth_layout_byte_for_byte():
    depth = depth_image()
    payload = it.compressed_depth(depth, depth_max=10.0, depth_quantization=100.0, png_level=1)
    assert payload.format == "32FC1; compressedDepth png"
    header = payload.data[:12]
    fmt, a, b = struct.unpack("<iff", header)
    assert fmt == 0  # INV_DEPTH
    assert a == np.float32(100.0 * 101.0)
    assert b == np.float32(1.0 - np.float32(10100.0) / np.float32(10.0))
    assert payload.data[12:20] == b"\x89PNG\r\n\x1a\n"
    ihdr = chunks(payload.data[12:])[0][1]
    assert ihdr == struct.pack(">IIBBBBB", 40, 30, 16, 0, 0, 0, 0)


def test_compressed_depth_decodes_as_the_plugin_does_within_one_quantisation_step():
    depth = depth_image()
    payload = it.compressed_depth(depth, depth_max=10.0, depth_quantization=100.0)
    _fmt, a, b = struct.unpack("<iff", payload.data[:12])
    quantised = cv2.imdecode(np.frombuffer(payload.data[12:], np.uint8), cv2.IMREAD_UNCHANGED)
    assert quantised.dtype == np.uint16
    restored = it.restored_depth(quantised, a, b)
    assert np.isnan(restored[0, :4]).all()  # NaN, inf, at depth_max, zero: no reading
    valid = (depth > 0) & (depth < 10.0)
    assert np.isnan(restored[~valid]).all()
    # one step of q at depth d is d^2 / A metres, and truncation loses less than one step
    step = depth[valid] ** 2 / a
    error = restored[valid] - depth[valid]
    assert (error >= -1e-4).all()  # truncating q towards zero only moves a depth further away
    assert (error <= step * (1 + 1e-3) + 1e-4).all()


def test_near_depths_saturate_instead_of_wrapping():
    quantised, a, b = it.quantised_inverse_depth(np.array([[0.01, 0.5]], np.float32), 10.0, 100.0)
    assert quantised[0, 0] == 65535
    assert quantised[0, 1] == np.uint16(np.float32(a) / np.float32(0.5) + np.float32(b))


def test_compressed_depth_takes_only_32fc1():
    with pytest.raises(it.EncodingFailed, match="32FC1"):
        it.compressed_depth(np.zeros((2, 2), np.uint16))
