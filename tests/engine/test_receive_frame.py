"""The receive loop reads each frame as a view of NNG's message: same bytes, kept alive by its views."""

from __future__ import annotations

import gc

import msgpack
import pynng

from airsim_mapper.engine.fast_frames import parse_frame_header
from airsim_mapper.engine.receive import decode_body, receive_frame
from airsim_mapper.simserver.protocol import encode_frame


def test_a_received_frame_is_a_view_whose_slices_outlive_it(tmp_path):
    address = f"ipc://{tmp_path}/frames"
    pixels = bytes(range(256)) * 4096
    frame = encode_frame("/cam", msgpack.packb({"time_stamp": 1, "data": pixels}, use_bin_type=True))
    with pynng.Pair0(listen=address) as server, pynng.Pair0(dial=address, recv_timeout=5000) as client:
        server.send(frame)
        server.send(b"second")
        view = receive_frame(client)
        assert isinstance(view, memoryview) and bytes(view) == frame
        header = parse_frame_header(view)
        message, fast = decode_body(view[header.body_start : header.body_end], fast=True)
        del view, header
        gc.collect()
        # the pixels are still a view of the frame, whose NNG message lives as long as they do
        assert fast and isinstance(message["data"], memoryview) and bytes(message["data"]) == pixels
        assert bytes(receive_frame(client)) == b"second"
