"""Waiting for a message on a pynng socket in the kernel, not on NNG's timer."""

from __future__ import annotations

import select
from typing import Any


class MessageWait:
    """`wait(ms)`: whether the socket holds a message, waiting up to `ms` milliseconds for one.

    A receive loop wakes now and then without a message only to see whether it should stop. With NNG's own
    receive timeout each wake is a timer on NNG's threads, about a millisecond of their CPU: at the
    client's 100 ms, most of what an idle bridge or server spent (docs/performance.md). This waits in
    `poll()` on NNG's receive descriptor, readable while the socket holds a message, and the caller then
    receives without blocking; closing the socket ends the wait at once.
    """

    def __init__(self, sock: Any) -> None:
        self._poller = select.poll()
        self._poller.register(sock.recv_fd, select.POLLIN)  # pynng's Closed on a closed socket

    def __call__(self, ms: int) -> bool:
        return bool(self._poller.poll(ms))
