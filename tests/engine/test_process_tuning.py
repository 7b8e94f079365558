"""Process tuning: rospy's queued connection without its per-publish yield, and the switch interval."""

from __future__ import annotations

import os
import socket
import struct
import subprocess
import sys
import threading
import time

import pytest
from harness import wait_until

from airsim_mapper.common.tuning import SWITCH_INTERVAL_S
from airsim_mapper.engine.rospy_internals import PromptQueuedConnection


class FakeTransport:
    """The part of a rospy transport that QueuedConnection uses."""

    def __init__(self, fail: bool = False) -> None:
        self.done = False
        self.fail = fail
        self.written: list[bytes] = []
        self.gate = threading.Event()
        self.gate.set()
        self.cond = threading.Condition()

    def set_cleanup_callback(self, _callback) -> None:
        pass

    def write_data(self, data: bytes) -> None:
        assert self.gate.wait(10)
        if self.fail:
            raise OSError("peer went away")
        with self.cond:
            self.written.append(data)
            self.cond.notify_all()

    def wait_for(self, count: int) -> list[bytes]:
        with self.cond:
            self.cond.wait_for(lambda: len(self.written) >= count, timeout=10)
            return list(self.written)


@pytest.fixture
def no_sleep(monkeypatch):
    """Fail if anything on the publishing path sleeps (rospy's original yields with time.sleep(0))."""
    import time as time_module

    real_sleep = time_module.sleep
    publisher = threading.current_thread()

    def guarded(seconds: float) -> None:
        assert threading.current_thread() is not publisher, "write_data slept on the publishing thread"
        real_sleep(seconds)

    monkeypatch.setattr(time_module, "sleep", guarded)


def test_writes_go_out_in_order_without_yielding(no_sleep) -> None:
    transport = FakeTransport()
    conn = PromptQueuedConnection(transport, 0)
    for i in range(50):
        assert conn.write_data(b"%d" % i) is True
    assert transport.wait_for(50) == [b"%d" % i for i in range(50)]
    transport.done = True
    conn._closed_connection_callback(transport)


def test_a_full_queue_drops_its_oldest_message() -> None:
    transport = FakeTransport()
    transport.gate.clear()
    conn = PromptQueuedConnection(transport, 2)
    conn.write_data(b"0")
    time.sleep(0.05)  # the writer thread takes b"0" and blocks on the gate
    for data in (b"1", b"2", b"3"):
        conn.write_data(data)
    transport.gate.set()
    assert transport.wait_for(3) == [b"0", b"2", b"3"]
    transport.done = True
    conn._closed_connection_callback(transport)


def test_a_writer_error_surfaces_on_the_next_publish() -> None:
    transport = FakeTransport(fail=True)
    conn = PromptQueuedConnection(transport, 1)
    conn.write_data(b"lost")
    deadline = time.monotonic() + 5
    while conn._error is None and time.monotonic() < deadline:
        time.sleep(0.005)
    with pytest.raises(OSError, match="peer went away"):
        conn.write_data(b"next")
    transport.done = True
    conn._closed_connection_callback(transport)


def test_a_batch_stops_at_its_first_error_and_keeps_no_traceback() -> None:
    """After a failed write the connection is gone: what was queued behind is not written, and the error
    kept for the next publish holds no frames (which would keep the sent messages' buffers alive)."""
    transport = FakeTransport()
    transport.gate.clear()
    written = transport.write_data

    def fail_on_one(data: bytes) -> None:
        if data == b"1":
            raise OSError("peer went away")
        written(data)

    transport.write_data = fail_on_one
    conn = PromptQueuedConnection(transport, 3)
    try:
        conn.write_data(b"0")
        time.sleep(0.05)  # the writer thread takes b"0" and blocks on the gate
        conn.write_data(b"1")
        conn.write_data(b"2")  # one batch with b"1"
        transport.gate.set()
        wait_until(lambda: conn._error is not None, 5, what="the writer's error")
        time.sleep(0.05)
        assert transport.written == [b"0"]
        assert conn._error is not None and conn._error.__traceback__ is None
    finally:
        transport.done = True
        conn._closed_connection_callback(transport)


class SocketTransport:
    """The part of a rospy TCPROS transport that the connection uses, over one end of a socket pair."""

    def __init__(self, sock: socket.socket) -> None:
        self.socket = sock
        self.done = False
        self.stat_bytes = 0
        self.stat_num_msg = 0
        self.writer_calls = 0  # sends made by the connection's writer thread

    def set_cleanup_callback(self, _callback) -> None:
        pass

    def write_data(self, data) -> None:
        self.writer_calls += 1
        self.socket.sendall(data)
        self.stat_bytes += len(data)
        self.stat_num_msg += 1


def framed(index: int, size: int) -> bytes:
    """A length-prefixed message (as TCPROS frames them) whose body repeats its index."""
    body = bytes([index % 251]) * size
    return struct.pack("<I", len(body)) + body


