"""The small ROS messages every pose carries, built by setting their fields directly.

genpy's generated constructors take keyword arguments through a generic loop and first fill every field
with a default object (a Header makes a Time, a Pose a Point and a Quaternion) that the caller then
replaces. A pose message goes through six of them, on the receive thread, for every robot at 100 Hz.
These builders set each field of a bare instance once; the result equals (and serialises exactly as)
the one the constructors give, which tests/convert/test_messages.py checks field by field. ROS 2's classes
are built with their constructors.
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


if ROS2:  # rosidl's classes need their constructors (and a Header has no seq)

    def header(stamp: Time, frame_id: str) -> Header:
        """std_msgs/Header of a stamp and a frame."""
        return Header(stamp=stamp, frame_id=frame_id)

    def pose(x: float, y: float, z: float, qw: float, qx: float, qy: float, qz: float) -> Pose:
        """geometry_msgs/Pose of a position and a (w, x, y, z) quaternion."""
        return Pose(
            position=Point(x=float(x), y=float(y), z=float(z)),
            orientation=Quaternion(x=float(qx), y=float(qy), z=float(qz), w=float(qw)),
        )

    def pose_stamped(head: Header, body: Pose) -> PoseStamped:
        """geometry_msgs/PoseStamped of a header and a pose."""
        return PoseStamped(header=head, pose=body)
