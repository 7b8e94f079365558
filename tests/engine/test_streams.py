"""Stream peaks: where a stall came from (arrival gap, wait for the worker, handling), per status window."""

from __future__ import annotations

import threading
import time

from airsim_mapper.engine.streams import Stream


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