def read_frames(sock: socket.socket, count: int) -> list[bytes]:
    """Read `count` length-prefixed messages; a message cut short would garble every later length."""
    sock.settimeout(10)
    buffer, frames = b"", []
    while len(frames) < count:
        buffer += sock.recv(1 << 20)
        while len(buffer) >= 4 and len(buffer) >= 4 + struct.unpack("<I", buffer[:4])[0]:
            size = struct.unpack("<I", buffer[:4])[0]
            frames.append(buffer[4 : 4 + size])
            buffer = buffer[4 + size :]
    return frames


def drain(sock: socket.socket, quiet_s: float = 0.5) -> list[bytes]:
    """Every whole message that arrives until the socket has been quiet for `quiet_s`."""
    sock.settimeout(quiet_s)
    buffer = b""
    while True:
        try:
            chunk = sock.recv(1 << 20)
        except TimeoutError:
            break
        if not chunk:
            break
        buffer += chunk
    frames = []
    while buffer:
        size = struct.unpack("<I", buffer[:4])[0]
        assert len(buffer) >= 4 + size, "a message was cut short"
        frames.append(buffer[4 : 4 + size])
        buffer = buffer[4 + size :]
    return frames


@pytest.fixture
def pair():
    writer, reader = socket.socketpair()
    writer.setblocking(True)  # as rospy's write_header leaves a publisher's socket (rospy may set a default)
    writer.setsockopt(socket.SOL_SOCKET, socket.SO_SNDBUF, 16 * 1024)
    yield writer, reader
    writer.close()
    reader.close()


def close(conn: PromptQueuedConnection, transport) -> None:
    transport.done = True
    conn._closed_connection_callback(transport)
    conn._thread.join(5)


def test_a_message_the_socket_takes_goes_out_on_the_publishing_thread(pair, no_sleep) -> None:
    writer, reader = pair
    transport = SocketTransport(writer)
    conn = PromptQueuedConnection(transport, 10)
    messages = [framed(i, 200) for i in range(20)]
    for data in messages:
        conn.write_data(data)
        assert read_frames(reader, 1) == [data[4:]]
    assert transport.writer_calls == 0  # no thread was woken
    assert (transport.stat_num_msg, transport.stat_bytes) == (20, sum(map(len, messages)))
    close(conn, transport)


def test_a_stalled_subscriber_never_blocks_and_never_gets_a_cut_message(pair) -> None:
    writer, reader = pair
    transport = SocketTransport(writer)
    conn = PromptQueuedConnection(transport, 2)
    started = time.monotonic()
    for i in range(40):  # 40 x 64 KB against a 16 KB send buffer and nobody reading
        conn.write_data(framed(i, 64 * 1024))
    assert time.monotonic() - started < 2.0
    frames = drain(reader)
    indices = [f[0] for f in frames]
    # every message arrives whole: the first went out in part and was finished, the queue kept the newest
    assert all(len(f) == 64 * 1024 for f in frames)
    assert indices[0] == 0 and indices[-2:] == [38, 39] and indices == sorted(indices)
    assert len(frames) <= 6  # the writer's first grab plus the queue's two, not all forty
    close(conn, transport)


def test_after_a_backlog_clears_sends_are_direct_again(pair) -> None:
    writer, reader = pair
    transport = SocketTransport(writer)
    conn = PromptQueuedConnection(transport, 0)
    for i in range(5):
        conn.write_data(framed(i, 64 * 1024))
    assert [f[0] for f in read_frames(reader, 5)] == [0, 1, 2, 3, 4]
    wait_until(lambda: not conn._busy and not conn._queue, 5, what="the writer to go idle")
    calls = transport.writer_calls
    conn.write_data(framed(5, 100))
    assert read_frames(reader, 1) == [bytes([5]) * 100]
    assert transport.writer_calls == calls
    close(conn, transport)


def test_a_socket_with_a_timeout_is_left_to_the_writer_thread(pair) -> None:
    writer, reader = pair
    writer.settimeout(5.0)  # a send on it would wait for room first: never on the publishing thread
    transport = SocketTransport(writer)
    conn = PromptQueuedConnection(transport, 10)
    conn.write_data(framed(1, 100))
    assert read_frames(reader, 1) == [bytes([1]) * 100]
    assert transport.writer_calls == 1
    close(conn, transport)


def test_a_broken_socket_surfaces_on_the_next_publish(pair) -> None:
    writer, reader = pair
    transport = SocketTransport(writer)
    conn = PromptQueuedConnection(transport, 1)
    reader.close()
    conn.write_data(framed(0, 100))
    wait_until(lambda: conn._error is not None, 5, what="the writer's error")
    with pytest.raises(OSError):
        conn.write_data(framed(1, 100))
    close(conn, transport)


PROBE = (
    "import sys, rospy.topics;"
    "from airsim_mapper.common.tuning import blas_threads;"
    "from airsim_mapper.engine.process_tuning import tune_process;"
    "tune_process();"
    "print(sys.getswitchinterval(), rospy.topics.QueuedConnection.__name__, *blas_threads())"
)


