"""The one place that touches rospy's internals (pinned: Debian 12's rospy, python3-rospy 1.15.15).

rospy's queued publisher connection (`rospy.impl.tcpros_pubsub.QueuedConnection`) hands every message to
a writer thread; `PromptQueuedConnection` subclasses it to send on the publishing thread when it can, and
so relies on its private state (`_lock`, `_cond_data_available`, `_queue`, `_queue_size`, `_error`,
`_connection`, `_run`). `publish_promptly` and `watch_connections_without_a_file` put the bridge's classes
in place of rospy's in `rospy.topics`. `missing_internals` says what of this is gone in the installed rospy.
"""

from __future__ import annotations

import re
import socket
import threading

import rospy.topics
from rospy.impl.tcpros_pubsub import QueuedConnection

from airsim_mapper.convert.buffer_data import Part
from airsim_mapper.engine.ros_link import ConnectionPoll

PINNED = "Debian 12's rospy (python3-rospy 1.15.15)"
QUEUE_STATE = ("_connection", "_queue_size", "_lock", "_cond_data_available", "_queue", "_error")


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


def publish_promptly() -> None:
    """Every rospy publisher connection made from now on is a `PromptQueuedConnection`."""
    rospy.topics.QueuedConnection = PromptQueuedConnection


def watch_connections_without_a_file() -> None:
    """rospy's topics made from now on watch their connections with `ConnectionPoll` (ros_link.py)."""
    rospy.topics.Poller = ConnectionPoll


def missing_internals() -> list[str]:
    """The private names of the installed rospy this module relies on that are gone or different."""
    import inspect

    missing = [
        f"rospy.topics.{name}" for name in ("QueuedConnection", "Poller") if not hasattr(rospy.topics, name)
    ]
    if not callable(getattr(QueuedConnection, "_run", None)):
        missing.append("QueuedConnection._run")
    made = inspect.getsource(QueuedConnection.__init__)
    missing.extend(
        f"QueuedConnection.{name}" for name in QUEUE_STATE if not re.search(rf"self\.{name}\s*=", made)
    )
    return missing
