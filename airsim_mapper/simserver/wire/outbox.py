"""The topics socket's outbox: publishers hand frames over and never wait for the client.

The simulation thread publishes a pose and every instrument each tick. Sending on the socket blocks while
the client is not reading and gives up the GIL, so a tick that sent its own messages was late whenever the
sensor thread was rendering. Frames now go to one sender thread in two lanes:

- small frames (poses, instruments: under `SMALL_FRAME_BYTES`) in order, sent first;
- large frames (images, clouds), sent when no small frame waits, keeping only the newest per topic.

A topic's frames never overtake each other: a small frame for a topic whose large frame still waits
replaces it in the large lane. When the client stops reading, the large lane holds one frame per topic and
the small lane drops its oldest frame beyond `SMALL_LANE_LIMIT`; drops are counted and logged.
"""

from __future__ import annotations

import logging
import threading
import time
from collections import OrderedDict, deque
from collections.abc import Callable

LOG = logging.getLogger("airsim_mapper.simserver.outbox")

SMALL_FRAME_BYTES = 64 * 1024
SMALL_LANE_LIMIT = 4096
WARN_PERIOD_S = 5.0


class Outbox:
    """Frames waiting for the socket, and the thread that sends them with `send(path, frame)`."""

    def __init__(self, send: Callable[[str, bytes], None], name: str = "topics-send") -> None:
        self._send = send
        self._cond = threading.Condition()
        self._small: deque[tuple[str, bytes]] = deque()
        self._large: OrderedDict[str, bytes] = OrderedDict()
        self._closed = False
        self._sending = False  # the sender thread holds a frame it took
        self.dropped = 0
        self._warned_at = 0.0
        self._thread = threading.Thread(target=self._run, name=name, daemon=True)
        self._thread.start()

    def put(self, path: str, frame: bytes) -> None:
        """Queue `frame` for `path`; never blocks."""
        with self._cond:
            if self._closed:
                return
            if len(frame) >= SMALL_FRAME_BYTES or path in self._large:
                if path in self._large:
                    self._drop(f"a newer frame replaced a waiting one on {path}")
                self._large[path] = frame
                self._large.move_to_end(path)
            else:
                if len(self._small) >= SMALL_LANE_LIMIT:
                    dropped_path, _ = self._small.popleft()
                    self._drop(f"the client is not reading; dropped the oldest frame of {dropped_path}")
                self._small.append((path, frame))
            self._cond.notify_all()

    def pending(self) -> int:
        with self._cond:
            return len(self._small) + len(self._large)

    def flush(self, timeout: float) -> bool:
        """Wait until every queued frame has been sent (or given up on); False on timeout."""
        deadline = time.monotonic() + timeout
        with self._cond:
            while self._small or self._large or self._sending:
                remaining = deadline - time.monotonic()
                if remaining <= 0 or self._closed:
                    return False
                self._cond.wait(remaining)
        return True

    def close(self, timeout: float = 2.0) -> None:
        """Stop the sender thread; frames still waiting are discarded."""
        with self._cond:
            self._closed = True
            self._small.clear()
            self._large.clear()
            self._cond.notify_all()
        if threading.current_thread() is not self._thread:
            self._thread.join(timeout=timeout)

    def _drop(self, why: str) -> None:
        """Count a dropped frame; log at most once per WARN_PERIOD_S (call with the lock held)."""
        self.dropped += 1
        now = time.monotonic()
        if now - self._warned_at >= WARN_PERIOD_S:
            self._warned_at = now
            LOG.warning("%s (%d frames dropped so far)", why, self.dropped)

    def _run(self) -> None:
        while True:
            with self._cond:
                while not self._closed and not self._small and not self._large:
                    self._cond.wait()
                if self._closed:
                    return
                path, frame = self._small.popleft() if self._small else self._large.popitem(last=False)
                self._sending = True
            try:
                self._send(path, frame)
            except Exception:  # the sender thread must outlive any one bad send
                LOG.exception("sending a frame on %s failed", path)
            finally:
                with self._cond:
                    self._sending = False
                    self._cond.notify_all()
