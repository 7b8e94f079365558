"""Publishing a message whose last field is a large byte buffer (an image's pixels) without copying it.

rospy serialises a message into its publisher's buffer and hands that buffer to each connection: on the
way, the pixels are copied once more, with the GIL held. A message that can serialise its head alone
(`serialize_head`, the converters' Buffer* classes) is handed over here in two parts instead, the head
and the pixels from where they are, to connections that take parts (`realtime.PromptQueuedConnection`,
which sends them with one `sendmsg`). The bytes on the wire are rospy's, byte for byte, and what rospy's
publish does around them is kept: the publisher's lock, the header's sequence number, the topic's
statistics, and a connection that fails is closed (rospy then drops it). Anything else (another message,
a latched topic, no subscriber, a closed or unregistered topic, rospy's own connections) goes through
rospy's publish.
"""

from __future__ import annotations

import contextlib
import io
import struct
from collections.abc import Callable
from typing import Any

import genpy
from rospy.core import is_shutdown
from rospy.exceptions import ROSSerializationException

from airsim_mapper.logs import ros_logger

log = ros_logger("airsim_mapper.publish")
LENGTH = struct.Struct("<I")  # TCPROS frames each message with its length


def publish(publisher: Any, message: Any) -> None:
    """`publisher.publish(message)`, handing the message's buffer over without a copy when it can."""
    serialize_head = getattr(message, "serialize_head", None)
    impl = getattr(publisher, "impl", None) if serialize_head is not None else None
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
            head, tail = serialized(message, serialize_head, impl.seq)
        except genpy.SerializationError as exc:  # as rospy's publish reports it
            raise ROSSerializationException(str(exc)) from exc
        for connection in connections:
            if is_shutdown():
                break
            try:
                connection.write_parts(head, tail)
            except Exception as exc:  # rospy's publish drops the connection whatever the error
                log.debug("closing the connection to %s: %s", connection.endpoint_id, exc)
                failed.append(connection)
        impl.message_data_sent += len(head) + tail.nbytes
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
    message: Any, serialize_head: Callable[[Any], memoryview], seq: int
) -> tuple[bytes, memoryview]:
    """rospy's `serialize_message` for a message whose buffer is sent apart: the length-prefixed head
    (the header's seq set, a None frame_id made "0"), and the buffer."""
    if getattr(type(message), "_has_header", False):
        header = message.header
        header.seq = seq
        if header.frame_id is None:
            header.frame_id = "0"
    buff = io.BytesIO()
    buff.seek(LENGTH.size)
    tail = serialize_head(buff)
    end = buff.tell()
    buff.seek(0)
    buff.write(LENGTH.pack(end - LENGTH.size + tail.nbytes))
    return buff.getvalue(), tail
