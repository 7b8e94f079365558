"""The topics outbox: never blocks a publisher, small frames first, per-topic order, bounded when stuck."""

from __future__ import annotations

import threading
import time

import pytest

from airsim_mapper.simserver.wire import outbox as outbox_module
from airsim_mapper.simserver.wire.outbox import SMALL_FRAME_BYTES, Outbox

BIG = b"x" * SMALL_FRAME_BYTES


class GatedSink:
    """A send function that blocks until opened and records what it sent."""

    def __init__(self) -> None:
        self.sent: list[tuple[str, bytes]] = []
        self.gate = threading.Event()
        self.entered = threading.Event()
        self.lock = threading.Lock()

    def __call__(self, path: str, frame: bytes) -> None:
        self.entered.set()
        assert self.gate.wait(10)
        with self.lock:
            self.sent.append((path, frame))

    def wait_for(self, count: int) -> list[tuple[str, bytes]]:
        deadline = time.monotonic() + 10
        while time.monotonic() < deadline:
            with self.lock:
                if len(self.sent) >= count:
                    return list(self.sent)
            time.sleep(0.005)
        raise AssertionError(f"only {len(self.sent)} of {count} frames sent")


@pytest.fixture
def stuck():
    """An outbox whose first send is in progress and blocked, so later frames queue up."""
    sink = GatedSink()
    box = Outbox(sink)
    box.put("/first", b"0")
    assert sink.entered.wait(5)
    yield box, sink
    sink.gate.set()
    box.close()


def test_small_frames_go_in_order_and_before_large_ones(stuck) -> None:
    box, sink = stuck
    box.put("/cam", BIG)
    for i in range(5):
        box.put("/pose", str(i).encode())
    sink.gate.set()
    sent = sink.wait_for(7)
    assert [p for p, _ in sent] == ["/first"] + ["/pose"] * 5 + ["/cam"]
    assert [f for _, f in sent[1:6]] == [b"0", b"1", b"2", b"3", b"4"]
    assert box.dropped == 0


def test_large_lane_keeps_the_newest_frame_per_topic(stuck) -> None:
    box, sink = stuck
    box.put("/cam", b"a" + BIG)
    box.put("/lidar", b"l" + BIG)
    box.put("/cam", b"b" + BIG)
    assert box.pending() == 2
    sink.gate.set()
    sent = sink.wait_for(3)
    assert [(p, f[:1]) for p, f in sent[1:]] == [("/lidar", b"l"), ("/cam", b"b")]
    assert box.dropped == 1


def test_a_topic_never_overtakes_itself(stuck) -> None:
    box, sink = stuck
    box.put("/lidar", BIG)
    box.put("/lidar", b"small, newer")  # must not go out before the large frame it follows
    sink.gate.set()
    sent = sink.wait_for(2)
    time.sleep(0.05)
    assert sink.sent == sent == [("/first", b"0"), ("/lidar", b"small, newer")]
    assert box.dropped == 1


def test_a_client_that_stops_reading_costs_bounded_memory(stuck, monkeypatch) -> None:
    box, sink = stuck
    monkeypatch.setattr(outbox_module, "SMALL_LANE_LIMIT", 100)
    for i in range(1000):  # returns at once although nothing can be sent
        box.put("/pose", str(i).encode())
        box.put(f"/cam{i % 3}", BIG)
    assert box.pending() == 100 + 3
    assert box.dropped == 900 + 997
    sink.gate.set()
    sent = sink.wait_for(104)
    assert sent[1] == ("/pose", b"900")  # the oldest were dropped, the newest kept


def test_a_failing_send_does_not_stop_the_sender() -> None:
    sent: list[str] = []

    def send(path: str, _frame: bytes) -> None:
        if path == "/bad":
            raise OSError("socket closed")
        sent.append(path)

    box = Outbox(send)
    box.put("/bad", b"1")
    box.put("/good", b"2")
    deadline = time.monotonic() + 5
    while not sent and time.monotonic() < deadline:
        time.sleep(0.005)
    box.close()
    assert sent == ["/good"]


def test_close_discards_waiting_frames_and_ignores_later_ones(stuck) -> None:
    box, sink = stuck
    box.put("/pose", b"1")
    closer = threading.Thread(target=box.close)
    closer.start()
    sink.gate.set()
    closer.join(5)
    box.put("/pose", b"2")
    assert box.pending() == 0
    assert sink.sent == [("/first", b"0")]


def test_flush_waits_until_the_frame_being_sent_and_every_queued_one_are_out():
    """A lock-step step flushes before it replies: its image must not wait where the next one replaces it."""
    sink = GatedSink()
    box = Outbox(sink)
    try:
        box.put("/img", BIG)
        assert sink.entered.wait(5)  # the sender holds the first image
        box.put("/img", BIG + b"2")
        assert box.flush(0.2) is False  # still sending: a flush gives up at its timeout
        sink.gate.set()
        assert box.flush(5.0) is True
        assert [frame for _, frame in sink.sent] == [BIG, BIG + b"2"] and box.pending() == 0
    finally:
        sink.gate.set()
        box.close()
