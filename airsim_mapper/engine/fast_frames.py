"""Fast topic frames: heavy simulator messages decoded straight into numpy, on the client's own socket.

The 1.1.0 client unpacks every topic frame with msgpack on its one receive thread, and msgpack turns each
float array (lidar clouds, `data_float`) into a Python list: 17-25 ms for a 100k-point scan. This module
keeps the client's connection, protocol and receive thread, and changes only what `recv()` returns:

- `install(client, heavy)` replaces `client.socket_topics` with a `RecvProxy` around the real socket.
  Everything but `recv` (send, close, dial, options) goes to the real socket unchanged.
- `RecvProxy.recv()` reads the real frame and peeks at its header. A MESSAGE frame whose body is large and
  whose topic `heavy(topic)` accepts (the engine answers: only the bridge's own callbacks listen, so no
  mission-script callback can see a rewritten frame) has its body decoded here: large msgpack float/int
  arrays (0xdc/0xdd + one type byte and a fixed-width big-endian value per element) become numpy arrays
  through a strided view, after every element's type byte is checked vectorially; large bin/str values
  are sliced once; every other value goes through msgpack itself. The proxy then returns a small frame
  `[2, topic, {"__fast__": key}]` and keeps the decoded dict in a side table. Anything unusual, and every
  other frame, passes through byte for byte.
- `FastFrames.resolve(message)` swaps such a placeholder for its decoded dict (any other message is
  returned as it is). Entries that are never resolved (a dropped frame, a client-side reliability drop)
  expire after `ttl_s`, and at most `per_topic` entries wait per topic, so the table stays bounded.

Decoded dicts equal what the client would have produced, except that large numeric arrays are numpy
arrays (float32 arrays stay float32) instead of lists. The converters accept both.
"""

from __future__ import annotations

import contextlib
import io
import itertools
import threading
import time
from collections import OrderedDict, deque
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import msgpack
import numpy as np

FAST_KEY = "__fast__"
MESSAGE_FRAME = 2
DEFAULT_MIN_BYTES = 32 * 1024  # smaller bodies unpack in microseconds: not worth rewriting
MIN_ARRAY_ELEMENTS = 64  # shorter arrays go through msgpack
MIN_SLICE_BYTES = 1024  # shorter bin/str values go through msgpack
READ_SIZE = 16 * 1024  # msgpack read-ahead for ordinary values

# msgpack type byte -> (big-endian numpy dtype of the value after it, little-endian result dtype)
TYPED_ELEMENTS: dict[int, tuple[str, str]] = {
    0xCA: (">f4", "<f4"),
    0xCB: (">f8", "<f8"),
    0xCC: ("u1", "u1"),
    0xCD: (">u2", "<u2"),
    0xCE: (">u4", "<u4"),
    0xCF: (">u8", "<u8"),
    0xD0: ("i1", "i1"),
    0xD1: (">i2", "<i2"),
    0xD2: (">i4", "<i4"),
    0xD3: (">i8", "<i8"),
}


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


# ---------------------------------------------------------------------------------------- pure decoding


@dataclass(frozen=True)
class FrameHeader:
    """Where the parts of a topics frame `[type, topic, body]` are."""

    frame_type: int
    topic: str
    body_start: int
    body_end: int


def _str_or_bin_span(buf: bytes, pos: int) -> tuple[int, int] | None:
    """(start, end) of the payload of the str/bin value at `pos`, or None if it is not one."""
    if pos >= len(buf):
        return None
    tag = buf[pos]
    if 0xA0 <= tag <= 0xBF:
        start, size = pos + 1, tag & 0x1F
    elif tag in (0xC4, 0xD9):
        start, size = pos + 2, buf[pos + 1] if pos + 1 < len(buf) else -1
    elif tag in (0xC5, 0xDA):
        start, size = pos + 3, int.from_bytes(buf[pos + 1 : pos + 3], "big")
    elif tag in (0xC6, 0xDB):
        start, size = pos + 5, int.from_bytes(buf[pos + 1 : pos + 5], "big")
    else:
        return None
    if size < 0 or start + size > len(buf):
        return None
    return start, start + size


def parse_frame_header(frame: bytes) -> FrameHeader | None:
    """The header of a `[type, topic, body]` frame (fixint type, str/bin topic and body), else None."""
    if len(frame) < 4 or frame[0] != 0x93 or frame[1] > 0x7F:
        return None
    topic_span = _str_or_bin_span(frame, 2)
    if topic_span is None:
        return None
    body_span = _str_or_bin_span(frame, topic_span[1])
    if body_span is None or body_span[1] != len(frame):
        return None
    try:
        topic = frame[topic_span[0] : topic_span[1]].decode("utf-8")
    except UnicodeDecodeError:
        return None
    return FrameHeader(frame[1], topic, *body_span)


