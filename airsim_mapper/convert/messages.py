"""The small ROS messages every pose carries, built by setting their fields directly.

genpy's generated constructors take keyword arguments through a generic loop and first fill every field
with a default object (a Header makes a Time, a Pose a Point and a Quaternion) that the caller then
replaces. A pose message goes through six of them, on the receive thread, for every robot at 100 Hz.
These builders set each field of a bare instance once; the result equals (and serialises exactly as)
the one the constructors give, which tests/convert/test_messages.py checks field by field (tests/ros2 on
ROS 2).
"""

from __future__ import annotations

from geometry_msgs.msg import Point, Pose, PoseStamped, Quaternion
from std_msgs.msg import Header

from airsim_mapper.convert.flavour import ROS2, Time, ros_time

__all__ = ["Time", "header", "pose", "pose_stamped", "ros_time"]
_new = object.__new__


def header(stamp: Time, frame_id: str) -> Header:
    """std_msgs/Header with seq 0 (rospy numbers it when publishing)."""
    out = _new(Header)
    out.seq, out.stamp, out.frame_id = 0, stamp, frame_id
    return out


def pose(x: float, y: float, z: float, qw: float, qx: float, qy: float, qz: float) -> Pose:
    """geometry_msgs/Pose of a position and a (w, x, y, z) quaternion."""
    position = _new(Point)
    position.x, position.y, position.z = x, y, z
    orientation = _new(Quaternion)
    orientation.x, orientation.y, orientation.z, orientation.w = qx, qy, qz, qw
    out = _new(Pose)
    out.position, out.orientation = position, orientation
    return out


def pose_stamped(head: Header, body: Pose) -> PoseStamped:
    """geometry_msgs/PoseStamped of a header and a pose."""
    out = _new(PoseStamped)
    out.header, out.pose = head, body
    return out


if ROS2:
    # rosidl's constructors make a default of every sub-message, even one given as an argument, which the
    # caller's then replaces: a PoseStamped built by keywords makes seven messages to keep four. These set
    # the fields of a bare instance, as its setters do when field checks are off (a Header has no seq).

    def header(stamp: Time, frame_id: str) -> Header:
        """std_msgs/Header of a stamp and a frame."""
        out = _new(Header)
        out._check_fields, out._stamp, out._frame_id = False, stamp, frame_id
        return out

    def pose(x: float, y: float, z: float, qw: float, qx: float, qy: float, qz: float) -> Pose:
        """geometry_msgs/Pose of a position and a (w, x, y, z) quaternion."""
        position = _new(Point)
        position._check_fields, position._x, position._y, position._z = False, float(x), float(y), float(z)
        orientation = _new(Quaternion)
        orientation._check_fields, orientation._w = False, float(qw)
        orientation._x, orientation._y, orientation._z = float(qx), float(qy), float(qz)
        out = _new(Pose)
        out._check_fields, out._position, out._orientation = False, position, orientation
        return out

    def pose_stamped(head: Header, body: Pose) -> PoseStamped:
        """geometry_msgs/PoseStamped of a header and a pose."""
        out = _new(PoseStamped)
        out._check_fields, out._header, out._pose = False, head, body
        return out
