"""The ROS link on ROS 2: the same face as `ros_link.RosLink` (publishers whose matched subscribers drive
lazy streams, subscribers, services, the clock, batched /tf, /tf_static, tf lookup), over one rclpy node.

QoS, all from mapping/qos.py: each bridge's `spec.qos` (the rule's, else its converter's catalogue profile),
/tf and /tf_static's, and those of the node's own topics without a rule (status, diagnostics).
There is no tf2_ros wheel: goals are moved between frames through the transforms this node itself sends.
"""

from __future__ import annotations

import importlib
import threading
import time
from collections.abc import Callable
from typing import Any

from rclpy.event_handler import PublisherEventCallbacks
from rclpy.qos import DurabilityPolicy, HistoryPolicy, QoSProfile, ReliabilityPolicy

from airsim_mapper.common.geometry import q_conjugate, q_mul, q_normalized, q_rotate
from airsim_mapper.common.ros_types import generated_kind
from airsim_mapper.engine.errors import EngineError, RosTypeError
from airsim_mapper.engine.ros2_cdr import tf_transforms, writer
from airsim_mapper.engine.tf_poses import FrameUnknown, moved_pose, transform_from_pose
from airsim_mapper.mapping.model import Qos
from airsim_mapper.mapping.qos import SERVICE_QOS, TF_QOS, TF_STATIC_QOS, node_topic_qos

__all__ = [
    "ClosedEndpoint",
    "FrameUnknown",
    "Ros2Link",
    "profile_of",
    "publish",
    "transform_from_pose",
]

FIRST_LOOKUP_S = 1.0  # the first goal in another frame waits this long for the node's own /tf
LOOKUP_POLL_S = 0.05


class ClosedEndpoint(EngineError, RuntimeError):
    """A message went to a publisher a concurrent stop destroyed."""


def message_class(ros_type: str, kind: str = "msg") -> type:
    """`pkg/Name` -> the rosidl class from `pkg.msg` (or `pkg.srv`)."""
    package, _, name = ros_type.partition("/")
    if generated_kind(ros_type) != ("topic" if kind == "msg" else "service"):
        raise RosTypeError(f"ROS {kind} type {ros_type!r} is not a generated {kind} type")
    try:
        return getattr(importlib.import_module(f"{package}.{kind}"), name)
    except (ImportError, AttributeError) as exc:
        raise RosTypeError(f"ROS {kind} type {ros_type!r} cannot be imported: {exc}") from exc


def profile_of(qos: Qos) -> QoSProfile:
    """rclpy's QoSProfile of the mapping's concrete Qos."""
    return QoSProfile(
        depth=qos.depth,
        history=HistoryPolicy[qos.history.upper()],
        reliability=ReliabilityPolicy[qos.reliability.upper()],
        durability=DurabilityPolicy[qos.durability.upper()],
    )


def publish(publisher: Any, message: Any) -> None:
    """`publisher.publish(message)` (rclpy copies ``data`` once, from the bytes the converter gave)."""
    publisher.publish(message)


class Publisher:
    """An rclpy publisher with rospy's face: `publish`, `get_num_connections`, `unregister`. A message of
    a type engine/ros2_cdr.py writes goes to rclpy as its CDR bytes."""

    def __init__(self, node: Any, rclpy_publisher: Any) -> None:
        self._node, self._publisher = node, rclpy_publisher
        self._lock = threading.Lock()
        self._type = rclpy_publisher.msg_type
        self._write = writer(self._type)

    def publish(self, message: Any) -> None:
        if self._write is not None and type(message) is self._type:
            message = self._write(message)
        with self._lock:
            if self._publisher is None:
                raise ClosedEndpoint("the publisher was destroyed")
            self._publisher.publish(message)

    def get_num_connections(self) -> int:
        with self._lock:
            return 0 if self._publisher is None else self._publisher.get_subscription_count()

    def unregister(self) -> None:
        with self._lock:
            publisher, self._publisher = self._publisher, None
        if publisher is not None:
            self._node.destroy_publisher(publisher)


class Endpoint:
    """A subscription or service with rospy's `unregister` / `shutdown`."""

    def __init__(self, destroy: Callable[[], Any]) -> None:
        self._destroy: Callable[[], Any] | None = destroy

    def unregister(self) -> None:
        destroy, self._destroy = self._destroy, None
        if destroy is not None:
            destroy()

    shutdown = unregister


class OwnFrames:
    """The latest transform of each child frame this node sent (on /tf or /tf_static): enough to move a
    goal between the bridge's own frames, with no tf2_ros."""

    def __init__(self) -> None:
        self._parents: dict[str, tuple[str, tuple[float, ...], tuple[float, ...]]] = {}
        self._lock = threading.Lock()

    def add(self, transforms: list[Any]) -> None:
        with self._lock:
            for t in transforms:
                p, r = t.transform.translation, t.transform.rotation
                child = t.child_frame_id.removeprefix("/")
                parent = t.header.frame_id.removeprefix("/")
                self._parents[child] = (parent, (p.x, p.y, p.z), q_normalized((r.w, r.x, r.y, r.z)))

    def clear(self) -> None:
        with self._lock:
            self._parents.clear()

    def to_root(self, frame: str) -> tuple[str, tuple[float, ...], tuple[float, ...]]:
        """(root, translation, rotation) of `frame` in the root of its tree."""
        translation, rotation = (0.0, 0.0, 0.0), (1.0, 0.0, 0.0, 0.0)
        seen = {frame}
        with self._lock:
            while frame in self._parents:
                parent, t, q = self._parents[frame]
                moved = q_rotate(q, translation)
                translation = tuple(a + b for a, b in zip(moved, t))
                rotation = q_mul(q, rotation)
                frame = parent
                if frame in seen:
                    break
                seen.add(frame)
        return frame, translation, rotation

    def transform(self, target: str, source: str) -> Any:
        """A TransformStamped target <- source, or FrameUnknown."""
        from geometry_msgs.msg import TransformStamped

        root_s, t_s, q_s = self.to_root(source)
        root_t, t_t, q_t = self.to_root(target)
        if root_s != root_t:
            raise FrameUnknown(source, target, "the two frames are not in one tree of this node's transforms")
        inverse = q_conjugate(q_t)
        translation = q_rotate(inverse, tuple(a - b for a, b in zip(t_s, t_t)))
        w, x, y, z = q_mul(inverse, q_s)
        out = TransformStamped()
        out.header.frame_id, out.child_frame_id = target, source
        tr = out.transform.translation
        tr.x, tr.y, tr.z = (float(v) for v in translation)
        ro = out.transform.rotation
        ro.w, ro.x, ro.y, ro.z = float(w), float(x), float(y), float(z)
        return out


