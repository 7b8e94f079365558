"""Per-topic streams: light messages are handled where they arrive, heavy ones by a worker of their own.

Each subscribed simulator topic gets one `Stream`, which runs the handlers of every bridge fed by that
topic. A stream whose handlers are all light (a pose, an instrument reading: a few fields in, one small
message out; the catalogue's `ConverterInfo.inline`) runs them on the receive thread as each message
arrives: no thread wake, no handoff of the GIL, as a bare client callback would. Any other stream has a
slot holding the newest message and a thread that takes it; a message that arrives while the previous one
is still waiting replaces it (drop-oldest, depth 1) and is counted, so a slow image conversion never
delays pose, tf or commands, and never builds a backlog. A stream goes from inline to a worker when a
heavy handler joins it, and stays there (a message handled inline after one left in the slot would
overtake it).
"""

from __future__ import annotations

import threading
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

from airsim_mapper.common.logs import ros_logger

log = ros_logger("airsim_mapper.streams")

# A handler converts and publishes one message; it may return transforms to broadcast. The transforms of
# all handlers of one message go out together, as one tf message.
Handler = Callable[[Any], "list | None"]


@dataclass
class StreamStats:
    received: int = 0
    dropped: int = 0
    handled: int = 0
    errors: int = 0
    last_receive: float = 0.0  # time.monotonic() of the newest message
    newest_stamp: int = 0  # the largest time_stamp (simulator ns) seen on the topic
    # Peaks since the last `take_peaks()` (seconds): they tell where a stall came from.
    arrival_gap_max: float = 0.0  # between two arrivals: the simulator, the wire or the receive loop
    wait_max: float = 0.0  # a message waiting in the slot for the worker: scheduling, the GIL
    handle_max: float = 0.0  # one run of all handlers: conversion and publishing

    def take_peaks(self) -> dict[str, float]:
        """The peaks in milliseconds, reset for the next window."""
        peaks = {
            "arrival_gap_max_ms": round(self.arrival_gap_max * 1000, 1),
            "wait_max_ms": round(self.wait_max * 1000, 1),
            "handle_max_ms": round(self.handle_max * 1000, 1),
        }
        self.arrival_gap_max = self.wait_max = self.handle_max = 0.0
        return peaks


@dataclass
class Stream:
    """The handlers of one simulator topic: inline on the receive thread, or a latest-message slot and a
    worker thread."""

    topic: str
    on_transforms: Callable[[list], None] | None = None
    handlers: list[Handler] = field(default_factory=list)
    stats: StreamStats = field(default_factory=StreamStats)
    # Told every stamp but a stream's first (the simulator's cached frame, possibly old): the time watch.
    on_stamp: Callable[[int, float, str], Any] | None = None
    inline: bool = False  # every handler is light: run them on the offering thread

    def __post_init__(self) -> None:
        self._cond = threading.Condition()
        self._pending: Any = None
        self._has_pending = False
        self._running = True
        self._thread: threading.Thread | None = None
        if not self.inline:
            self._start_worker()

    def _start_worker(self) -> None:
        self._thread = threading.Thread(target=self._work, name=f"stream:{self.topic}", daemon=True)
        self._thread.start()

    def add_handler(self, handler: Handler, inline: bool) -> None:
        """One more handler; a heavy one moves an inline stream to a worker for good."""
        with self._cond:
            self.handlers = [*self.handlers, handler]
            if self.inline and not inline:
                self.inline = False
                self._start_worker()

    def remove_handler(self, handler: Handler) -> bool:
        """Take a handler off (bound methods are made afresh on each access: equal, not identical); True
        while others remain."""
        with self._cond:
            self.handlers = [h for h in self.handlers if h != handler]
            return bool(self.handlers)

    def offer(self, _topic_info: Any, message: Any) -> None:
        """Receive-thread callback: handle the message (inline) or store it and wake the worker. Never
        raises; blocks only for light handlers' work."""
        now = time.monotonic()
        with self._cond:
            stats = self.stats
            if stats.last_receive:
                stats.arrival_gap_max = max(stats.arrival_gap_max, now - stats.last_receive)
            stats.received += 1
            stats.last_receive = now
            stamp = message.get("time_stamp") if type(message) is dict else None
            if type(stamp) is int and stamp > stats.newest_stamp:
                stats.newest_stamp = stamp
            if not self._running:
                return  # stopped: nothing would take it
            inline = self.inline
            if inline:
                handlers = self.handlers
            else:
                if self._has_pending:
                    stats.dropped += 1
                self._pending = message
                self._has_pending = True
                self._cond.notify()
        if type(stamp) is int and self.on_stamp is not None and stats.received > 1:
            self.on_stamp(stamp, now, self.topic)
        if inline:
            self._handle(handlers, message, now)

    def _work(self) -> None:
        while True:
            with self._cond:
                while self._running and not self._has_pending:
                    self._cond.wait()
                if not self._running:
                    return
                message, self._pending, self._has_pending = self._pending, None, False
                handlers = self.handlers
                arrived = self.stats.last_receive
            self._handle(handlers, message, arrived)

    def _handle(self, handlers: list[Handler], message: Any, arrived: float) -> None:
        """Run every handler on one message, then send their transforms as one tf message."""
        start = time.monotonic()
        transforms: list = []
        for handler in handlers:
            try:
                transforms.extend(handler(message) or ())
            except Exception:  # a handler bug must not kill the stream
                self.stats.errors += 1
                log.exception("handler for %s failed", self.topic)
        if transforms and self.on_transforms is not None:
            try:
                self.on_transforms(transforms)
            except Exception:
                self.stats.errors += 1
                log.exception("tf for %s failed", self.topic)
        stats = self.stats
        stats.handled += 1
        stats.wait_max = max(stats.wait_max, start - arrived)
        stats.handle_max = max(stats.handle_max, time.monotonic() - start)

    def stop(self) -> None:
        with self._cond:
            self._running = False
            self._pending, self._has_pending = None, False  # a message left waiting is dropped, not kept
            self._cond.notify()
            thread = self._thread
        if thread is not None and threading.current_thread() is not thread:
            thread.join(timeout=5)
