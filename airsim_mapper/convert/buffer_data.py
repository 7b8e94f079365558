"""Messages whose ``data`` byte array is held as any byte buffer, and serialised without copying it.

genpy packs a ``uint8[]`` with `struct`, which takes only bytes and copies them once more on the way into
the buffer. The converters' Buffer* messages (`image.BufferImage`, `compressed_image.BufferCompressedImage`)
keep ``data`` as a view of the received frame or of the converted array, and serialise it as it is; a
publisher can send it from where it is (`engine.publish`).
"""

from __future__ import annotations

import struct
from typing import Any


def serialize_head(message: Any, base: type, buff: Any) -> memoryview:
    """Serialize all of `message`, a `base` genpy message whose last field ``data`` is a uint8[] held as
    any byte buffer, but that buffer's bytes: every other field through genpy (``data`` as an empty array,
    a zero length, last), the length put right. Returns the bytes, a flat view: written next, they
    complete the message. A publisher can send them from where they are (`engine.publish`)."""
    data, message.data = message.data, b""
    try:
        base.serialize(message, buff)
    finally:
        message.data = data
    tail = memoryview(data).cast("B")
    buff.seek(buff.tell() - 4)
    buff.write(struct.pack("<I", tail.nbytes))
    return tail


def serialize_buffer_last(message: Any, base: type, buff: Any) -> None:
    """Serialize `message` as `serialize_head` does, then its buffer's bytes."""
    buff.write(serialize_head(message, base, buff))
