"""The topics channel: a Pair0 socket, the topic table, the subscription set and a last-value cache.

Every publish caches the serialised body; a MESSAGE frame is sent only while the topic is subscribed.
A SUBSCRIBE frame marks the topic and immediately sends its cached value (this is how `/$topics` and
camera info reach the client, protocol.md §2.4-§2.5). When the client's pipe goes away, every
subscription is cleared.

Sensors publish on every tick whether or not anyone listens, as the real ones do, so a subscription that
arrives just after a tick (subscribe and step go on different sockets) gets that tick's sample. A topic
nobody subscribes to is `offer`ed instead: the cache keeps a function that makes the sample, called only if
a subscription or a reader asks for it.
"""

from __future__ import annotations

import logging
import threading
from collections.abc import Callable, Iterable
from dataclasses import dataclass
from typing import Any

import pynng

from airsim_mapper.common.nng_wait import MessageWait
from airsim_mapper.simserver.wire import protocol
from airsim_mapper.simserver.wire.outbox import Outbox

LOG = logging.getLogger("airsim_mapper.simserver.topics")

TOPICS_PATH = "/$topics"
RECV_WAIT_MS = 100  # the receive loop's wait for a client's frame before it sees whether the hub stops
PUBLISHED = "published"
SUBSCRIBED = "subscribed"


@dataclass(frozen=True)
class TopicInfo:
    """One row of the topic table, as listed in `/$topics`."""

    path: str
    type: str = PUBLISHED
    message_type: str = ""
    frequency: int = 0

    def as_message(self) -> dict[str, Any]:
        return {
            "path": self.path,
            "type": self.type,
            "message_type": self.message_type,
            "frequency": self.frequency,
        }


MessageHandler = Callable[[str, Any], None]
Make = Callable[[], Any]


def topic_list_message(infos: Iterable[TopicInfo]) -> list[dict[str, Any]]:
    """The `/$topics` body: every topic (including itself) in lexicographic path order."""
    rows = {info.path: info for info in infos}
    rows.setdefault(TOPICS_PATH, TopicInfo(TOPICS_PATH, PUBLISHED, "topic-list", 0))
    return [rows[path].as_message() for path in sorted(rows)]


