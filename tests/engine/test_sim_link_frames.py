"""The link's own receive loop: frames over the size limit and frames of an unknown type are dropped and
counted, and the frames after them are delivered."""

from __future__ import annotations

import threading

import msgpack
import pynng

from airsim_mapper.engine.sim_link import FrameCounts, SimLink
from airsim_mapper.simserver.wire.protocol import encode_frame

TOPIC = "/Sim/S/robots/D/actual_pose"


class Socket:
    """A topics socket that hands out `frames`, then reports itself closed."""

    def __init__(self, frames: list[bytes]) -> None:
        self.frames = list(frames)
        self.recv_timeout = 0

    def recv(self) -> bytes:
        if self.frames:
            return self.frames.pop(0)
        raise pynng.exceptions.Closed(-1, "closed")

    def add_post_pipe_remove_cb(self, _cb) -> None:
        pass

    def remove_post_pipe_remove_cb(self, _cb) -> None:
        pass


class Client:
    def __init__(self, frames: list[bytes], callback) -> None:
        self.socket_topics = Socket(frames)
        self.socket_services = None
        self.recv_topic_thread = None
        self.state = True
        self.subs = {TOPIC: {"callbacks": [callback]}}
        self.topics: dict = {}


def receive(frames: list[bytes], counts: FrameCounts) -> list:
    got: list = []
    client = Client(frames, lambda _info, message: got.append(message))
    link = SimLink(client, counts)
    thread: threading.Thread = client.recv_topic_thread
    thread.join(timeout=5)
    link.stop_loop()
    return got


def frame(message: object, frame_type: int = 2) -> bytes:
    return encode_frame(TOPIC, msgpack.packb(message, use_bin_type=True), frame_type)


def test_a_frame_over_the_limit_is_dropped_before_unpacking_and_counted(caplog):
    counts = FrameCounts(max_frame_bytes=1000)
    big = frame({"data": bytes(2000)})
    got = receive([frame({"n": 1}), big, frame({"n": 2})], counts)
    assert got == [{"n": 1}, {"n": 2}]
    assert (counts.oversized, counts.bad) == (1, 0)
    assert any(
        "frame dropped: over the 0.000953674 MB limit (--max-frame-mb)" in r.getMessage()
        for r in caplog.records
    )


def test_a_frame_of_an_unknown_type_is_dropped_and_counted_as_bad(caplog):
    counts = FrameCounts()
    got = receive([frame({"n": 1}, frame_type=7), frame({"n": 2}, frame_type=0), frame({"n": 3})], counts)
    assert got == [{"n": 3}]
    assert (counts.bad, counts.oversized) == (2, 0)
    assert "frame of unknown type 7 dropped (only MESSAGE is expected)" in caplog.text


def test_the_counts_outlive_a_link():
    counts = FrameCounts(max_frame_bytes=10)
    receive([frame({"n": 1})], counts)
    receive([frame({"n": 1})], counts)
    assert counts.oversized == 2


def test_a_failing_callback_is_no_bad_frame_and_is_logged_with_its_traceback(caplog):
    counts = FrameCounts()

    def failing(_info, _message):
        raise KeyError("the callback's own bug")

    client = Client([frame({"n": 1}), frame({"n": 2})], failing)
    link = SimLink(client, counts)
    client.recv_topic_thread.join(timeout=5)
    link.stop_loop()
    assert (counts.callback_errors, counts.bad) == (2, 0)
    logged = [r for r in caplog.records if "a callback failed" in r.getMessage()]
    assert len(logged) == 1 and logged[0].exc_info[0] is KeyError  # the second held back (rate limit)


def test_the_links_connection_state_is_one_object_with_its_own_lock():
    from airsim_mapper.engine.sim_link import LinkState

    state = LinkState()
    assert state.connected() and not state.dead and not state.closing
    state.drop()
    assert not state.connected() and not state.dead
    state.kill()
    state.begin_close()
    assert state.dead and state.closing
    link = SimLink(Client([], lambda *_: None), FrameCounts())
    link.mark_dead()
    assert link.dead and link.connection.dead and not link.connected()
    link.stop_loop()
