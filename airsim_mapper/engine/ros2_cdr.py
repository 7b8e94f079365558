"""The messages the bridge sends for every pose, written as CDR bytes for rclpy to publish as they are.

rclpy's `publish` of a message copies each field into the type's C struct (reading every attribute through
its Python property) before the DDS type support serialises the struct; given `bytes`, it hands them to
DDS as an already serialised message. For the small messages sent at the pose rate (geometry_msgs/
PoseStamped, tf2_msgs/TFMessage, rosgraph_msgs/Clock) the bytes are written here with `struct` from the
message the converter built, so the converters stay what says what a message holds; anything else is
published as the message.

The bytes are what rclpy's `serialize_message` gives: the encapsulation header of little-endian plain CDR
(XCDR1), then the fields in order, each aligned to its size (doubles to 8) counted from after that header;
a string is its UTF-8 bytes with a NUL, after their count as a uint32.
"""

from __future__ import annotations

import struct
from collections.abc import Callable
from typing import Any

ENCAPSULATION = b"\x00\x01\x00\x00"  # CDR, little-endian, no options
STAMP = struct.Struct("<iI")  # builtin_interfaces/Time: sec, nanosec
COUNT = struct.Struct("<I")  # a string's or a sequence's length
SEVEN_DOUBLES = struct.Struct("<7d")  # a position or translation, then a quaternion (x, y, z, w)

Writer = Callable[[Any], bytes]


def _string(out: bytearray, text: str) -> None:
    """A string at the end of `out` (which ends 4-aligned after the encapsulation header)."""
    data = text.encode()
    out += COUNT.pack(len(data) + 1)
    out += data
    out += b"\x00"


def _header(out: bytearray, header: Any) -> None:
    """std_msgs/Header (stamp, frame_id), `out` 4-aligned."""
    stamp = header.stamp
    out += STAMP.pack(stamp.sec, stamp.nanosec)
    _string(out, header.frame_id)


def _align(out: bytearray, size: int) -> None:
    out += bytes(-(len(out) - len(ENCAPSULATION)) % size)


def _point_and_quaternion(out: bytearray, point: Any, q: Any) -> None:
    _align(out, 8)
    out += SEVEN_DOUBLES.pack(point.x, point.y, point.z, q.x, q.y, q.z, q.w)


def pose_stamped(message: Any) -> bytes:
    """geometry_msgs/PoseStamped as CDR."""
    out = bytearray(ENCAPSULATION)
    _header(out, message.header)
    pose = message.pose
    _point_and_quaternion(out, pose.position, pose.orientation)
    return bytes(out)


def tf_message(message: Any) -> bytes:
    """tf2_msgs/TFMessage as CDR."""
    return tf_transforms(message.transforms)


def tf_transforms(transforms: list[Any]) -> bytes:
    """tf2_msgs/TFMessage of these geometry_msgs/TransformStamped as CDR."""
    out = bytearray(ENCAPSULATION)
    out += COUNT.pack(len(transforms))
    for t in transforms:
        _align(out, 4)
        _header(out, t.header)
        _align(out, 4)
        _string(out, t.child_frame_id)
        transform = t.transform
        _point_and_quaternion(out, transform.translation, transform.rotation)
    return bytes(out)


def clock(message: Any) -> bytes:
    """rosgraph_msgs/Clock as CDR."""
    stamp = message.clock
    return ENCAPSULATION + STAMP.pack(stamp.sec, stamp.nanosec)


def writer(message_class: type) -> Writer | None:
    """The CDR writer of a message class, None for a class that is published as a message."""
    name = f"{message_class.__module__.split('.')[0]}/{message_class.__name__}"
    return WRITERS.get(name)


WRITERS: dict[str, Writer] = {
    "geometry_msgs/PoseStamped": pose_stamped,
    "tf2_msgs/TFMessage": tf_message,
    "rosgraph_msgs/Clock": clock,
}
