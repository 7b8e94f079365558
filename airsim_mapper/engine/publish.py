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
from typing import Any

from rospy.core import is_shutdown

from airsim_mapper.logs import ros_logger

log = ros_logger("airsim_mapper.publish")
LENGTH = struct.Struct("<I")  # TCPROS frames each message with its length


def publish(publisher: Any, message: Any) -> None:
    """`publisher.publish(message)`, handing the message's buffer over without a copy when it can."""
    serialize_head = getattr(message, "serialize_head", None)
    impl = getattr(publisher, "impl", None) if serialize_head is not None else None
    if impl is None or impl.closed or impl.is_latch:
        publisher.publish(message)
        return
    connections = impl.connections
    if not connections or not all(hasattr(c, "write_parts") for c in connections):
        publisher.publish(message)
        return
    failed = []
    impl.acquire()
    try:
        impl.seq += 1
        message.header.seq = impl.seq
        buff = io.BytesIO()
        buff.seek(LENGTH.size)
        tail = serialize_head(buff)
        end = buff.tell()
        buff.seek(0)
        buff.write(LENGTH.pack(end - LENGTH.size + tail.nbytes))
        head = buff.getvalue()
        for connection in connections:
            if is_shutdown():
                break
            try:
                connection.write_parts(head, tail)
            except Exception as exc:  # rospy's publish drops the connection whatever the error
                log.debug("closing the connection to %s: %s", connection.endpoint_id, exc)
                failed.append(connection)
        impl.message_data_sent += len(head) + tail.nbytes
    finally:
        impl.release()
    for connection in failed:
        with contextlib.suppress(Exception):
            connection.close()
