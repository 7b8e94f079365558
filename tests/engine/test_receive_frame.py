"""The receive loop reads each frame as a view of NNG's message: same bytes, kept alive by its views."""

from __future__ import annotations

import gc
import threading
import types

import msgpack
import pynng

from airsim_mapper.engine.fast_frames import parse_frame_header
from airsim_mapper.engine.receive import READ_AHEAD_FRAMES, decode_body, read_ahead, receive_frame
from airsim_mapper.engine.sim_link import SimLink
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


def test_nng_reads_frames_ahead_of_the_links_receive_loop_in_order(tmp_path):
    """The link lets NNG read a few frames ahead of its loop (a burst of poses is not taken one round trip
    through NNG's threads at a time); every frame still arrives, in order."""
    address, count = f"ipc://{tmp_path}/ahead", 3 * READ_AHEAD_FRAMES
    got: list = []
    every = threading.Event()

    def on_message(_info, message) -> None:
        got.append(message["n"])
        if len(got) == count:
            every.set()

    with pynng.Pair0(listen=address, send_timeout=5000) as server, pynng.Pair0(dial=address) as sock:
        client = types.SimpleNamespace(
            socket_topics=sock, socket_services=None, recv_topic_thread=None, state=True, topics={}
        )
        client.subs = {"/ahead": {"callbacks": [on_message]}}
        link = SimLink(client)
        try:
            for number in range(count):
                server.send(encode_frame("/ahead", msgpack.packb({"n": number})))
            assert every.wait(10) and got == list(range(count))
            assert sock.recv_buffer_size == READ_AHEAD_FRAMES  # set by the loop as it started
        finally:
            client.state = False
            client.recv_topic_thread.join(timeout=2)
            link.stop_loop()
    read_ahead(types.SimpleNamespace())  # not a pynng socket: nothing to set, no error
