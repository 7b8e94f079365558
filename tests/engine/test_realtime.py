"""Process tuning: rospy's queued connection without its per-publish yield, and the switch interval."""

from __future__ import annotations

import os
import subprocess
import sys
import threading
import time

import pytest

from airsim_mapper.engine.realtime import PromptQueuedConnection
from airsim_mapper.tuning import SWITCH_INTERVAL_S


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


PROBE = (
    "import sys, rospy.topics;"
    "from airsim_mapper.tuning import blas_threads;"
    "from airsim_mapper.engine.realtime import tune_process;"
    "tune_process();"
    "print(sys.getswitchinterval(), rospy.topics.QueuedConnection.__name__, *blas_threads())"
)


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

    from airsim_mapper.engine.realtime import GcPauses

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
from airsim_mapper.engine.realtime import freeze_heap, thaw_heap
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


def test_a_frozen_heap_is_skipped_by_full_collections_and_thawing_frees_old_cycles() -> None:
    run = {"capture_output": True, "text": True, "check": True}
    frozen, thawed, faster, held, freed = subprocess.run(
        [sys.executable, "-c", FREEZE_PROBE], **run
    ).stdout.split()
    assert int(frozen) > 200_000 and int(thawed) == 0
    assert faster == "True"  # the 200,000 frozen lists are no longer walked
    assert held == "True" and freed == "True"  # a frozen cycle waits for the thaw, then is collected
