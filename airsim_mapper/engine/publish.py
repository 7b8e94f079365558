"""Publishing a message that holds a large byte buffer (pixels, points) without copying it.

rospy serialises a message into its publisher's buffer and hands that buffer to each connection: on the way,
the pixels are copied once more, with the GIL held. A message that can serialise itself apart
(`serialize_apart`, the converters' Buffer* classes, `convert.buffer_data`) is handed over here in parts
instead, its head, then the buffer from where it is and the fields after it, to connections that take parts
(`rospy_internals.PromptQueuedConnection`, which sends them with one `sendmsg`). The bytes on the wire are
rospy's, byte for byte, and what rospy's publish does around them is kept: the publisher's lock, the
header's sequence number, the topic's statistics, and a connection that fails is closed (rospy then drops
it). Anything else (another message, a latched topic, no subscriber, a closed or unregistered topic,
rospy's own connections) goes through rospy's publish.
"""

from __future__ import annotations

import contextlib
import io
from collections.abc import Callable
from typing import Any

import genpy
from rospy.core import is_shutdown
from rospy.exceptions import ROSSerializationException

from airsim_mapper.common.logs import ros_logger
from airsim_mapper.convert.buffer_data import LENGTH, Part

log = ros_logger("airsim_mapper.publish")


def publish(publisher: Any, message: Any) -> None:
    """`publisher.publish(message)`, handing the message's buffer over without a copy when it can."""
    serialize_apart = getattr(message, "serialize_apart", None)
    impl = getattr(publisher, "impl", None) if serialize_apart is not None else None
    lock = getattr(impl, "publock", None)  # None once the topic is closed
    if lock is None:
        publisher.publish(message)
        return
    failed = []
    with lock:  # rospy's publish lock, re-entrant: rospy's own publish may run inside it
        connections = impl.connections
        if not in_parts(impl, connections):
            publisher.publish(message)
            return
        impl.seq += 1
        try:
            parts = serialized(message, serialize_apart, impl.seq)
        except genpy.SerializationError as exc:  # as rospy's publish reports it
            raise ROSSerializationException(str(exc)) from exc
        for connection in connections:
            if is_shutdown():
                break
            try:
                connection.write_parts(parts)
            except Exception as exc:  # rospy's publish drops the connection whatever the error
                log.debug("closing the connection to %s: %s", connection.endpoint_id, exc)
                failed.append(connection)
        impl.message_data_sent += sum(map(len, parts))
    for connection in failed:
        with contextlib.suppress(Exception):
            connection.close()


def in_parts(impl: Any, connections: list[Any]) -> bool:
    """Whether rospy's publish would send to `connections` now (an open topic, not latched, with
    subscribers), and every one of them takes a message in parts."""
    if impl.closed or impl.is_latch or not connections:
        return False
    return all(hasattr(connection, "write_parts") for connection in connections)


def serialized(
    message: Any, serialize_apart: Callable[[Any], tuple[Part, ...]], seq: int
) -> tuple[Part, ...]:
    """rospy's `serialize_message` for a message whose buffer is sent apart, in parts: the length-prefixed
    head (the header's seq set, a None frame_id made "0"), then the buffer and the fields after it."""
    if getattr(type(message), "_has_header", False):
        header = message.header
        header.seq = seq
        if header.frame_id is None:
            header.frame_id = "0"
    buff = io.BytesIO()
    buff.seek(LENGTH.size)
    rest = serialize_apart(buff)
    end = buff.tell()
    buff.seek(0)
    buff.write(LENGTH.pack(end - LENGTH.size + sum(map(len, rest))))
    return (buff.getvalue(), *rest)
