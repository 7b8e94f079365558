"""Images: zero-copy BGR, PNG decoding, float16/uint16 depth to 32FC1 metres, GRAY8, size checks."""

from __future__ import annotations

import cv2
import numpy as np
import pytest

from airsim_mapper.convert.context import ConvertContext
from airsim_mapper.convert.errors import ConversionError, OversizedData
from airsim_mapper.convert.image import MAX_PIXELS, image, png_size

CTX = ConvertContext(frame_id="airsim_node/Drone1/FrontCamera/scene_camera")


def sim_image(encoding, data, width, height, **extra):
    msg = {
        "time_stamp": 1_000_000_123,
        "height": height,
        "width": width,
        "encoding": encoding,
        "big_endian": False,
        "step": 1,
        "data": data,
    }
    msg.update(extra)
    return msg


def pixels(msg) -> np.ndarray:
    dtype = {"bgr8": np.uint8, "mono8": np.uint8, "32FC1": np.float32}[msg.encoding]
    return np.frombuffer(msg.data, dtype=dtype)


def test_bgr_image_keeps_the_sim_bytes_object_without_copying(roundtrip):
    data = bytes(range(256)) * 9  # 2304 bytes = 32x24x3
    msg = image(sim_image("BGR", data, 32, 24), CTX)
    assert msg.data is data
    assert (msg.encoding, msg.width, msg.height, msg.step, msg.is_bigendian) == ("bgr8", 32, 24, 96, 0)
    assert msg.header.frame_id == CTX.frame_id
    assert msg.header.stamp.to_nsec() == 1_000_000_123
    assert roundtrip(msg) == msg


def test_full_hd_bgr_image_is_not_copied_and_converts_fast(timed):
    data = bytes(1920 * 1080 * 3)
    msg = image(sim_image("BGR", data, 1920, 1080), CTX)
    assert msg.data is data
    assert timed(5, lambda: image(sim_image("BGR", data, 1920, 1080), CTX)) < 0.005


def test_bgr_from_a_list_of_ints_getimages_form_is_packed():
    msg = image(sim_image("BGR", [1, 2, 3, 4, 5, 6], 2, 1), CTX)
    assert msg.data == bytes([1, 2, 3, 4, 5, 6])


def test_bgr_from_a_memoryview_is_accepted():
    msg = image(sim_image("BGR", memoryview(bytes([9, 8, 7])), 1, 1), CTX)
    assert msg.data == bytes([9, 8, 7])


def test_png_is_decoded_to_bgr8(roundtrip):
    bgr = np.arange(4 * 3 * 3, dtype=np.uint8).reshape(3, 4, 3)
    ok, png = cv2.imencode(".png", bgr)
    assert ok
    msg = image(sim_image("PNG", png.tobytes(), 4, 3), CTX)
    assert (msg.encoding, msg.step) == ("bgr8", 12)
    assert msg.data == bgr.tobytes()
    assert roundtrip(msg) == msg


def test_float16_depth_becomes_float32_metres_with_inf_kept():
    depth = np.array([[0.5, 1.25], [100.0, np.inf]], dtype="<f2")
    msg = image(sim_image("16FC1", depth.tobytes(), 2, 2), CTX)
    assert (msg.encoding, msg.step) == ("32FC1", 8)
    assert pixels(msg).tolist() == [0.5, 1.25, 100.0, float("inf")]


def test_big_endian_float16_depth_is_read_as_big_endian():
    depth = np.array([2.0, 3.5], dtype=">f2")
    msg = image(sim_image("16FC1", depth.tobytes(), 2, 1, big_endian=True), CTX)
    assert pixels(msg).tolist() == [2.0, 3.5]
    assert msg.is_bigendian == 0


def test_full_hd_float16_depth_converts_in_a_few_milliseconds(timed):
    data = np.full(1920 * 1080, 12.5, dtype="<f2").tobytes()
    msg = image(sim_image("16FC1", data, 1920, 1080), CTX)
    assert len(msg.data) == 1920 * 1080 * 4
    assert timed(5, lambda: image(sim_image("16FC1", data, 1920, 1080), CTX)) < 0.1  # ~2-4 ms idle


