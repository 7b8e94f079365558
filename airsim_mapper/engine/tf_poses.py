"""Poses and transforms between tf frames, for either ROS flavour: a pose as a transform, a pose moved
into another frame, and the error when tf has no way between two frames."""

from __future__ import annotations

from typing import Any

from geometry_msgs.msg import TransformStamped

from airsim_mapper.common.logs import shorten
from airsim_mapper.engine.errors import EngineError


def transform_from_pose(pose_stamped: Any, parent: str, child: str) -> TransformStamped:
    """A TransformStamped parent -> child from a geometry_msgs/PoseStamped (same stamp)."""
    t = TransformStamped()
    t.header.stamp = pose_stamped.header.stamp
    t.header.frame_id = parent
    t.child_frame_id = child
    p, q = pose_stamped.pose.position, pose_stamped.pose.orientation
    t.transform.translation.x, t.transform.translation.y, t.transform.translation.z = p.x, p.y, p.z
    t.transform.rotation.x, t.transform.rotation.y = q.x, q.y
    t.transform.rotation.z, t.transform.rotation.w = q.z, q.w
    return t


class FrameUnknown(EngineError, LookupError):
    """tf cannot transform a message's frame into the frame a command needs."""

    def __init__(self, source: str, target: str, why: str) -> None:
        super().__init__(
            f"frame {shorten(source)!r} cannot be transformed into {shorten(target)!r} with tf: {why}"
        )


def moved_pose(pose_stamped: Any, transform: TransformStamped) -> Any:
    """`pose_stamped` expressed in the transform's parent frame. The pose's quaternion is composed as it is
    (not normalised), so a zero, non-unit or non-finite goal is still refused by the converter's checks."""
    from geometry_msgs.msg import PoseStamped

    from airsim_mapper.common.geometry import q_mul, q_normalized, q_rotate

    t, r = transform.transform.translation, transform.transform.rotation
    rotation = q_normalized((r.w, r.x, r.y, r.z))
    p, q = pose_stamped.pose.position, pose_stamped.pose.orientation
    x, y, z = q_rotate(rotation, (p.x, p.y, p.z))
    w, qx, qy, qz = q_mul(rotation, (q.w, q.x, q.y, q.z))
    out = PoseStamped()
    if hasattr(out.header, "seq"):  # ROS1's header
        out.header.seq = pose_stamped.header.seq
    out.header.stamp = pose_stamped.header.stamp
    out.header.frame_id = transform.header.frame_id
    out.pose.position.x, out.pose.position.y, out.pose.position.z = x + t.x, y + t.y, z + t.z
    o = out.pose.orientation
    o.w, o.x, o.y, o.z = w, qx, qy, qz
    return out
