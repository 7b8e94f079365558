"""The bridge's process settings: the shared thread tuning, prompt rospy publishing, a frozen heap.

`airsim_mapper.tuning` gives one BLAS thread and a 0.5 ms GIL switch interval. On top, the bridge uses
`PromptQueuedConnection`: rospy's queued connection, which here sends on the publishing thread when the
socket takes the message at once, instead of waking a writer thread and yielding the GIL on every
publish. `freeze_heap` keeps the objects of a running scene out of full collections, and `GcPauses`
reports the longest garbage collection for the status topic.

The soak (`make soak`) measures their effect; `AIRSIM_MAPPER_NO_TUNING=1` turns off the thread settings and
prompt publishing for comparison (the heap is frozen either way).
"""

from __future__ import annotations

import gc
import socket
import threading
import time

import rospy
import rospy.topics
from rospy.impl.tcpros_pubsub import QueuedConnection

from airsim_mapper.convert.buffer_data import Part
from airsim_mapper.engine.ros_link import ConnectionPoll
from airsim_mapper.tuning import tune_threads


class PromptQueuedConnection(QueuedConnection):
    """rospy's queued publisher connection that sends on the publishing thread when it can.

    rospy hands every message to the connection's writer thread and then calls `time.sleep(0)`. Each
    handoff wakes a thread that must take the GIL before it can send, and the yield gives the GIL away
    once per publish and subscriber; with busy threads in the process a pose that fans out to six topics
    waited for the GIL between its own publishes (docs/reliability.md has the measurements).

    Here, when nothing is queued or being sent, `write_data` offers the message to the socket without
    blocking (MSG_DONTWAIT). A message the socket takes whole is done; no thread wakes. If the socket
    takes part of it, the rest becomes `_partial`, which the writer thread sends before anything else and
    the queue limit never drops (a message cut short would corrupt the stream). If it takes nothing, or
    anything is already waiting, the message is queued as in rospy. A slow subscriber therefore still
    never blocks the publisher, and the queue's drop-oldest limit still applies. `write_parts` does the
    same for a message in parts (`engine.publish`: a head, then an image's pixels or a cloud's points
    where they are): the rest of one the socket took in part stays views of them.

    rospy has the transport call a method of the connection when it closes, and the connection holds the
    transport: a reference cycle, so every connection a stopped publisher had (its topic, its transport,
    its writer thread's objects) lived on in the frozen heap (`freeze_heap`). Here the transport wakes the
    writer through the connection's condition alone (`WakeOnClose`), and a closed connection is freed by
    reference counting.
    """

    def __init__(self, connection, queue_size: int) -> None:
        self._partial: tuple[memoryview, ...] | None = None  # the unsent rest of a message taken in part
        self._busy = False  # the writer thread holds messages it took from the queue
        super().__init__(connection, queue_size)
        connection.set_cleanup_callback(WakeOnClose(self._cond_data_available))

    def write_data(self, data: bytes) -> bool:
        return self._write((data,), len(data))

    def write_parts(self, parts: tuple[Part, ...]) -> bool:
        """`write_data` for a message in parts (flat buffers), sent from where they are (`engine.publish`):
        copied into one only when it must wait in the queue."""
        return self._write(parts, sum(map(len, parts)))

    def _write(self, parts: tuple[Part, ...], total: int) -> bool:
        with self._lock:
            if self._error:
                error, self._error = self._error, None
                raise error
            if not self._queue and not self._busy and self._partial is None:
                sent = self._send_now(parts)
                if sent:
                    self._connection.stat_bytes += sent
                    if sent == total:
                        self._connection.stat_num_msg += 1
                    else:  # the writer thread sends the rest (and counts the message)
                        self._partial = unsent(parts, sent)
                        self._cond_data_available.notify()
                    return True
            if self._queue_size > 0 and len(self._queue) == self._queue_size:
                del self._queue[0]
            self._queue.append(parts[0] if len(parts) == 1 else b"".join(parts))
            self._cond_data_available.notify()
        return True

    def _send_now(self, parts: tuple[Part, ...]) -> int:
        """Bytes of `parts` the socket took without blocking; 0 leaves them all to the writer thread."""
        sock = getattr(self._connection, "socket", None)
        if sock is None or self._connection.done or sock.gettimeout() is not None:
            return 0  # no socket yet, closing, or a socket with a timeout (send would poll first)
        try:
            if len(parts) == 1:
                return sock.send(parts[0], socket.MSG_DONTWAIT)
            return sock.sendmsg(parts, (), socket.MSG_DONTWAIT)
        except OSError:  # full (EAGAIN) or broken: the writer thread's sendall meets and reports errors
            return 0

    def _run(self) -> None:
        connection = self._connection
        while not connection.done:
            with self._lock:
                while not self._queue and self._partial is None and not connection.done:
                    self._cond_data_available.wait()
                batch = ([self._partial] if self._partial is not None else []) + [
                    (data,) for data in self._queue
                ]
                self._partial, self._queue = None, []
                self._busy = True
            try:
                self._send(batch)
            finally:
                batch = []  # a sent frame (the rest of one is a view of it) is not kept until the next
                with self._lock:
                    self._busy = False

    def _send(self, batch: list[tuple[Part, ...]]) -> None:
        connection = self._connection
        for parts in batch:
            try:
                for part in parts[:-1]:
                    connection.write_data(part)  # rospy's blocking sendall, its error handling
                    connection.stat_num_msg -= 1  # which counts each write as a message
                connection.write_data(parts[-1])
            except Exception as exc:  # the connection is closed: the rest of the batch goes nowhere
                with self._lock:
                    self._error = exc.with_traceback(None)  # its frames would keep the batch's views alive
                break


