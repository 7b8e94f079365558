"""image_compressed and image_compressed_depth: a simulator frame as image_transport's compressed and
compressedDepth topics carry it, decoded back the way the plugins' subscribers do."""

from __future__ import annotations

import struct

import cv2
import numpy as np
import pytest
from sensor_msgs.msg import CompressedImage

from airsim_mapper.convert import image_transport, registry
from airsim_mapper.convert.context import ConvertContext
from airsim_mapper.convert.errors import ConversionError, OversizedData

ROWS, COLS = np.indices((24, 32))
FRAME = np.stack([ROWS * 4, COLS * 3, (ROWS + COLS) * 2], axis=-1).astype(np.uint8)  # B, G, R: smooth
DEPTH = np.linspace(0.5, 60.0, 24 * 32, dtype=np.float32).reshape(24, 32)


def sim_image(encoding: str, data: bytes, width: int = 32, height: int = 24) -> dict:
    return {"time_stamp": 2_000_000_007, "width": width, "height": height, "encoding": encoding, "data": data}


def ctx(**params) -> ConvertContext:
    return ConvertContext(frame_id="cam_optical", params=params)


def test_a_bgr_frame_becomes_a_jpeg_in_the_compressed_format(roundtrip):
    msg = registry.get("image_compressed")(sim_image("BGR", FRAME.tobytes()), ctx(jpeg_quality=95))
    received = roundtrip(msg)
    assert (received._type, received._md5sum) == (CompressedImage._type, CompressedImage._md5sum)
    assert received.format == "bgr8; jpeg compressed bgr8"
    assert (received.header.stamp.secs, received.header.stamp.nsecs) == (2, 7)
    assert received.header.frame_id == "cam_optical"
    decoded = cv2.imdecode(np.frombuffer(received.data, np.uint8), cv2.IMREAD_COLOR)
    assert np.abs(decoded.astype(int) - FRAME).mean() < 2


def test_format_png_is_lossless():
    msg = registry.get("image_compressed")(sim_image("BGR", FRAME.tobytes()), ctx(format="png", png_level=1))
    assert msg.format == "bgr8; png compressed bgr8"
    decoded = cv2.imdecode(np.frombuffer(bytes(msg.data), np.uint8), cv2.IMREAD_UNCHANGED)
    np.testing.assert_array_equal(decoded, FRAME)


def test_a_depth_frame_becomes_compressed_depth_within_one_quantisation_step():
    data = DEPTH.astype("<f2").tobytes()  # the simulator's float16 metres
    msg = registry.get("image_compressed_depth")(sim_image("16FC1", data), ctx(depth_max=100.0))
    assert msg.format == "32FC1; compressedDepth png"
    fmt, a, b = struct.unpack_from("<iff", msg.data)
    assert fmt == 0 and a == 10100.0 and b == np.float32(1 - 10100.0 / 100.0)
    quantised = cv2.imdecode(np.frombuffer(bytes(msg.data)[12:], np.uint8), cv2.IMREAD_UNCHANGED)
    restored = image_transport.restored_depth(quantised, a, b)
    sent = DEPTH.astype(np.float16).astype(np.float32)
    # q truncated: the restored depth is at most one step (d^2 / A at that depth) further away
    assert np.all(restored >= sent - 1e-4)
    assert np.all(restored - sent <= restored**2 / a * 1.001 + 1e-4)


def test_the_image_converters_bounds_hold():
    with pytest.raises(
        OversizedData, match=r"^image_compressed: image: 32x24 is over the limit of 100 pixels"
    ):
        registry.get("image_compressed")(sim_image("BGR", FRAME.tobytes()), ctx(max_pixels=100))


def test_a_colour_frame_on_the_depth_transport_is_refused_as_a_conversion_error():
    with pytest.raises(ConversionError, match="image_compressed_depth: compressedDepth takes a depth image"):
        registry.get("image_compressed_depth")(sim_image("BGR", FRAME.tobytes()), ctx())
    with pytest.raises(ConversionError, match="cannot send 32FC1 as jpeg"):
        registry.get("image_compressed")(sim_image("16FC1", DEPTH.astype("<f2").tobytes()), ctx())
