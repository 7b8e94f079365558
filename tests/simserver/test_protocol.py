"""The wire encoding matches the bytes verified against the real 1.1.0 client (protocol.md §2.2, §3)."""

from __future__ import annotations

import msgpack
import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from airsim_mapper.simserver.wire import protocol


def test_server_message_frame_packs_topic_and_body_as_msgpack_str_like_the_cpp_server():
    body = msgpack.packb({"time_stamp": 5}, use_bin_type=True)
    frame = protocol.encode_frame("/a", body)
    assert frame == bytes.fromhex("9302a22f61ad") + body
    assert frame[:6] == bytes.fromhex("93 02 a2 2f 61 ad")


def test_client_subscribe_frame_bytes_decode_to_a_subscribe_on_the_topics_path():
    frame = protocol.decode_frame(bytes.fromhex("93 00 a8 2f 24 74 6f 70 69 63 73 a0"))
    assert frame == protocol.Frame(protocol.FrameType.SUBSCRIBE, "/$topics", b"")


def test_client_unsubscribe_frame_bytes_decode_to_an_unsubscribe():
    assert protocol.decode_frame(bytes.fromhex("93 01 a2 2f 61 a0")) == protocol.Frame(1, "/a", b"")


def test_client_publish_frame_carries_the_inner_message_as_bin():
    raw = bytes.fromhex("93 02 a2 2f 61 c4 0d 81 aa 74 69 6d 65 5f 73 74 61 6d 70 05")
    frame = protocol.decode_frame(raw)
    assert frame.type == protocol.FrameType.MESSAGE and frame.topic == "/a"
    assert protocol.decode_body(frame.body) == {"time_stamp": 5}


@pytest.mark.parametrize(
    ("raw", "message"),
    [
        (b"\xc1", "frame is not msgpack"),
        (msgpack.packb([0, "/a"]), "frame must be an array of 3"),
        (msgpack.packb({"a": 1}), "frame must be an array of 3, got dict"),
        (msgpack.packb(["x", "/a", b""]), r"frame must be \[int, str, bytes\]"),
        (msgpack.packb([0, b"\xff", b""], use_bin_type=True), "frame topic is not UTF-8"),
    ],
)
def test_malformed_frames_are_rejected_with_a_reason(raw, message):
    with pytest.raises(protocol.BadFrameError, match=message):
        protocol.decode_frame(raw)


def test_verified_load_scene_request_bytes_decode_to_method_params_and_id():
    inner = bytes.fromhex("81 ac") + b"scene_config" + bytes.fromhex("a2") + b"{}"
    raw = (
        bytes.fromhex("84 a6")
        + b"method"
        + bytes.fromhex("c4 0e")
        + b"/Sim/LoadScene"
        + bytes.fromhex("a6")
        + b"params"
        + bytes.fromhex("81 a4")
        + b"data"
        + bytes.fromhex("c4 11")
        + inner
        + bytes.fromhex("a7")
        + b"version"
        + bytes.fromhex("cb 3ff0000000000000 a2")
        + b"id"
        + bytes.fromhex("01")
    )
    assert protocol.decode_request(raw) == protocol.Request(1, "/Sim/LoadScene", {"scene_config": "{}"})


def test_request_with_a_str_method_and_plain_params_is_accepted():
    raw = msgpack.packb({"method": "/Sim/X", "params": {"a": 1}, "id": 7})
    assert protocol.decode_request(raw) == protocol.Request(7, "/Sim/X", {"a": 1})


@pytest.mark.parametrize(
    ("raw", "message"),
    [
        (b"\x00garbage\xc1", "request is not msgpack"),
        (msgpack.packb([1, 2]), "request must be a map, got list"),
        (msgpack.packb({"params": {}}), "request has no method"),
        (msgpack.packb({"method": b"\xff"}, use_bin_type=True), "request method is not UTF-8"),
        (
            msgpack.packb({"method": "/m", "params": {"data": b"\xc1"}}, use_bin_type=True),
            "params are not msgpack",
        ),
        (msgpack.packb({"method": "/m", "params": [1]}), "request params must be a map, got list"),
    ],
)
def test_malformed_requests_are_rejected_with_a_reason(raw, message):
    with pytest.raises(protocol.BadRequestError, match=message):
        protocol.decode_request(raw)


def test_success_reply_double_encodes_the_result_with_a_float32_version():
    raw = protocol.encode_result(3, "SceneBasicDrone")
    outer = msgpack.unpackb(raw, raw=False)
    assert outer["id"] == 3 and outer["version"] == 1.0
    assert msgpack.unpackb(outer["result"]["data"], raw=False) == "SceneBasicDrone"
    assert b"\xa7version\xca\x3f\x80\x00\x00" in raw