@pytest.mark.live
def test_tune_process_installs_both_settings_and_can_be_turned_off() -> None:
    run = {"capture_output": True, "text": True, "check": True}
    out = subprocess.run([sys.executable, "-c", PROBE], **run).stdout.split()
    assert float(out[0]) == pytest.approx(SWITCH_INTERVAL_S) and out[1] == "PromptQueuedConnection"
    assert out[2:] == ["1"]  # numpy's OpenBLAS, limited to one thread
    env = {**os.environ, "AIRSIM_MAPPER_NO_TUNING": "1"}
    out = subprocess.run([sys.executable, "-c", PROBE], env=env, **run).stdout.split()
    assert float(out[0]) == pytest.approx(0.005) and out[1] == "QueuedConnection"
    assert len(out[2:]) == 1


def test_gc_pauses_reports_the_longest_collection_once() -> None:
    import gc

    from airsim_mapper.engine.process_tuning import GcPauses

    pauses = GcPauses()
    try:
        garbage = [[] for _ in range(200_000)]
        for item in garbage:
            item.append(item)  # cycles, so the collection has work to do
        del garbage
        gc.collect()
        assert pauses.collections >= 1
        assert pauses.take_peak_ms() > 0.0
        assert pauses.take_peak_ms() == 0.0
    finally:
        pauses.close()
    assert pauses._on_gc not in gc.callbacks


FREEZE_PROBE = """
import gc, time, weakref
from airsim_mapper.engine.process_tuning import freeze_heap, thaw_heap
class Node: pass
kept = [[] for _ in range(200_000)]
cycle = Node(); cycle.me = cycle; alive = weakref.ref(cycle)
started = time.perf_counter(); gc.collect(); before = time.perf_counter() - started
freeze_heap()
frozen = gc.get_freeze_count()
started = time.perf_counter(); gc.collect(); after = time.perf_counter() - started
del cycle
gc.collect()
leaked_while_frozen = alive() is not None
thaw_heap()
gc.collect()
print(frozen, gc.get_freeze_count(), after < before / 5, leaked_while_frozen, alive() is None)
"""


@pytest.mark.live
def test_a_frozen_heap_is_skipped_by_full_collections_and_thawing_frees_old_cycles() -> None:
    run = {"capture_output": True, "text": True, "check": True}
    frozen, thawed, faster, held, freed = subprocess.run(
        [sys.executable, "-c", FREEZE_PROBE], **run
    ).stdout.split()
    assert int(frozen) > 200_000 and int(thawed) == 0
    assert faster == "True"  # the 200,000 frozen lists are no longer walked
    assert held == "True" and freed == "True"  # a frozen cycle waits for the thaw, then is collected


ENGINE_PROBE = """
import sys, types, rospy.topics
from airsim_mapper.common.tuning import blas_threads
from airsim_mapper.engine import Engine, NodeNames, SimAccess
from airsim_mapper.mapping.loader import load_mapping
from airsim_mapper.common.resources import DEFAULT_MAPPING
client = types.SimpleNamespace(socket_topics=None, socket_services=None, subs={}, topics={}, state=True)
before = blas_threads()
names, sim = NodeNames("probe"), SimAccess("sim_config")
engine = Engine(client, load_mapping(DEFAULT_MAPPING), names, sim, tune=sys.argv[1] == "tune")
blas = "kept" if blas_threads() == before else ",".join(map(str, blas_threads()))
print(sys.getswitchinterval(), rospy.topics.QueuedConnection.__name__, blas, engine._freeze_heap)
"""


@pytest.mark.live
def test_only_an_engine_asked_to_tune_changes_the_process() -> None:
    """A mission script's wrapper leaves the interpreter, rospy and BLAS alone; the node's tunes them."""
    run = {"capture_output": True, "text": True, "check": True, "timeout": 60}
    env = {k: v for k, v in os.environ.items() if k != "AIRSIM_MAPPER_NO_TUNING"}
    plain = subprocess.run([sys.executable, "-c", ENGINE_PROBE, "plain"], env=env, **run).stdout.split()
    assert float(plain[0]) == pytest.approx(0.005) and plain[1] == "QueuedConnection"
    assert plain[2:] == ["kept", "False"]
    tuned = subprocess.run([sys.executable, "-c", ENGINE_PROBE, "tune"], env=env, **run).stdout.split()
    assert float(tuned[0]) == pytest.approx(SWITCH_INTERVAL_S) and tuned[1] == "PromptQueuedConnection"
    assert tuned[2] in ("kept", "1") and tuned[3] == "True"  # "kept" on a one-core host


@pytest.mark.live
def test_keep_frame_buffers_fixes_glibcs_thresholds_unless_tuning_is_off() -> None:
    probe = "from airsim_mapper.common.tuning import keep_frame_buffers; print(keep_frame_buffers())"
    run = {"capture_output": True, "text": True, "check": True}
    assert subprocess.run([sys.executable, "-c", probe], **run).stdout.split() == ["True"]
    env = {**os.environ, "AIRSIM_MAPPER_NO_TUNING": "1"}
    assert subprocess.run([sys.executable, "-c", probe], env=env, **run).stdout.split() == ["False"]
