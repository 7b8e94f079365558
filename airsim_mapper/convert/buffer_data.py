"""Messages whose ``data`` byte array is held as any byte buffer, and serialised without copying it.

genpy packs a ``uint8[]`` with `struct`, which takes only bytes and copies them once more on the way into
the buffer. The converters' Buffer* messages (`image.BufferImage`, `compressed_image.BufferCompressedImage`,
`pointcloud.BufferPointCloud2`) keep ``data`` as a view of the received frame or of the converted array.
`serialize_apart` writes every field through genpy but ``data``'s bytes, and returns those bytes with the
serialised fields after them: written next, in order, they complete the message. So `serialize` writes
the bytes once, and a publisher can send them from where they are (`engine.publish`).
"""

from __future__ import annotations

import array
import struct
from typing import Any, Union

Part = Union[bytes, memoryview]  # a flat byte buffer, one part of a serialised message
LENGTH = struct.Struct("<I")  # the length before a uint8[]'s bytes


class BufferData:
    """Mixin of a genpy message class whose ``data`` (uint8[]) may be any byte buffer.

    `_genpy_class` is the genpy class; `_after_data` the size of its fixed-size fields after ``data`` (0 when
    ``data`` is the last field). Same type, md5sum and bytes on the wire as the genpy class; but not equal
    to a genpy message holding the same bytes, and not for deepcopy or pickling (``data`` is a view).
    `serialize_apart` needs `buff` positioned at its end: it truncates what follows.
    """

    __slots__ = ()
    _genpy_class: type
    _after_data = 0

    def serialize(self, buff: Any) -> None:
        for part in self.serialize_apart(buff):
            buff.write(part)

    def serialize_apart(self, buff: Any) -> tuple[Part, ...]:
        return serialize_apart(self, self._genpy_class, buff, self._after_data)


def serialize_apart(message: Any, base: type, buff: Any, after: int = 0) -> tuple[Part, ...]:
    """Serialize `message`, a `base` genpy message whose ``data`` is a uint8[] held as any byte buffer,
    up to ``data``'s bytes (every field before them through genpy, then their length). Returns what
    completes the message: those bytes as a flat view, then the `after` bytes of the fields after them
    when there are any."""
    data, message.data = message.data, b""
    try:
        base.serialize(message, buff)  # data as an empty array: a zero length, then the fields after it
    finally:
        message.data = data
    view = memoryview(data).cast("B")
    end = buff.tell()
    buff.seek(end - after)
    rest = buff.read(after)
    buff.seek(end - after - LENGTH.size)
    buff.write(LENGTH.pack(view.nbytes))
    if not after:
        return (view,)
    buff.truncate()
    return view, rest


def ros2_buffer_message(base: type) -> type:
    """ROS 2's stand-in for a Buffer* class: called as the class is, it makes a message of the rosidl class
    `base` whose ``data`` is what rclpy's setter would store, an `array.array('B')`, filled with one copy
    from wherever the bytes lie (through the setter, bytes first: two copies, three in the constructor)."""
    from airsim_mapper.convert.flavour import byte_data

    def __new__(cls: type, **fields: Any) -> Any:
        data = fields.pop("data", None)
        message = base(**fields)
        if data is not None:
            try:
                flat = memoryview(data).cast("B")
            except (TypeError, ValueError):  # not one flat buffer (a list of ints, a strided array)
                flat = byte_data(data)
            held = array.array("B")
            held.frombytes(flat)
            message._data = held
        return message

    return type(f"Buffer{base.__name__}", (), {"__new__": __new__, "__doc__": base.__doc__})