def test_error_reply_carries_code_and_message_in_the_inner_map():
    outer = msgpack.unpackb(protocol.encode_error(4, 1, "nope"), raw=False)
    assert outer["id"] == 4
    assert msgpack.unpackb(outer["error"]["data"], raw=False) == {"code": 1.0, "message": "nope"}


def test_float32_array_packs_each_element_as_msgpack_float32():
    values = np.array([1.5, -2.0, 3.25], dtype=np.float64)
    raw = protocol.float32_array(values).data
    assert raw == bytes.fromhex("93 ca 3fc00000 ca c0000000 ca 40500000")
    big = np.linspace(-1, 1, 70000, dtype=np.float32)
    assert msgpack.unpackb(protocol.float32_array(big).data) == pytest.approx(big.tolist())


def test_int32_array_round_trips_through_msgpack():
    values = np.array([-5, 0, 7, 2**31 - 1], dtype=np.int64)
    assert msgpack.unpackb(protocol.int32_array(values).data) == values.tolist()


def test_uint8_list_is_the_json_form_of_image_bytes():
    data = bytes(range(256)) * 3
    raw = protocol.uint8_list(data).data
    assert msgpack.unpackb(raw) == list(data)
    assert raw == msgpack.packb(list(data))


def test_pack_splices_numpy_arrays_and_raw_chunks_into_an_ordinary_message():
    message = {
        "time_stamp": np.int64(9),
        "point_cloud": np.array([1.0, 2.0, 3.0], dtype=np.float32),
        "laser_index_cloud": np.array([0, 1], dtype=np.int32),
        "data": b"\x01\x02",
        "nested": [{"k": protocol.Raw(msgpack.packb("x"))}],
        "wide": {f"k{i}": i for i in range(20)},
    }
    decoded = msgpack.unpackb(protocol.pack(message), raw=False)
    assert decoded["time_stamp"] == 9
    assert decoded["point_cloud"] == [1.0, 2.0, 3.0]
    assert decoded["laser_index_cloud"] == [0, 1]
    assert decoded["data"] == b"\x01\x02"
    assert decoded["nested"] == [{"k": "x"}]
    assert decoded["wide"] == {f"k{i}": i for i in range(20)}


def test_pack_refuses_numpy_arrays_it_cannot_represent():
    with pytest.raises(TypeError, match="cannot pack a numpy array of dtype <U1"):
        protocol.pack(np.array(["a"]))


def test_parameters_are_dumped_like_nlohmann_json_in_error_messages():
    assert protocol.dump_params({"b": 1, "a": [1, 2]}) == '{"a":[1,2],"b":1}'


@pytest.mark.parametrize("size", [0, 31, 32, 255, 256, 4095, 4096, 65535, 65536, 70000])
def test_a_message_frame_is_the_frame_of_the_packed_message_byte_for_byte(size):
    data = bytes(range(256)) * (size // 256) + bytes(size % 256)
    message = {"time_stamp": 7, "encoding": "BGR", "data": data, "pose": np.arange(3.0)}
    frame = protocol.message_frame("/Sim/S/robots/R/sensors/C/scene_camera", message)
    body = protocol.pack(message)
    assert frame.frame == protocol.encode_frame("/Sim/S/robots/R/sensors/C/scene_camera", body)
    assert frame.body == body
    assert protocol.decode_body(body)["data"] == data
    assert body == protocol.pack({**message, "pose": protocol.float32_array(np.arange(3.0))})
    packed = protocol.message_frame("/t", body)  # an already packed body
    assert packed.frame == protocol.encode_frame("/t", body)


plain_values = st.recursive(
    st.none()
    | st.booleans()
    | st.integers(-(2**63), 2**64 - 1)
    | st.floats(allow_nan=False)
    | st.text(max_size=40)
    | st.binary(max_size=300)
    | st.floats(allow_nan=False).map(np.float64)
    | st.floats(allow_nan=False, width=32).map(np.float32)
    | st.integers(-(2**31), 2**31 - 1).map(np.int64)
    | st.booleans().map(np.bool_),
    lambda inner: st.lists(inner, max_size=20) | st.dictionaries(st.text(max_size=12), inner, max_size=20),
    max_leaves=40,
)


@given(plain_values)
def test_msgpacks_own_packer_gives_the_bytes_of_pack_for_a_message_of_plain_values(message):
    assert protocol.pack_plain(message) == protocol.pack(message)


def test_the_plain_packer_refuses_numpy_arrays_and_raw_chunks_rather_than_pack_them_differently():
    with pytest.raises(TypeError, match="pack_plain cannot pack ndarray: use pack"):
        protocol.pack_plain({"pose": np.arange(3.0)})
    with pytest.raises(TypeError, match="pack_plain cannot pack Raw: use pack"):
        protocol.pack_plain({"nested": [protocol.Raw(b"\xc0")]})
