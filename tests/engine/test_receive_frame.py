"""The receive loop reads each frame as a view of NNG's message: same bytes, kept alive by its views; it
waits for frames in the kernel, sees a stopped client within its wait, and stops at once when its client is
closed."""

from __future__ import annotations

import gc
import threading
import time
import types

import msgpack
import pynng
import pytest

from airsim_mapper.engine import receive
from airsim_mapper.engine.fast_frames import parse_frame_header
from airsim_mapper.engine.receive import (
    READ_AHEAD_FRAMES,
    FrameWait,
    close_client,
    read_ahead,
    receive_frame,
    unpack_message,
)
from airsim_mapper.engine.sim_link import SimLink
from airsim_mapper.simserver.wire.protocol import encode_frame


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
        message, fast = unpack_message(view[header.body_start : header.body_end], fast=True)
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


def idle_client(sock: pynng.Socket) -> tuple[types.SimpleNamespace, SimLink]:
    client = types.SimpleNamespace(
        socket_topics=sock, socket_services=None, recv_topic_thread=None, state=True, topics={}, subs={}
    )
    return client, SimLink(client)


def test_the_wait_for_a_frame_ends_empty_after_its_time_and_at_once_with_a_frame(tmp_path, monkeypatch):
    monkeypatch.setattr(receive, "WAIT_MS", 20)
    address = f"ipc://{tmp_path}/wait"
    with pynng.Pair0(listen=address, send_timeout=5000) as server, pynng.Pair0(dial=address) as sock:
        wait = FrameWait(sock)
        start = time.monotonic()
        assert wait() is None and time.monotonic() - start >= 0.015
        server.send(b"frame")
        deadline = time.monotonic() + 5
        while (frame := wait()) is None and time.monotonic() < deadline:
            pass
        assert bytes(frame) == b"frame"
        assert sock.recv_timeout == -1  # NNG's own timer is not used: the socket's option is left alone
    with pytest.raises(pynng.exceptions.TryAgain), pynng.Pair0(listen=f"ipc://{tmp_path}/empty") as sock:
        receive_frame(sock, block=False)


def test_an_idle_loop_takes_the_next_frame(tmp_path):
    address, got = f"ipc://{tmp_path}/idle", threading.Event()
    with pynng.Pair0(listen=address, send_timeout=5000) as server, pynng.Pair0(dial=address) as sock:
        client, link = idle_client(sock)
        client.subs["/idle"] = {"callbacks": [lambda _info, _message: got.set()]}
        try:
            time.sleep(0.3)  # waits without a frame
            server.send(encode_frame("/idle", msgpack.packb({"n": 1})))
            assert got.wait(5)
            assert sock.recv_timeout == -1  # the loop waited in poll(), not on NNG's receive timer
        finally:
            client.state = False
            link.stop_loop()


def test_close_client_ends_a_waiting_loop_at_once_and_a_stopped_client_within_its_wait(tmp_path, monkeypatch):
    for close in (True, False):
        with pynng.Pair0(listen=f"ipc://{tmp_path}/close{close}") as _server:
            sock = pynng.Pair0(dial=f"ipc://{tmp_path}/close{close}")
            # closing: a wait far longer than the test, which only the closed socket can end
            monkeypatch.setattr(receive, "WAIT_MS", 60_000 if close else 100)
            client, link = idle_client(sock)
            time.sleep(0.3)  # idle: the loop is waiting for a frame
            start = time.monotonic()
            if close:  # the node's shutdown, and a lost simulator
                close_client(client)
                assert not client.recv_topic_thread.is_alive()
                assert time.monotonic() - start < 5  # not the wait's 60 s
            else:  # the client's own disconnect(): stop, then join, as a mission script does
                client.state = False
                client.recv_topic_thread.join(5)
                assert not client.recv_topic_thread.is_alive()
                assert time.monotonic() - start < 0.9  # one wait (100 ms), with room for a busy host
                sock.close()
            link.stop_loop()