class TopicHub:
    """Owns the Pair0 socket and everything about topics; safe to call from any thread."""

    def __init__(self, address: str, port: int, send_timeout_ms: int = 250) -> None:
        self.url = f"tcp://{address}:{port}"
        self._socket = pynng.Pair0(listen=self.url, send_timeout=send_timeout_ms)
        self._socket.add_post_pipe_connect_cb(self._on_pipe_connected)
        self._socket.add_post_pipe_remove_cb(self._on_pipe_removed)
        self._pipes: set[int] = set()
        self._lock = threading.RLock()
        self._outbox = Outbox(self._write)
        self._table: dict[str, TopicInfo] = {}
        self._subscribed: set[str] = set()
        self._cache: dict[str, protocol.TopicFrame | Make] = {}  # a function: offered, not made yet
        self._handlers: dict[str, MessageHandler] = {}
        self._stopping = threading.Event()
        self._thread = threading.Thread(target=self._recv_loop, name="topics-recv", daemon=True)

    # -- lifecycle

    def start(self) -> None:
        self._thread.start()

    def stop(self) -> None:
        self._stopping.set()
        self._thread.join(timeout=2.0)
        self._outbox.close()
        self._socket.close()

    # -- table

    def set_table(self, infos: Iterable[TopicInfo], handlers: dict[str, MessageHandler]) -> None:
        """Replace the topic table (scene load): cache and subscriptions start empty, `/$topics` is cached."""
        infos = list(infos)
        frame = protocol.message_frame(TOPICS_PATH, topic_list_message(infos))
        with self._lock:
            self._table = {info.path: info for info in infos}
            self._table.setdefault(TOPICS_PATH, TopicInfo(TOPICS_PATH, PUBLISHED, "topic-list", 0))
            self._subscribed.clear()
            self._cache = {TOPICS_PATH: frame}
            self._handlers = dict(handlers)

    def table(self) -> dict[str, TopicInfo]:
        with self._lock:
            return dict(self._table)

    def is_subscribed(self, path: str) -> bool:
        return path in self._subscribed

    def subscriptions(self) -> set[str]:
        with self._lock:
            return set(self._subscribed)

    def cached(self, path: str) -> bytes | None:
        """The last value of `path`, packed (an offered sample is made now)."""
        with self._lock:
            made = self._made(path)
        return made.body if made is not None else None

    def _made(self, path: str) -> protocol.TopicFrame | None:
        """The cached frame of `path`, making an offered sample first (call with the lock held)."""
        cached = self._cache.get(path)
        if callable(cached):
            cached = self._cache[path] = protocol.message_frame(path, cached())
        return cached

    # -- publishing

    def publish(self, path: str, message: Any) -> bool:
        """Cache `message` (packed, or a frame packed for `path`) as the last value of `path`; send it if
        subscribed. False if unknown."""
        frame = message if isinstance(message, protocol.TopicFrame) else protocol.message_frame(path, message)
        with self._lock:
            if path not in self._table:
                return False
            self._cache[path] = frame
            if path in self._subscribed:  # queued under the lock, so frames keep the order of their caching
                self._send(path, frame)
        return True

    def offer(self, path: str, make: Make) -> bool:
        """Publish `make()` if `path` is subscribed; else keep `make` as its last value, made only if a
        subscription or `cached` asks for it. True if it was made now."""
        with self._lock:
            if path not in self._table:
                return False
            if path not in self._subscribed:
                self._cache[path] = make
                return False
        return self.publish(path, make())

    def flush(self, timeout: float) -> bool:
        """Wait until every published frame is on the socket (or dropped by its send timeout)."""
        return self._outbox.flush(timeout)

    def unsubscribe(self, paths: Iterable[str]) -> bool:
        """The `/Sim/Unsubscribe` service: false if any path is not a registered topic."""
        all_known = True
        with self._lock:
            for path in paths:
                if path not in self._table:
                    all_known = False
                self._subscribed.discard(path)
        return all_known

    def _send(self, path: str, frame: protocol.TopicFrame) -> None:
        self._outbox.put(path, frame.frame)

    def _write(self, path: str, frame: bytes) -> None:
        """The outbox's sender thread: one frame onto the socket."""
        try:
            self._socket.send(frame)
        except pynng.Timeout:
            LOG.warning("dropped a message on %s: the client is not reading", path)
        except pynng.NNGException as exc:
            LOG.debug("send on %s failed: %s", path, exc)

    # -- receiving

    def _recv_loop(self) -> None:
        try:
            ready = MessageWait(self._socket)
        except pynng.Closed:
            return
        while not self._stopping.is_set():
            try:
                if not ready(RECV_WAIT_MS):  # then sees whether the hub stops
                    continue
                raw = self._socket.recv(block=False)
            except pynng.TryAgain:
                continue
            except pynng.Closed:
                return
            except pynng.NNGException as exc:
                LOG.debug("topics recv failed: %s", exc)
                continue
            try:
                self._on_frame(protocol.decode_frame(raw))
            except protocol.BadFrameError as exc:
                LOG.warning("ignored a bad topics frame: %s", exc)
            except Exception:
                LOG.exception("failed to handle a topics frame")

    def _on_frame(self, frame: protocol.Frame) -> None:
        if frame.type == protocol.FrameType.SUBSCRIBE:
            self._subscribe(frame.topic)
        elif frame.type == protocol.FrameType.UNSUBSCRIBE:
            self.unsubscribe([frame.topic])
        elif frame.type == protocol.FrameType.MESSAGE:
            self._on_message(frame.topic, frame.body)
        else:
            LOG.warning("ignored a frame of unknown type %s on %s", frame.type, frame.topic)

    def _subscribe(self, path: str) -> None:
        with self._lock:
            if path not in self._table:
                LOG.error("subscribe to unknown topic %s", path)
                return
            self._subscribed.add(path)
            try:
                cached = self._made(path)
            except Exception:
                self._cache.pop(path, None)
                LOG.exception("could not make the last sample of %s for a new subscriber", path)
                return
            if cached is not None:  # queued under the lock: a newer publish cannot overtake it
                self._send(path, cached)

    def _on_message(self, path: str, body: bytes) -> None:
        with self._lock:
            info = self._table.get(path)
            handler = self._handlers.get(path)
        if info is None or info.type != SUBSCRIBED or handler is None:
            LOG.warning("ignored a message on %s: not a server-subscribed topic", path)
            return
        handler(path, protocol.decode_body(body))

    def _on_pipe_connected(self, pipe: pynng.Pipe) -> None:
        with self._lock:
            self._pipes.add(pipe.id)

    def _on_pipe_removed(self, pipe: pynng.Pipe) -> None:
        with self._lock:
            if pipe.id not in self._pipes:
                return  # a refused second peer: the real client is still connected
            self._pipes.discard(pipe.id)
            gone = len(self._subscribed)
            self._subscribed.clear()
        LOG.info("topics client disconnected; cleared %d subscriptions", gone)