def test_uint16_millimetre_depth_becomes_float32_metres():
    depth = np.array([0, 1500, 65535], dtype="<u2")
    msg = image(sim_image("16UC1", depth.tobytes(), 3, 1), CTX)
    assert pixels(msg).tolist() == pytest.approx([0.0, 1.5, 65.535])


def test_uint16_depth_from_a_list_of_ints_is_read_as_bytes():
    msg = image(sim_image("16UC1", [0xE8, 0x03], 1, 1), CTX)  # 1000 mm little-endian
    assert pixels(msg).tolist() == [1.0]


def test_gray8_becomes_mono8_without_copying():
    data = bytes([1, 2, 3, 4, 5, 6])
    msg = image(sim_image("GRAY8", data, 3, 2), CTX)
    assert (msg.encoding, msg.step) == ("mono8", 3)
    assert msg.data is data


def test_git_server_32fc1_depth_is_read_from_data_float():
    msg = image(sim_image("32FC1", b"", 2, 1, data_float=[1.5, 2.5]), CTX)
    assert pixels(msg).tolist() == [1.5, 2.5]


def test_truncated_bgr_data_is_rejected_with_sizes():
    with pytest.raises(ConversionError, match=r"image: data has 100 bytes, expected 921600 for 640x480 BGR"):
        image(sim_image("BGR", bytes(100), 640, 480), CTX)


def test_truncated_depth_is_rejected():
    with pytest.raises(ConversionError, match=r"image: data has 7 bytes, expected 8 for 2x2 16FC1"):
        image(sim_image("16FC1", bytes(7), 2, 2), CTX)


def test_unknown_encoding_is_rejected_listing_the_known_ones():
    with pytest.raises(ConversionError, match=r"image: unknown encoding 'YUV'; expected one of \['16FC1'"):
        image(sim_image("YUV", b"", 0, 0), CTX)


def test_data_that_is_not_a_png_is_rejected_before_decoding():
    with pytest.raises(ConversionError, match=r"image: PNG data does not start with the PNG signature"):
        image(sim_image("PNG", b"not a png", 4, 3), CTX)


def test_corrupt_png_is_rejected():
    _ok, png = cv2.imencode(".png", np.zeros((3, 4, 3), dtype=np.uint8))
    broken = png.tobytes()[:40] + b"\0" * 30
    with pytest.raises(ConversionError, match=r"image: PNG data could not be decoded"):
        image(sim_image("PNG", broken, 4, 3), CTX)


def test_a_png_header_is_read_without_decoding():
    _ok, png = cv2.imencode(".png", np.zeros((3, 4, 3), dtype=np.uint8))
    assert png_size(png.tobytes()) == (4, 3)
    with pytest.raises(ConversionError, match=r"image: PNG data is 20 bytes, too short for its header"):
        png_size(png.tobytes()[:20])
    with pytest.raises(ConversionError, match=r"image: PNG's first chunk is b'IDAT', not IHDR"):
        png_size(png.tobytes()[:12] + b"IDAT" + png.tobytes()[16:])


def png_claiming(width: int, height: int) -> bytes:
    """A small real PNG whose IHDR says width x height (a decompression bomb's header)."""
    _ok, png = cv2.imencode(".png", np.zeros((2, 2, 3), dtype=np.uint8))
    data = bytearray(png.tobytes())
    data[16:24] = width.to_bytes(4, "big") + height.to_bytes(4, "big")
    return bytes(data)


def test_a_png_whose_header_differs_from_the_message_is_not_decoded(monkeypatch):
    monkeypatch.setattr(cv2, "imdecode", lambda *_: pytest.fail("decoded"))
    with pytest.raises(
        ConversionError, match=r"image: PNG header says 16000x16000, the message 2x2; not decoded"
    ):
        image(sim_image("PNG", png_claiming(16000, 16000), 2, 2), CTX)


