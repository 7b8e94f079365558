"""A receive proxy on the client's topics socket that decodes heavy frames there (a bench comparison).

The bench measures the shipped node against this older approach: `install(client, heavy)` replaces
`client.socket_topics` with a `RecvProxy` that reads each frame, decodes a large MESSAGE body of a topic
`heavy(topic)` accepts with the engine's `decode_map`, and hands the client a small placeholder frame
`[2, topic, {"__fast__": key}]`; `FastFrames.resolve(message)` swaps a placeholder for its decoded dict.
Every other frame passes through byte for byte. Unresolved entries expire after `ttl_s`, and at most
`per_topic` wait per topic, so the side table stays bounded.
"""

from __future__ import annotations

import contextlib
import itertools
import threading
import time
from collections import OrderedDict, deque
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import msgpack

from airsim_mapper.engine.fast_frames import MESSAGE_FRAME, decode_map, parse_frame_header

FAST_KEY = "__fast__"
DEFAULT_MIN_BYTES = 32 * 1024  # smaller bodies unpack in microseconds: not worth rewriting


class FastFramesError(RuntimeError):
    """Fast frames could not be installed or a placeholder could not be resolved."""


class NotConnectedError(FastFramesError):
    def __init__(self) -> None:
        super().__init__("fast frames: the client has no topics socket; call client.connect() first")


class ExpiredFrameError(FastFramesError):
    def __init__(self, key: int) -> None:
        super().__init__(f"fast frames: frame {key} expired or was already resolved")
        self.key = key


@dataclass
class FastStats:
    frames: int = 0  # frames read from the socket
    fast: int = 0  # frames decoded here and replaced by a placeholder
    fast_bytes: int = 0  # body bytes of those frames
    passthrough: int = 0  # frames returned byte for byte
    fallback: int = 0  # heavy frames whose body this module does not decode (returned as they are)
    resolved: int = 0  # placeholders swapped for their message
    expired: int = 0  # side-table entries dropped unresolved (age or per-topic cap)


def placeholder_frame(topic: str, key: int) -> bytes:
    """The small frame handed to the client instead of a decoded one."""
    return msgpack.packb(
        [MESSAGE_FRAME, topic, msgpack.packb({FAST_KEY: key}, use_bin_type=True)], use_bin_type=True
    )


def placeholder_key(message: Any) -> int | None:
    """The side-table key of a placeholder message, or None for any other message."""
    if type(message) is dict and len(message) == 1:
        key = message.get(FAST_KEY)
        if isinstance(key, int):
            return key
    return None


# ---------------------------------------------------------------------------------------- the side table


@dataclass
class _Entry:
    topic: str
    deadline: float
    message: dict[str, Any]


@dataclass
class FastFrames:
    """Rewrites heavy frames and resolves their placeholders; thread-safe and bounded."""

    heavy: Callable[[str], bool]
    min_bytes: int = DEFAULT_MIN_BYTES
    ttl_s: float = 2.0
    per_topic: int = 4
    views: bool = False  # large bin values as memoryviews of the frame (for consumers that accept them)
    stats: FastStats = field(default_factory=FastStats)

    def __post_init__(self) -> None:
        self._lock = threading.Lock()
        self._entries: OrderedDict[int, _Entry] = OrderedDict()
        self._by_topic: dict[str, deque[int]] = {}
        self._keys = itertools.count(1)
        self._client: Any = None
        self._real: Any = None

    # -- receive side (the client's receive thread)

    def rewrite(self, frame: bytes) -> bytes:
        """The frame the client should see: a placeholder for a decoded heavy frame, else `frame`."""
        self.stats.frames += 1
        header = parse_frame_header(frame)
        if (
            header is None
            or header.frame_type != MESSAGE_FRAME
            or header.body_end - header.body_start < self.min_bytes
            or not self._is_heavy(header.topic)
        ):
            self.stats.passthrough += 1
            return frame
        try:
            message = decode_map(frame, header.body_start, header.body_end, self.views)
        except Exception:  # malformed body: the client's own path reports it as it always did
            message = None
        if message is None:
            self.stats.fallback += 1
            return frame
        key = self._store(header.topic, message)
        self.stats.fast += 1
        self.stats.fast_bytes += header.body_end - header.body_start
        return placeholder_frame(header.topic, key)

    def _is_heavy(self, topic: str) -> bool:
        try:
            return bool(self.heavy(topic))
        except Exception:
            return False

    def _store(self, topic: str, message: dict[str, Any]) -> int:
        now = time.monotonic()
        with self._lock:
            key = next(self._keys)
            self._entries[key] = _Entry(topic, now + self.ttl_s, message)
            keys = self._by_topic.setdefault(topic, deque())
            keys.append(key)
            while len(keys) > self.per_topic:
                self._drop(keys.popleft())
            self._expire(now)
        return key

    def _drop(self, key: int) -> None:
        if self._entries.pop(key, None) is not None:
            self.stats.expired += 1

    def _expire(self, now: float) -> None:
        while self._entries:
            key, entry = next(iter(self._entries.items()))
            if entry.deadline > now:
                return
            self._entries.popitem(last=False)
            self.stats.expired += 1
            keys = self._by_topic.get(entry.topic)
            if keys and keys[0] == key:
                keys.popleft()

    # -- consumer side (any thread)

    def resolve(self, message: Any) -> Any:
        """The decoded message behind a placeholder (taken from the table); other messages unchanged."""
        key = placeholder_key(message)
        if key is None:
            return message
        with self._lock:
            entry = self._entries.pop(key, None)
            if entry is None:
                raise ExpiredFrameError(key)
            keys = self._by_topic.get(entry.topic)
            if keys is not None:
                with contextlib.suppress(ValueError):
                    keys.remove(key)
                if not keys:
                    del self._by_topic[entry.topic]
            self.stats.resolved += 1
        return entry.message

    def pending(self) -> int:
        """Entries waiting to be resolved."""
        with self._lock:
            self._expire(time.monotonic())
            return len(self._entries)

    # -- installation

    def uninstall(self) -> None:
        """Give the client its real socket back (pending placeholders can still be resolved)."""
        client, real = self._client, self._real
        if client is not None and isinstance(client.socket_topics, RecvProxy):
            client.socket_topics = real
        self._client = self._real = None


class RecvProxy:
    """Stands in for the client's topics socket: `recv` goes through FastFrames, the rest is forwarded."""

    def __init__(self, real: Any, fast: FastFrames) -> None:
        object.__setattr__(self, "_real", real)
        object.__setattr__(self, "_fast", fast)

    def recv(self, *args: Any, **kwargs: Any) -> bytes:
        return self._fast.rewrite(self._real.recv(*args, **kwargs))

    def __getattr__(self, name: str) -> Any:
        return getattr(self._real, name)

    def __setattr__(self, name: str, value: Any) -> None:
        setattr(self._real, name, value)


def install(client: Any, heavy: Callable[[str], bool], **options: Any) -> FastFrames:
    """Put a RecvProxy on the client's topics socket (idempotent: a second call returns the first)."""
    socket = client.socket_topics
    if isinstance(socket, RecvProxy):
        return socket._fast
    if socket is None:
        raise NotConnectedError()
    fast = FastFrames(heavy, **options)
    fast._client, fast._real = client, socket
    client.socket_topics = RecvProxy(socket, fast)
    return fast
