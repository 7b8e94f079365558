"""Protocol-exact wire encoding of Project AirSim's topics and services channels (protocol.md §2, §3).

Topic frames are msgpack arrays `[type, topic, body]`; the server packs them like the C++ server
(`use_bin_type=False`, so topic and body travel as msgpack str). Service requests and replies carry their
payload msgpack-encoded twice: the named parameters (or the result) are packed once more and sent as bin
under the key `data`.

`pack` is a small msgpack packer that also accepts numpy arrays and pre-encoded `Raw` chunks, so heavy
messages (images, point clouds) are encoded with vectorised numpy instead of per-element Python.
"""

from __future__ import annotations

import json
import struct
from dataclasses import dataclass
from enum import IntEnum
from typing import Any

import msgpack
import numpy as np

from airsim_mapper.simserver.errors import SimServerError

API_VERSION = 1.0
LARGE_BYTES = 4096  # byte strings from this size on are packed by reference (see `message_frame`)


class FrameType(IntEnum):
    SUBSCRIBE = 0
    UNSUBSCRIBE = 1
    MESSAGE = 2


class BadFrameError(SimServerError, ValueError):
    """A topics-channel frame that is not a msgpack array [type, topic, body]."""


class BadRequestError(SimServerError, ValueError):
    """A services-channel request that is not a double-msgpack request envelope."""


@dataclass(frozen=True)
class Raw:
    """Bytes that are already msgpack-encoded and are spliced into a message as they are."""

    data: bytes


@dataclass(frozen=True)
class Frame:
    type: int
    topic: str
    body: bytes


@dataclass(frozen=True)
class Request:
    id: int
    method: str
    params: dict[str, Any]


# ---------------------------------------------------------------------------------------------- packing


def _array_header(n: int) -> bytes:
    if n < 16:
        return bytes([0x90 | n])
    if n < 0x10000:
        return b"\xdc" + struct.pack(">H", n)
    return b"\xdd" + struct.pack(">I", n)


def _map_header(n: int) -> bytes:
    if n < 16:
        return bytes([0x80 | n])
    if n < 0x10000:
        return b"\xde" + struct.pack(">H", n)
    return b"\xdf" + struct.pack(">I", n)


def _bin_header(n: int) -> bytes:
    if n < 0x100:
        return b"\xc4" + bytes([n])
    if n < 0x10000:
        return b"\xc5" + struct.pack(">H", n)
    return b"\xc6" + struct.pack(">I", n)


def _raw_header(n: int) -> bytes:
    """msgpack raw (str) header, as `use_bin_type=False` packs bytes: no str8 in the old format."""
    if n < 32:
        return bytes([0xA0 | n])
    if n < 0x10000:
        return b"\xda" + struct.pack(">H", n)
    return b"\xdb" + struct.pack(">I", n)


def _typed_array(values: np.ndarray, marker: int, dtype: str) -> Raw:
    """An msgpack array whose every element is `marker` followed by the big-endian value."""
    flat = np.asarray(values).reshape(-1)
    cells = np.empty(flat.size, dtype=np.dtype([("marker", "u1"), ("value", dtype)]))
    cells["marker"] = marker
    cells["value"] = flat
    return Raw(_array_header(flat.size) + cells.tobytes())


def float32_array(values: np.ndarray) -> Raw:
    """msgpack array of float32 (0xca + 4 bytes per element), as the real server sends float lists."""
    return _typed_array(values, 0xCA, ">f4")


def int32_array(values: np.ndarray) -> Raw:
    """msgpack array of int32 (0xd2 + 4 bytes per element)."""
    return _typed_array(values, 0xD2, ">i4")


def uint8_list(data: bytes | np.ndarray) -> Raw:
    """msgpack array of small unsigned ints (the JSON form of image `data` in GetImages replies).

    Bytes below 0x80 are positive fixints (1 byte); the others are uint8 (0xcc + byte).
    """
    values = np.frombuffer(data, dtype=np.uint8) if isinstance(data, (bytes, bytearray)) else data
    values = np.ascontiguousarray(values, dtype=np.uint8).reshape(-1)
    large = values >= 0x80
    where = np.arange(values.size) + np.cumsum(large)  # output index of each value byte
    out = np.empty(values.size + int(np.count_nonzero(large)), dtype=np.uint8)
    out[where] = values
    out[where[large] - 1] = 0xCC
    return Raw(_array_header(values.size) + out.tobytes())


def _numpy_array(array: np.ndarray) -> Raw:
    if np.issubdtype(array.dtype, np.floating):
        return float32_array(array)
    if np.issubdtype(array.dtype, np.integer) or array.dtype == bool:
        return int32_array(array)
    raise TypeError(f"cannot pack a numpy array of dtype {array.dtype}")


def _pack_into(obj: Any, out: list[bytes]) -> None:
    if isinstance(obj, Raw):
        out.append(obj.data)
    elif isinstance(obj, dict):
        out.append(_map_header(len(obj)))
        for key, value in obj.items():
            out.append(msgpack.packb(key, use_bin_type=True))
            _pack_into(value, out)
    elif isinstance(obj, (list, tuple)):
        out.append(_array_header(len(obj)))
        for item in obj:
            _pack_into(item, out)
    elif isinstance(obj, np.ndarray):
        out.append(_numpy_array(obj).data)
    elif isinstance(obj, np.generic):
        out.append(msgpack.packb(obj.item(), use_bin_type=True))
    elif isinstance(obj, (bytes, memoryview)) and len(obj) >= LARGE_BYTES:
        out += (_bin_header(len(obj)), obj)  # kept by reference: copied once, by the final join
    else:
        out.append(msgpack.packb(obj, use_bin_type=True))