def test_an_image_over_max_pixels_is_oversized_before_anything_is_decoded(monkeypatch):
    monkeypatch.setattr(cv2, "imdecode", lambda *_: pytest.fail("decoded"))
    with pytest.raises(OversizedData, match=rf"image: 16000x16000 is over the limit of {MAX_PIXELS} pixels"):
        image(sim_image("PNG", png_claiming(16000, 16000), 16000, 16000), CTX)
    with pytest.raises(OversizedData, match=r"image: 20000x20000 is over"):
        image(sim_image("BGR", b"", 20000, 20000), CTX)


def test_a_rule_may_set_its_own_max_pixels():
    ctx = ConvertContext(params={"max_pixels": 11})
    with pytest.raises(OversizedData, match=r"image: 4x3 is over the limit of 11 pixels \(max_pixels\)"):
        image(sim_image("BGR", bytes(36), 4, 3), ctx)
    assert image(sim_image("BGR", bytes(36), 4, 3), ConvertContext(params={"max_pixels": 12})).width == 4


@pytest.mark.parametrize("width, height", [(0, 0), (0, 360), (640, 0)])
def test_an_image_without_pixels_is_dropped(width, height):
    with pytest.raises(ConversionError, match=rf"image: size {width}x{height} has no pixels"):
        image(sim_image("BGR", b"", width, height), CTX)


def test_empty_png_is_rejected():
    with pytest.raises(ConversionError, match=r"image: PNG data is empty"):
        image(sim_image("PNG", b"", 4, 3), CTX)


def test_png_of_another_size_is_rejected():
    _ok, png = cv2.imencode(".png", np.zeros((3, 4, 3), dtype=np.uint8))
    with pytest.raises(ConversionError, match=r"image: PNG header says 4x3, the message 5x3; not decoded"):
        image(sim_image("PNG", png.tobytes(), 5, 3), CTX)


def test_missing_data_is_rejected():
    msg = sim_image("BGR", b"", 1, 1)
    del msg["data"]
    with pytest.raises(ConversionError, match=r"image: image has no 'data'"):
        image(msg, CTX)


def test_negative_size_is_rejected():
    with pytest.raises(ConversionError, match=r"image: size 2x-1 must not be negative"):
        image(sim_image("BGR", b"", 2, -1), CTX)


def test_non_integer_width_is_rejected():
    with pytest.raises(ConversionError, match=r"image: width must be an integer, got 2.0"):
        image(sim_image("BGR", b"", 2.0, 1), CTX)


def test_data_list_with_values_out_of_byte_range_is_rejected():
    with pytest.raises(ConversionError, match=r"image: data list must hold ints in 0..255"):
        image(sim_image("GRAY8", [256], 1, 1), CTX)


def test_data_of_another_type_is_rejected():
    with pytest.raises(ConversionError, match=r"image: data must be bytes or a list of ints, got str"):
        image(sim_image("GRAY8", "x", 1, 1), CTX)


def test_float16_conversion_matches_numpy_bit_for_bit_including_specials():
    rng = np.random.default_rng(3)
    depth = (rng.random(64 * 48) * 200).astype("<f2")
    depth[:6] = [np.inf, -np.inf, np.nan, -0.0, np.float16(6e-8), np.float16(-3e-5)]
    msg = image(sim_image("16FC1", depth.tobytes(), 64, 48), CTX)
    assert np.frombuffer(msg.data, "<u4").tolist() == depth.astype("<f4").view("<u4").tolist()


def test_big_endian_float16_full_frame_matches_little_endian():
    depth = np.linspace(0.0, 50.0, 32 * 16).astype("<f2")
    little = image(sim_image("16FC1", depth.tobytes(), 32, 16), CTX)
    big = image(sim_image("16FC1", depth.astype(">f2").tobytes(), 32, 16, big_endian=True), CTX)
    assert big.data == little.data


