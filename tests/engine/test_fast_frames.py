"""Fast decoding of topic frames: large msgpack arrays become numpy, everything else is the client's."""

from __future__ import annotations

from typing import Any

import msgpack
import numpy as np
from framekit import LIDAR_TOPIC, client_decode, image_frame, lidar_frame

from airsim_mapper.engine.fast_frames import decode_map, parse_frame_header


def decoded(frame: bytes, views: bool = False) -> tuple[str, Any]:
    """A frame's topic and its body through `decode_map`, as the node's receive loop decodes it."""
    header = parse_frame_header(frame)
    return header.topic, decode_map(frame, header.body_start, header.body_end, views=views)


def test_a_lidar_frame_decodes_to_numpy_arrays_equal_to_the_clients_lists():
    frame = lidar_frame()
    expected_topic, expected = client_decode(frame)
    topic, message = decoded(frame)
    assert topic == expected_topic == LIDAR_TOPIC
    assert list(message) == list(expected)
    for key in ("point_cloud", "intensity_cloud"):
        assert message[key].dtype == np.float32
        np.testing.assert_array_equal(message[key], np.asarray(expected[key], dtype=np.float32))
    for key in ("segmentation_cloud", "laser_index_cloud"):
        assert message[key].dtype == np.int32
        np.testing.assert_array_equal(message[key], np.asarray(expected[key]))
    assert message["azimuth_elevation_range_cloud"] == expected["azimuth_elevation_range_cloud"] == []
    assert message["time_stamp"] == expected["time_stamp"]
    assert message["pose"] == expected["pose"]


def test_an_image_frame_keeps_its_pixels_as_bytes_and_every_other_field_as_the_client_has_it():
    frame = image_frame()
    _, expected = client_decode(frame)
    _, message = decoded(frame)
    assert type(message["data"]) is bytes
    assert message == expected


def test_with_views_large_bin_values_are_memoryviews_of_the_frame_with_the_same_bytes():
    frame = image_frame()
    _, expected = client_decode(frame)
    _, message = decoded(frame, views=True)
    assert isinstance(message["data"], memoryview)
    assert message["data"].obj is frame
    assert bytes(message["data"]) == expected["data"]


def test_float64_and_small_int_arrays_decode_with_their_own_widths():
    values = {
        "doubles": np.linspace(-1.0, 1.0, 300),  # msgpack packs Python floats as float64 (0xcb)
        "small": np.arange(300) % 100,  # all positive fixints
        "bytes_u8": np.full(300, 200),  # all uint8 (0xcc)
        "shorts": np.full(300, -1000),  # all int16 (0xd1)
    }
    body = msgpack.packb({k: v.tolist() for k, v in values.items()}, use_bin_type=True)
    message = decode_map(body)
    assert message["doubles"].dtype == np.float64
    np.testing.assert_array_equal(message["doubles"], values["doubles"])
    for key in ("small", "bytes_u8", "shorts"):
        np.testing.assert_array_equal(message[key], values[key])


def test_an_array_of_mixed_element_types_falls_back_to_msgpack_and_still_decodes_exactly():
    mixed = [i % 300 for i in range(1000)]  # fixints and 0xcd uint16: msgpack-c's shortest encoding
    floats = [0.5] * 99 + ["x"]  # one element with another type byte
    body = msgpack.packb({"mixed": mixed, "floats": floats, "tail": 7}, use_bin_type=True)
    assert decode_map(body) == {"mixed": mixed, "floats": floats, "tail": 7}


def test_a_body_that_is_not_a_map_is_not_decoded():
    assert decode_map(b"") is None
    assert decode_map(msgpack.packb([1, 2])) is None
    assert decode_map(msgpack.packb(list(range(100)), use_bin_type=True)) is None


def test_the_frame_header_is_read_from_str_or_bin_topic_and_body_forms():
    body = b"\x81\xa1a\x01"
    for use_bin in (False, True):
        frame = msgpack.packb([2, "/topic", body], use_bin_type=use_bin)
        header = parse_frame_header(frame)
        assert header is not None
        assert (header.frame_type, header.topic) == (2, "/topic")
        assert frame[header.body_start : header.body_end] == body
    assert parse_frame_header(b"\x92\x02\xa1a") is None
    assert parse_frame_header(msgpack.packb([2, 5, b"x"])) is None
    assert parse_frame_header(msgpack.packb([2, "/t", b"x"]) + b"junk") is None


def test_a_received_view_decodes_exactly_as_the_same_bytes_without_copying_the_pixels():
    for frame in (lidar_frame(), image_frame(width=320, height=240)):
        view = memoryview(frame)  # as the receive loop holds a frame: a view of the transport's message
        header = parse_frame_header(view)
        assert header == parse_frame_header(frame)
        from_view = decode_map(view, header.body_start, header.body_end, views=True)
        from_bytes = decode_map(frame, header.body_start, header.body_end, views=True)
        assert list(from_view) == list(from_bytes)
        for key, value in from_bytes.items():
            if isinstance(value, np.ndarray):
                np.testing.assert_array_equal(from_view[key], value)
            elif isinstance(value, memoryview):
                assert from_view[key].obj is frame and bytes(from_view[key]) == bytes(value)
            else:
                assert from_view[key] == value


def test_a_view_with_one_odd_element_falls_back_as_bytes_do():
    floats = [0.5] * 99 + ["x"]
    body = msgpack.packb({"floats": floats, "big": list(range(70000)), "tail": 7}, use_bin_type=True)
    assert decode_map(memoryview(body))["floats"] == floats
    assert decode_map(memoryview(body))["tail"] == 7  # after a value longer than one read
