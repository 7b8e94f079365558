"""Stream peaks: where a stall came from (arrival gap, wait for the worker, handling), per status window."""

from __future__ import annotations

import threading
import time
import weakref

from airsim_mapper.engine.streams import Stream


class Message:
    """A message that can be watched with a weak reference."""


def wait_until(predicate, timeout: float = 5.0) -> None:
    deadline = time.monotonic() + timeout
    while not predicate() and time.monotonic() < deadline:
        time.sleep(0.002)
    assert predicate()


def test_peaks_show_the_arrival_gap_and_the_handling_time_then_reset() -> None:
    def slow(_message) -> None:
        time.sleep(0.05)

    stream = Stream("/t", None, [slow])
    try:
        stream.offer(None, 1)
        wait_until(lambda: stream.stats.handled == 1)
        time.sleep(0.12)
        stream.offer(None, 2)
        wait_until(lambda: stream.stats.handled == 2)
        peaks = stream.stats.take_peaks()
        assert peaks["arrival_gap_max_ms"] >= 120
        assert peaks["handle_max_ms"] >= 50
        assert peaks["wait_max_ms"] < peaks["arrival_gap_max_ms"]
        assert set(stream.stats.take_peaks().values()) == {0.0}
    finally:
        stream.stop()


def test_a_message_that_waits_behind_a_busy_worker_shows_as_wait() -> None:
    release = threading.Event()

    def blocking(message) -> None:
        if message == 1:
            assert release.wait(5)

    stream = Stream("/t", None, [blocking])
    try:
        stream.offer(None, 1)
        time.sleep(0.02)
        stream.offer(None, 2)  # waits in the slot while message 1 blocks the worker
        time.sleep(0.1)
        release.set()
        wait_until(lambda: stream.stats.handled == 2)
        peaks = stream.stats.take_peaks()
        assert peaks["wait_max_ms"] >= 100
        assert peaks["handle_max_ms"] >= 100
    finally:
        stream.stop()


def test_a_message_waiting_when_its_stream_stops_is_dropped_not_kept() -> None:
    busy, release = threading.Event(), threading.Event()

    def blocking(message) -> None:
        if message == 1:
            busy.set()
            assert release.wait(5)

    stream = Stream("/t", None, [blocking])
    stream.offer(None, 1)
    assert busy.wait(5)
    waiting = Message()
    gone = weakref.ref(waiting)
    stream.offer(None, waiting)  # waits in the slot behind message 1
    del waiting
    threading.Timer(0.1, release.set).start()  # the worker finishes 1 while stop() waits for it
    stream.stop()
    assert stream.stats.handled == 1
    assert gone() is None


def stream_threads() -> list[str]:
    return [t.name for t in threading.enumerate() if t.name.startswith("stream:")]


def test_an_inline_stream_handles_each_message_on_the_offering_thread_with_no_worker() -> None:
    seen: list[tuple[int, str]] = []
    sent: list[list] = []
    stream = Stream(
        "/inline",
        sent.append,
        [lambda m: seen.append((m, threading.current_thread().name)) or ["tf"]],
        inline=True,
    )
    try:
        assert "stream:/inline" not in stream_threads()
        for n in range(3):
            stream.offer(None, n)
            assert seen[-1] == (n, threading.current_thread().name)  # done before offer returned
        assert sent == [["tf"]] * 3
        assert (stream.stats.received, stream.stats.handled, stream.stats.dropped) == (3, 3, 0)
    finally:
        stream.stop()
    late = Message()
    gone = weakref.ref(late)
    stream.offer(None, late)
    del late
    assert len(seen) == 3  # stopped: nothing more is handled
    assert gone() is None  # nor kept


def test_a_failing_inline_handler_is_counted_and_the_others_still_run() -> None:
    seen: list[int] = []

    def broken(_message) -> None:
        raise RuntimeError("a handler bug")

    stream = Stream("/inline", None, [broken, seen.append], inline=True)
    try:
        stream.offer(None, 1)  # does not raise
        assert seen == [1] and stream.stats.errors == 1
    finally:
        stream.stop()


def test_a_heavy_handler_moves_an_inline_stream_to_a_worker_for_good() -> None:
    threads: list[str] = []

    def light(_message) -> None:
        threads.append(threading.current_thread().name)

    def heavy(_message) -> None:
        pass

    stream = Stream("/mixed", None, [light], inline=True)
    try:
        stream.offer(None, 1)
        stream.add_handler(heavy, inline=False)
        assert "stream:/mixed" in stream_threads()
        stream.offer(None, 2)
        wait_until(lambda: len(threads) == 2)
        assert threads == [threading.current_thread().name, "stream:/mixed"]
        assert stream.remove_handler(heavy)  # the light one remains
        stream.offer(None, 3)
        wait_until(lambda: len(threads) == 3)
        assert threads[-1] == "stream:/mixed"  # no way back: a message in the slot would be overtaken
    finally:
        stream.stop()
    assert "stream:/mixed" not in stream_threads()