def _map_header(buf: bytes, pos: int) -> tuple[int, int] | None:
    tag = buf[pos]
    if 0x80 <= tag <= 0x8F:
        return tag & 0x0F, pos + 1
    if tag == 0xDE:
        return int.from_bytes(buf[pos + 1 : pos + 3], "big"), pos + 3
    if tag == 0xDF:
        return int.from_bytes(buf[pos + 1 : pos + 5], "big"), pos + 5
    return None


def _typed_array(buf: bytes, pos: int, end: int) -> tuple[np.ndarray, int] | None:
    """A large array whose elements all share one fixed-width type byte, as numpy; else None."""
    tag = buf[pos]
    if tag == 0xDC:
        count, first = int.from_bytes(buf[pos + 1 : pos + 3], "big"), pos + 3
    elif tag == 0xDD:
        count, first = int.from_bytes(buf[pos + 1 : pos + 5], "big"), pos + 5
    else:
        return None
    if count < MIN_ARRAY_ELEMENTS or first >= end:
        return None
    marker = buf[first]
    if marker <= 0x7F:  # positive fixints: every element is one byte below 0x80
        if first + count > end:
            return None
        values = np.frombuffer(buf, dtype=np.uint8, count=count, offset=first)
        if values.max() > 0x7F:
            return None
        return values.copy(), first + count
    types = TYPED_ELEMENTS.get(marker)
    if types is None:
        return None
    wire, native = types
    cell = np.dtype([("marker", "u1"), ("value", wire)])
    if first + count * cell.itemsize > end:
        return None
    stop = first + count * cell.itemsize
    # every element's type byte, gathered by a strided bytes slice (C speed) and compared in one memcmp
    if buf[first : stop : cell.itemsize] != bytes((marker,)) * count:
        return None
    cells = np.frombuffer(buf, dtype=cell, count=count, offset=first)
    return cells["value"].astype(native), stop


def _large_slice(buf: bytes, pos: int, end: int, views: bool) -> tuple[Any, int] | None:
    """A large bin (-> bytes, or a memoryview of `buf` with `views`) or str (-> str) value; else None."""
    span = _str_or_bin_span(buf, pos)
    if span is None or span[1] > end or span[1] - span[0] < MIN_SLICE_BYTES:
        return None
    if buf[pos] in (0xC4, 0xC5, 0xC6):
        data = memoryview(buf)[span[0] : span[1]] if views else buf[span[0] : span[1]]
        return data, span[1]
    data = buf[span[0] : span[1]]
    try:
        return data.decode("utf-8"), span[1]
    except UnicodeDecodeError:
        return None


def _unpack_at(stream: io.BytesIO, pos: int) -> tuple[Any, int]:
    """One ordinary msgpack value at `pos`, decoded as the client does (str keys, bin as bytes)."""
    stream.seek(pos)
    unpacker = msgpack.Unpacker(stream, raw=False, read_size=READ_SIZE)
    value = unpacker.unpack()
    return value, pos + unpacker.tell()


def decode_map(
    buf: bytes, start: int = 0, end: int | None = None, views: bool = False
) -> dict[str, Any] | None:
    """The msgpack map in `buf[start:end]` with its large arrays as numpy; None if it is not a map.

    With `views`, large bin values are read-only memoryviews into `buf` instead of copies.
    Raises whatever msgpack raises for a malformed value (the caller falls back to the client's path).
    """
    end = len(buf) if end is None else end
    if start >= end:
        return None
    header = _map_header(buf, start)
    if header is None:
        return None
    count, pos = header
    stream = io.BytesIO(buf)  # shares the bytes object: no copy
    out: dict[str, Any] = {}
    for _ in range(count):  # one pass per key (a dozen or so), never per element
        tag = buf[pos]
        if 0xA0 <= tag <= 0xBF:  # fixstr key: the common case, decoded without msgpack
            key, pos = buf[pos + 1 : pos + 1 + (tag & 0x1F)].decode("utf-8"), pos + 1 + (tag & 0x1F)
        else:
            key, pos = _unpack_at(stream, pos)
        fast = _typed_array(buf, pos, end) or _large_slice(buf, pos, end, views)
        value, pos = fast if fast is not None else _unpack_at(stream, pos)
        out[key] = value
        if pos > end:
            return None
    return out if pos == end else None


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