def pack(obj: Any) -> bytes:
    """msgpack bytes of `obj` (str keys, bytes as bin); numpy arrays and `Raw` chunks are supported."""
    out: list[bytes] = []
    _pack_into(obj, out)
    return b"".join(out)


def _scalar(obj: Any) -> Any:
    """msgpack's `default` for `pack_plain`: a numpy scalar as `pack` packs it, anything else refused."""
    if isinstance(obj, np.generic):
        return obj.item()
    raise TypeError(f"pack_plain cannot pack {type(obj).__name__}: use pack")


def pack_plain(obj: Any) -> bytes:
    """`pack(obj)` by msgpack's C packer, for a message of plain values (dicts, lists, strings, numbers,
    numpy scalars, small byte strings): the same bytes without `pack`'s walk over every field in Python,
    which took most of a pose's publishing. A numpy array or `Raw` chunk raises TypeError; a large byte
    string would be copied once more than `message_frame` copies it."""
    return msgpack.packb(obj, use_bin_type=True, default=_scalar)


# ---------------------------------------------------------------------------------------------- topics


def encode_frame(topic: str, body: bytes, frame_type: int = FrameType.MESSAGE) -> bytes:
    """A topics frame as the C++ server packs it: topic and body as msgpack str (raw)."""
    return msgpack.packb([int(frame_type), topic, body], use_bin_type=False)


@dataclass(frozen=True)
class TopicFrame:
    """A MESSAGE frame packed once (`encode_frame` of the packed message): sent as it is, body on demand."""

    frame: bytes
    body_offset: int

    @property
    def body(self) -> bytes:
        return self.frame[self.body_offset :]


def message_frame(topic: str, message: Any) -> TopicFrame:
    """`encode_frame(topic, pack(message))` with the message's large byte strings copied once (an image's
    pixels were copied three times: into the body, by its join, and into the frame). `message` may be an
    already packed body (bytes)."""
    chunks: list[bytes] = []
    if isinstance(message, bytes):
        chunks.append(message)
    else:
        _pack_into(message, chunks)
    size = sum(len(chunk) for chunk in chunks)
    head = _array_header(3) + msgpack.packb(int(FrameType.MESSAGE)) + msgpack.packb(topic, use_bin_type=False)
    head += _raw_header(size)
    return TopicFrame(b"".join([head, *chunks]), len(head))


def decode_frame(raw: bytes) -> Frame:
    """Parse a frame from the client (topic str, body bin or str); raises BadFrameError."""
    try:
        frame = msgpack.unpackb(raw, raw=True)
    except Exception as exc:
        raise BadFrameError(f"frame is not msgpack: {exc}") from exc
    if not isinstance(frame, (list, tuple)) or len(frame) != 3:
        raise BadFrameError(f"frame must be an array of 3, got {type(frame).__name__}")
    frame_type, topic, body = frame
    if not isinstance(frame_type, int) or not isinstance(topic, bytes) or not isinstance(body, bytes):
        raise BadFrameError("frame must be [int, str, bytes]")
    try:
        return Frame(frame_type, topic.decode("utf-8"), body)
    except UnicodeDecodeError as exc:
        raise BadFrameError("frame topic is not UTF-8") from exc


def decode_body(body: bytes) -> Any:
    """The message inside a MESSAGE frame's body."""
    return msgpack.unpackb(body, raw=False)


# ---------------------------------------------------------------------------------------------- services


def decode_request(raw: bytes) -> Request:
    """Parse a request envelope: method as bin or str, params double-encoded under `data`."""
    try:
        envelope = msgpack.unpackb(raw, raw=False)
    except Exception as exc:
        raise BadRequestError(f"request is not msgpack: {exc}") from exc
    if not isinstance(envelope, dict):
        raise BadRequestError(f"request must be a map, got {type(envelope).__name__}")
    method = envelope.get("method")
    if isinstance(method, bytes):
        try:
            method = method.decode("utf-8")
        except UnicodeDecodeError as exc:
            raise BadRequestError("request method is not UTF-8") from exc
    if not isinstance(method, str):
        raise BadRequestError("request has no method")
    params_field = envelope.get("params", {})
    if isinstance(params_field, dict) and "data" in params_field:
        try:
            params = msgpack.unpackb(params_field["data"], raw=False)
        except Exception as exc:
            raise BadRequestError(f"request params are not msgpack: {exc}") from exc
    else:
        params = params_field
    if params is None:
        params = {}
    if not isinstance(params, dict):
        raise BadRequestError(f"request params must be a map, got {type(params).__name__}")
    request_id = envelope.get("id", -1)
    return Request(request_id if isinstance(request_id, int) else -1, method, params)


def _envelope(request_id: int, key: str, inner: bytes) -> bytes:
    return msgpack.packb(
        {"id": request_id, key: {"data": inner}, "version": API_VERSION},
        use_bin_type=True,
        use_single_float=True,
    )


def encode_result(request_id: int, result: Any) -> bytes:
    """Success reply: {id, result: {data: bin(msgpack(result))}, version: float32 1.0}."""
    return _envelope(request_id, "result", pack(result))


def encode_error(request_id: int, code: float, message: str) -> bytes:
    """Failure reply: {id, error: {data: bin(msgpack({code, message}))}, version}."""
    return _envelope(request_id, "error", pack({"code": float(code), "message": message}))


def dump_params(params: dict[str, Any]) -> str:
    """Parameters as the real server prints them in error messages (compact JSON, sorted keys)."""
    return json.dumps(params, separators=(",", ":"), sort_keys=True, default=repr)