class Ros2Link:
    """Every ROS 2 endpoint the runners make, and tf, on one rclpy node (spun by the caller's executor)."""

    def __init__(self, node: Any) -> None:
        from tf2_msgs.msg import TFMessage

        self.node = node
        self._tf_message = TFMessage
        self._tf = node.create_publisher(TFMessage, "/tf", profile_of(TF_QOS))
        self._static_tf = node.create_publisher(TFMessage, "/tf_static", profile_of(TF_STATIC_QOS))
        self._static: dict[str, Any] = {}
        self._static_lock = threading.Lock()
        self.frames = OwnFrames()
        self._lookups = False  # a goal asked for a transform: keep the own frames up to date

    def publisher(
        self,
        name: str,
        ros_type: str,
        *,
        queue_size: int,
        latch: bool = False,
        on_peers: Callable[[], None] | None = None,
        qos: Qos | None = None,
    ) -> Publisher:
        """A publisher of `ros_type` with the bridge's `qos` (else, a topic of the node's own, the one
        mapping/qos.py gives it); `on_peers` runs whenever a subscriber matches or leaves."""
        events = None
        if on_peers is not None:
            events = PublisherEventCallbacks(matched=lambda _info: on_peers())
        profile = profile_of(node_topic_qos(latch) if qos is None else qos)
        made = self.node.create_publisher(message_class(ros_type), name, profile, event_callbacks=events)
        return Publisher(self.node, made)

    def subscriber(
        self,
        name: str,
        ros_type: str,
        callback: Callable[[Any], None],
        *,
        queue_size: int,
        qos: Qos | None = None,
    ) -> Endpoint:
        profile = profile_of(node_topic_qos(latch=False) if qos is None else qos)
        made = self.node.create_subscription(message_class(ros_type), name, callback, profile)
        return Endpoint(lambda: self.node.destroy_subscription(made))

    def service(
        self, name: str, srv_type: str, handler: Callable[[Any], Any], *, qos: Qos | None = None
    ) -> tuple[Endpoint, type]:
        """A service with the bridge's `qos` (else the services profile)."""
        srv_class = message_class(srv_type, "srv")
        made = self.node.create_service(
            srv_class,
            name,
            lambda request, _response: handler(request),
            qos_profile=profile_of(SERVICE_QOS if qos is None else qos),
        )
        return Endpoint(lambda: self.node.destroy_service(made)), srv_class.Response

    def now(self) -> Any:
        return self.node.get_clock().now().to_msg()

    def param(self, name: str) -> Any:
        """The node's parameter for the ROS1 name `name` (slashes as dots, as ROS 2 names parameters: `-p
        airsim_node.Drone1.cam.scene_camera.compressed.jpeg_quality:=50`), None when it is not set."""
        dotted = name.strip("/").replace("/", ".")
        if not self.node.has_parameter(dotted):
            return None
        return self.node.get_parameter(dotted).value

    def send_tf(self, transforms: list[Any]) -> None:
        if transforms:
            if self._lookups:
                self.frames.add(transforms)
            self._tf.publish(tf_transforms(transforms))

    def tf_wanted(self) -> bool:
        return self._lookups or self._tf.get_subscription_count() > 0

    def set_static_tf(self, transform: Any) -> None:
        with self._static_lock:
            self._static[transform.child_frame_id] = transform
            self._send_static()

    def remove_static_tf(self, child: str) -> None:
        with self._static_lock:
            if self._static.pop(child, None) is not None:
                self._send_static()

    def _send_static(self) -> None:
        transforms = list(self._static.values())
        self.frames.add(transforms)
        if self.node.context.ok():  # bridges stopping after rclpy shut down (a wrapper with it): nobody hears
            self._static_tf.publish(self._tf_message(transforms=transforms))

    def transform_pose(self, pose_stamped: Any, target: str) -> Any:
        """A PoseStamped in the `target` frame through this node's own latest transforms (FrameUnknown when
        they do not connect the two frames). The first lookup starts recording /tf and gives it
        FIRST_LOOKUP_S to arrive."""
        deadline = time.monotonic() + (0.0 if self._lookups else FIRST_LOOKUP_S)
        self._lookups = True
        source, target = pose_stamped.header.frame_id.removeprefix("/"), target.removeprefix("/")
        while True:
            try:
                return moved_pose(pose_stamped, self.frames.transform(target, source))
            except FrameUnknown:
                if time.monotonic() >= deadline:
                    raise
                time.sleep(LOOKUP_POLL_S)

    def forget_tf(self) -> None:
        self.frames.clear()
        with self._static_lock:
            self.frames.add(list(self._static.values()))

    def close(self) -> None:
        self.frames.clear()
