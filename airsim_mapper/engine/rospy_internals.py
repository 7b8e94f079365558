"""The one place that touches rospy's internals (pinned: Debian 12's rospy, python3-rospy 1.15.15).

rospy's queued publisher connection (`rospy.impl.tcpros_pubsub.QueuedConnection`) hands every message to
a writer thread; `PromptQueuedConnection` subclasses it to send on the publishing thread when it can, and
so relies on its private state (`_lock`, `_cond_data_available`, `_queue`, `_queue_size`, `_error`,
`_connection`, `_run`). `ConnectionPoll` replaces rospy's per-topic `rospy.topics.Poller`;
`publish_promptly` and `watch_connections_without_a_file` put the two in place of rospy's in
`rospy.topics`. `widen_accept_backlog` reaches rospy's private TCPROS server (`tcpros_base._tcpros_server`).
`missing_internals` says what of this is gone in the installed rospy.
"""

from __future__ import annotations

import contextlib
import re
import select
import socket
import threading
from collections.abc import Iterator

import rospy
import rospy.topics
from rospy.impl.tcpros_pubsub import QueuedConnection

from airsim_mapper.convert.buffer_data import Part

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


class ConnectionPoll(rospy.topics.Poller):
    """rospy's per-topic watch for dead connections, on poll(2) instead of an epoll: no open file per topic.

    rospy gives every topic an epoll object and never closes it; it goes only when the topic is collected,
    which a frozen heap (`freeze_heap`) delays for good. So each topic held an open file (a robot with
    1,000 IMUs hit `ulimit -n 1024`) and each restarted one leaked it (every live mapping reload).
    `process_tuning.tune_process` installs it for every topic made afterwards, with the frozen heap.

    It watches what rospy's epoll watches: an error, a hang-up, and the peer's half-close (POLLRDHUP, the
    FIN of a closed peer). rospy's own poll(2) fallback misses the half-close, so a connection whose peer
    had just gone stayed listed; a new publisher at the same node URI then found it, took itself for
    connected (`has_connection`) and was never connected. The methods sit on the class: rospy keeps
    bound methods on the instance, a cycle that outlives the topic in a frozen heap.
    """

    _WATCH = select.POLLRDHUP  # POLLHUP and POLLERR are reported whatever the mask
    _GONE = select.POLLHUP | select.POLLERR | select.POLLRDHUP

    def __init__(self) -> None:
        self.poller = select.poll()
        # rospy polls from its registration thread (`check`, unlocked) and under the topic's lock when a
        # connection is added; epoll allows that, but a poll object raises on a concurrent poll().
        self._lock = threading.Lock()

    def add_fd(self, fd: int) -> None:
        with self._lock:
            self.poller.register(fd, self._WATCH)

    def remove_fd(self, fd: int) -> None:
        with self._lock:
            self.poller.unregister(fd)

    def error_iter(self) -> Iterator[int]:
        """The watched descriptors whose connection has ended."""
        with self._lock:
            events = self.poller.poll(0)
        return (fd for fd, event in events if event & self._GONE)


ACCEPT_BACKLOG = 128  # connections the node's TCPROS port queues while it handles one


def widen_accept_backlog(backlog: int = ACCEPT_BACKLOG) -> None:
    """Let the node's TCPROS port queue `backlog` new connections instead of rospy's 5.

    rospy's TCPROS server listens with a backlog of 5 and reads each new connection's header on its one
    accept thread. A subscriber of many topics at once (`rosbag record` of ten topics, rviz) connects to
    them all within milliseconds: the kernel dropped the connections beyond the fifth and their clients
    retried a second later, so those topics started 1 s late. Listening again on the same socket only
    changes its queue. The server is started first, as rospy does at the first publisher or service; before
    `init_node` (which sets its port) and after shutdown (which closes it) nothing is done."""
    from rospy.impl import tcpros_base

    if not rospy.core.is_initialized() or rospy.is_shutdown():
        return
    tcpros_base.start_tcpros_server()
    server = getattr(tcpros_base._tcpros_server, "tcp_ros_server", None)
    sock = getattr(server, "server_sock", None)
    if sock is not None:
        with contextlib.suppress(OSError):  # closed by a shutdown meanwhile
            sock.listen(backlog)


def publish_promptly() -> None:
    """Every rospy publisher connection made from now on is a `PromptQueuedConnection`."""
    rospy.topics.QueuedConnection = PromptQueuedConnection


def watch_connections_without_a_file() -> None:
    """rospy's topics made from now on watch their connections with `ConnectionPoll`."""
    rospy.topics.Poller = ConnectionPoll


def missing_internals() -> list[str]:
    """The private names of the installed rospy this module relies on that are gone or different."""
    import inspect

    missing = [
        f"rospy.topics.{name}" for name in ("QueuedConnection", "Poller") if not hasattr(rospy.topics, name)
    ]
    if not callable(getattr(QueuedConnection, "_run", None)):
        missing.append("QueuedConnection._run")
    from rospy.impl import tcpros_base

    if not hasattr(tcpros_base, "_tcpros_server"):
        missing.append("rospy.impl.tcpros_base._tcpros_server")
    made = inspect.getsource(QueuedConnection.__init__)
    missing.extend(
        f"QueuedConnection.{name}" for name in QUEUE_STATE if not re.search(rf"self\.{name}\s*=", made)
    )
    return missing
