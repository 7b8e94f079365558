"""Fast decoding of large topic frames: msgpack float/int arrays straight into numpy.

The 1.1.0 client unpacks every topic frame with msgpack, which turns each float array (lidar clouds,
`data_float`) into a Python list of floats, element by element. `decode_map` decodes a frame body instead:
large msgpack float/int arrays (0xdc/0xdd + one type byte and a fixed-width big-endian value per element)
become numpy arrays through a strided view, after every element's type byte is checked vectorially; large
bin/str values are sliced once (as memoryviews of the frame with `views`); every other value goes through
msgpack itself. Anything it does not recognise returns None, and the caller decodes the body as the client
would. Decoded dicts equal the client's, except that large numeric arrays are numpy arrays (float32 stays
float32) instead of lists; the converters accept both.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Union

import msgpack
import numpy as np

Buffer = Union[bytes, memoryview]  # a frame as received: bytes, or a view of the transport's message
MESSAGE_FRAME = 2
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


@dataclass(frozen=True)
class FrameHeader:
    """Where the parts of a topics frame `[type, topic, body]` are."""

    frame_type: int
    topic: str
    body_start: int
    body_end: int


def _str_or_bin_span(buf: Buffer, pos: int) -> tuple[int, int] | None:
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


def parse_frame_header(frame: Buffer) -> FrameHeader | None:
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
        topic = str(frame[topic_span[0] : topic_span[1]], "utf-8")
    except UnicodeDecodeError:
        return None
    return FrameHeader(frame[1], topic, *body_span)


def _map_header(buf: Buffer, pos: int) -> tuple[int, int] | None:
    tag = buf[pos]
    if 0x80 <= tag <= 0x8F:
        return tag & 0x0F, pos + 1
    if tag == 0xDE:
        return int.from_bytes(buf[pos + 1 : pos + 3], "big"), pos + 3
    if tag == 0xDF:
        return int.from_bytes(buf[pos + 1 : pos + 5], "big"), pos + 5
    return None


def _typed_array(buf: Buffer, pos: int, end: int) -> tuple[np.ndarray, int] | None:
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
    cells = np.frombuffer(buf, dtype=cell, count=count, offset=first)
    if type(buf) is bytes:
        # every element's type byte, gathered by a strided bytes slice (C speed) and compared in one memcmp
        if buf[first : stop : cell.itemsize] != bytes((marker,)) * count:
            return None
    elif (cells["marker"] != marker).any():  # a memoryview: compared in numpy, without a copy
        return None
    return cells["value"].astype(native), stop


def _large_slice(buf: Buffer, pos: int, end: int, views: bool) -> tuple[Any, int] | None:
    """A large bin (-> bytes, or a memoryview of `buf` with `views`) or str (-> str) value; else None."""
    span = _str_or_bin_span(buf, pos)
    if span is None or span[1] > end or span[1] - span[0] < MIN_SLICE_BYTES:
        return None
    if buf[pos] in (0xC4, 0xC5, 0xC6):
        data = memoryview(buf)[span[0] : span[1]] if views else buf[span[0] : span[1]]
        return data, span[1]
    try:
        return str(buf[span[0] : span[1]], "utf-8"), span[1]
    except UnicodeDecodeError:
        return None


def _unpack_at(buf: Buffer, pos: int) -> tuple[Any, int]:
    """One ordinary msgpack value at `pos`, decoded as the client does (str keys, bin as bytes).

    The value is fed READ_SIZE bytes at a time, so only its own bytes (and less than READ_SIZE more) are
    copied, whether `buf` is bytes or a memoryview.
    """
    unpacker = msgpack.Unpacker(raw=False)
    fed = pos
    while True:
        unpacker.feed(buf[fed : fed + READ_SIZE])
        fed += READ_SIZE
        try:
            return unpacker.unpack(), pos + unpacker.tell()
        except msgpack.OutOfData:
            if fed >= len(buf):
                raise ValueError("truncated value") from None


def decode_map(
    buf: Buffer, start: int = 0, end: int | None = None, views: bool = False
) -> dict[str, Any] | None:
    """The msgpack map in `buf[start:end]` with its large arrays as numpy; None if it is not a map.

    `buf` is bytes or a byte memoryview (a received frame, not copied). With `views`, large bin values
    are memoryviews into `buf` instead of copies. Raises whatever msgpack raises for a malformed value
    (the caller falls back to the client's path).
    """
    end = len(buf) if end is None else end
    if start >= end:
        return None
    header = _map_header(buf, start)
    if header is None:
        return None
    count, pos = header
    out: dict[str, Any] = {}
    for _ in range(count):  # one pass per key (a dozen or so), never per element
        tag = buf[pos]
        if 0xA0 <= tag <= 0xBF:  # fixstr key: the common case, decoded without msgpack
            key, pos = str(buf[pos + 1 : pos + 1 + (tag & 0x1F)], "utf-8"), pos + 1 + (tag & 0x1F)
        else:
            key, pos = _unpack_at(buf, pos)
        fast = _typed_array(buf, pos, end) or _large_slice(buf, pos, end, views)
        value, pos = fast if fast is not None else _unpack_at(buf, pos)
        out[key] = value
        if pos > end:
            return None
    return out if pos == end else None