def test_the_simulators_camera_info_on_the_disparity_image_topic_is_skipped_not_an_error():
    from airsim_mapper.convert.camera_info import camera_info
    from airsim_mapper.convert.context import ConvertContext
    from airsim_mapper.convert.image import image

    sim_info = {
        "width": 320,
        "height": 240,
        "distortion_model": "",
        "distortion_params": [0.0] * 5,
        "intrinsic_camera_matrix": [160.0, 0, 160, 0, 160, 120, 0, 0, 1],
        "rectification_matrix": [1.0, 0, 0, 0, 1, 0, 0, 0, 1],
        "projection_matrix": [1.0] + [0.0] * 11,
    }
    ctx = ConvertContext(source={"fov-degrees": 90})
    assert image(sim_info, ctx) is None
    assert camera_info(sim_info, ctx) is None


def wire(msg) -> bytes:
    from io import BytesIO

    buff = BytesIO()
    msg.serialize(buff)
    return buff.getvalue()


def test_images_go_on_the_wire_byte_for_byte_as_genpy_writes_them():
    from sensor_msgs.msg import Image

    from tools.bench.costs import as_genpy

    bgr = np.arange(4 * 3 * 3, dtype=np.uint8).reshape(3, 4, 3)
    depth = np.linspace(0.5, 40.0, 12, dtype=np.float16)
    frame = b"header" + bgr.tobytes() + b"trailer"
    cases = {
        "BGR bytes": sim_image("BGR", bgr.tobytes(), 4, 3),
        "BGR view of a frame": sim_image("BGR", memoryview(frame)[6 : 6 + bgr.size], 4, 3),
        "PNG": sim_image("PNG", cv2.imencode(".png", bgr)[1].tobytes(), 4, 3),
        "16FC1": sim_image("16FC1", depth.tobytes(), 4, 3),
        "32FC1 data_float": sim_image("32FC1", b"", 4, 3, data_float=depth.astype(np.float32).tolist()),
        "GRAY8": sim_image("GRAY8", bytes(range(12)), 4, 3),
    }
    for name, sim in cases.items():
        msg = image(sim, CTX)
        plain = as_genpy(msg)
        assert type(plain) is Image and type(plain.data) is bytes
        assert wire(msg) == wire(plain), name
        assert Image().deserialize(wire(msg)).data == bytes(msg.data), name


def test_pixels_in_a_received_frame_are_published_without_a_copy():
    frame = b"\x00" * 10 + bytes(range(48)) + b"\x00" * 10
    view = memoryview(frame)[10:58]
    msg = image(sim_image("BGR", view, 4, 4), CTX)
    assert msg.data.obj is frame  # still the frame's own memory
    assert wire(msg).endswith(len(view).to_bytes(4, "little") + bytes(range(48)))


def test_the_real_servers_empty_images_are_rejected_naming_what_is_missing():
    # depth with "compress": true, and "compress" with "pixels-as-float": the real server sends no pixels
    with pytest.raises(ConversionError, match=r"image: data has 0 bytes, expected 153600 for 320x240 16FC1"):
        image(sim_image("16FC1", b"", 320, 240), CTX)
    with pytest.raises(ConversionError, match=r"image: PNG data is empty"):
        image(sim_image("PNG", [], 320, 240), CTX)


def test_an_image_whose_pixels_would_take_over_max_bytes_is_oversized_before_decoding(monkeypatch):
    monkeypatch.setattr(cv2, "imdecode", lambda *_: pytest.fail("decoded"))
    assert MAX_PIXELS > 7000 * 7000  # under the pixel cap, but 147 MB once decoded
    over = r"7000x7000 bgr8 takes 147000000 bytes, over the limit of 100000000"
    with pytest.raises(OversizedData, match=over):
        image(sim_image("PNG", png_claiming(7000, 7000), 7000, 7000), CTX)
    ctx = ConvertContext(params={"max_bytes": 47})
    with pytest.raises(OversizedData, match=r"4x3 32FC1 takes 48 bytes, over the limit of 47 \(max_bytes\)"):
        image(sim_image("16FC1", bytes(24), 4, 3), ctx)
    assert image(sim_image("16FC1", bytes(24), 4, 3), ConvertContext(params={"max_bytes": 48})).width == 4
