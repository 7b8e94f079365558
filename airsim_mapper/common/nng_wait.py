"""Waiting for a message on a pynng socket in the kernel, not on NNG's timer."""

from __future__ import annotations

import select
from typing import Any

import pynng

GONE = select.POLLNVAL | select.POLLERR | select.POLLHUP  # the descriptor closed: so is its socket


class MessageWait:
    """Called with `ms`: whether the socket holds a message, waiting up to `ms` milliseconds for one.

    A receive loop wakes now and then without a message only to see whether it should stop. With NNG's own
    receive timeout each of those wakes runs NNG's timer and worker threads; here the wait is `poll()` on
    NNG's receive descriptor, readable while the socket holds a message, which costs nothing while idle
    (docs/performance.md). The caller then receives without blocking. Closing the socket closes the
    descriptor, which ends the wait at once: pynng's Closed, so that no loop polls a dead descriptor.
    """

    def __init__(self, sock: Any) -> None:
        self._poller = select.poll()
        self._poller.register(sock.recv_fd, select.POLLIN)  # pynng's Closed on a closed socket

    def __call__(self, ms: int) -> bool:
        events = self._poller.poll(ms)
        if any(event & GONE for _fd, event in events):
            raise pynng.exceptions.Closed("the socket's receive descriptor is closed", pynng.lib.NNG_ECLOSED)
        return bool(events)
