"""The node's main loop sleeps until it is woken: by a signal, or by rospy's shutdown hook."""

from __future__ import annotations

import signal
import threading
import time

from airsim_mapper.cli.startup import Stopper


def test_a_wait_lasts_its_timeout_when_nothing_wakes_it():
    stop = Stopper(5.0)
    started = time.monotonic()
    stop.wait(0.2)
    assert 0.18 <= time.monotonic() - started < 1.0


def test_a_wake_from_another_thread_ends_the_wait():
    stop = Stopper(5.0)
    threading.Timer(0.1, stop.wake).start()  # rospy's shutdown hook, from one of rospy's threads
    started = time.monotonic()
    stop.wait(5.0)
    assert time.monotonic() - started < 1.0


def test_a_signal_ends_the_wait_at_once(monkeypatch):
    """Even one taken by another thread (which then runs no Python): the wake-up comes from the C-level
    handler. The signal also arms the shutdown deadline, which here records instead of ending the process
    (it would end pytest itself)."""
    overdue = threading.Event()
    monkeypatch.setattr(Stopper, "_overdue", lambda _self: overdue.set())
    stop = Stopper(1.0)
    previous = signal.getsignal(signal.SIGUSR1)
    previous_fd = stop.install((signal.SIGUSR1,))
    try:
        threading.Timer(0.1, signal.raise_signal, (signal.SIGUSR1,)).start()  # raised on the timer thread
        started = time.monotonic()
        stop.wait(5.0)
        assert time.monotonic() - started < 1.0
        assert stop.signals == [signal.SIGUSR1] and bool(stop)
        started = time.monotonic()
        stop.wait(0.2)  # what woke the first wait was read: this one sleeps
        assert time.monotonic() - started >= 0.18
        assert overdue.wait(5)  # the deadline, --shutdown-timeout, was armed by the signal
    finally:
        signal.signal(signal.SIGUSR1, previous)
        signal.set_wakeup_fd(previous_fd)