def unsent(parts: tuple[Part, ...], sent: int) -> tuple[memoryview, ...]:
    """What is left of `parts` after their first `sent` bytes, as views of them (no copy)."""
    for index, part in enumerate(parts):
        view = memoryview(part)
        if sent < view.nbytes:
            return (view[sent:], *map(memoryview, parts[index + 1 :]))
        sent -= view.nbytes
    return ()


class WakeOnClose:
    """A transport's cleanup callback that wakes its connection's writer thread (rospy's
    `_closed_connection_callback`) without referring to the connection."""

    def __init__(self, data_available: threading.Condition) -> None:
        self._data_available = data_available

    def __call__(self, _transport: object) -> None:
        with self._data_available:
            self._data_available.notify()


def tune_process() -> None:
    """Apply the thread settings and prompt publishing to this process (idempotent).

    The node applies them; a mission script's wrapper only with `tune_process=True`. rospy's topics also
    watch their connections without an open file of their own (`ConnectionPoll`): with the heap frozen,
    the one rospy makes would outlive every topic."""
    rospy.topics.Poller = ConnectionPoll
    if tune_threads():
        rospy.topics.QueuedConnection = PromptQueuedConnection


def freeze_heap() -> float:
    """Collect once, then move every surviving object out of the collector's sight; the time in ms.

    A full collection stops every thread for as long as it takes to walk all tracked objects, tens of
    thousands after the bridge's imports alone, in the middle of the pose path (docs/reliability.md has
    the measured pauses). After `gc.freeze()` later collections walk only what was made since.
    """
    started = time.perf_counter()
    gc.collect()
    gc.freeze()
    return (time.perf_counter() - started) * 1000.0


def thaw_heap() -> None:
    """Undo `freeze_heap` (before a scene change), so the replaced bridges' cycles are still collected."""
    gc.unfreeze()


class GcPauses:
    """The longest garbage collection of this process per window: a collection stops every thread."""

    def __init__(self) -> None:
        self._started = 0.0
        self.longest = 0.0
        self.collections = 0
        gc.callbacks.append(self._on_gc)

    def _on_gc(self, phase: str, _info: dict) -> None:
        if phase == "start":
            self._started = time.perf_counter()
        else:
            self.collections += 1
            self.longest = max(self.longest, time.perf_counter() - self._started)

    def take_peak_ms(self) -> float:
        """The longest pause since the previous call, in milliseconds."""
        longest, self.longest = self.longest, 0.0
        return round(longest * 1000, 1)

    def close(self) -> None:
        if self._on_gc in gc.callbacks:
            gc.callbacks.remove(self._on_gc)
