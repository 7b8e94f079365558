"""The ROS side of the engine: message classes, the ROS link (publishers with peer listeners,
subscribers, services, the clock) and batched tf."""

from __future__ import annotations

import importlib
import threading
from collections.abc import Callable
from typing import Any

import rospy
import tf2_ros
from geometry_msgs.msg import TransformStamped

from airsim_mapper.common.ros_types import generated_kind
from airsim_mapper.engine.errors import RosTypeError
from airsim_mapper.engine.rospy_internals import widen_accept_backlog
from airsim_mapper.engine.tf_poses import FrameUnknown, moved_pose, transform_from_pose

__all__ = ["FrameUnknown", "RosLink", "message_class", "moved_pose", "publisher", "transform_from_pose"]
CLEAR_AGAIN_S = 1.0  # tf's buffer is cleared once more this long after a jump back in time
ClosedEndpoint = rospy.ROSException  # what `publish` raises on a publisher a concurrent stop unregistered


def message_class(ros_type: str, kind: str = "msg") -> type:
    """`pkg/Name` -> the generated class from `pkg.msg` (or `pkg.srv`); only genpy-generated types."""
    package, _, name = ros_type.partition("/")
    if generated_kind(ros_type) != ("topic" if kind == "msg" else "service"):
        raise RosTypeError(f"ROS {kind} type {ros_type!r} is not a genpy-generated {kind} type")
    try:
        return getattr(importlib.import_module(f"{package}.{kind}"), name)
    except (ImportError, AttributeError) as exc:
        raise RosTypeError(f"ROS {kind} type {ros_type!r} cannot be imported: {exc}") from exc


class PeerListener(rospy.SubscribeListener):
    """Calls `on_change` whenever a subscriber connects to or leaves a publisher."""

    def __init__(self, on_change: Callable[[], None]) -> None:
        self._on_change = on_change

    def peer_subscribe(self, topic_name: str, topic_publish: Any, peer_publish: Any) -> None:
        self._on_change()

    def peer_unsubscribe(self, topic_name: str, num_peers: int) -> None:
        self._on_change()


class TfBroadcaster:
    """Sends a batch of transforms as one tf message; the first user creates the /tf publisher."""

    def __init__(self) -> None:
        self._broadcaster: tf2_ros.TransformBroadcaster | None = None
        self._lock = threading.Lock()

    def _ready(self) -> tf2_ros.TransformBroadcaster:
        with self._lock:
            if self._broadcaster is None:
                self._broadcaster = tf2_ros.TransformBroadcaster()
            return self._broadcaster

    def send(self, transforms: list[TransformStamped]) -> None:
        if transforms:
            self._ready().sendTransform(transforms)

    def wanted(self) -> bool:
        """Whether a tf message now would reach anyone: /tf has a subscriber. rospy drops a message
        nobody subscribes to, so a pose's transform need not be built then. The first call advertises
        /tf, so that subscribers find it."""
        broadcaster = self._broadcaster or self._ready()
        return broadcaster.pub_tf.get_num_connections() > 0


class StaticTf:
    """The node's static transforms, all in one latched /tf_static message (a latched topic replays only
    its last message to a new subscriber, so each change sends every transform again)."""

    def __init__(self) -> None:
        self._publisher: rospy.Publisher | None = None
        self._transforms: dict[str, TransformStamped] = {}
        self._lock = threading.Lock()

    def set(self, transform: TransformStamped) -> None:
        with self._lock:
            self._transforms[transform.child_frame_id] = transform
            self._send()

    def remove(self, child: str) -> None:
        with self._lock:
            if self._transforms.pop(child, None) is not None:
                self._send()

    def _send(self) -> None:
        from tf2_msgs.msg import TFMessage

        if self._publisher is None:
            self._publisher = rospy.Publisher("/tf_static", TFMessage, queue_size=100, latch=True)
        self._publisher.publish(TFMessage(list(self._transforms.values())))


def publisher(
    name: str,
    ros_type: str,
    *,
    queue_size: int,
    latch: bool = False,
    on_peers: Callable[[], None] | None = None,
) -> Any:
    """A rospy publisher of `ros_type` (`package/Type`); `on_peers` runs whenever a subscriber connects or
    leaves."""
    listener = PeerListener(on_peers) if on_peers is not None else None
    return rospy.Publisher(
        name, message_class(ros_type), queue_size=queue_size, latch=latch, subscriber_listener=listener
    )


class RosLink:
    """Every ROS endpoint the runners make, and tf: the engine's one door to rospy for bridges.

    As the sim link owns the client, this owns the node's side. Runners use only these methods, so unit
    tests give them a fake (tests/fakes.py) and run without a master.
    """

    def __init__(self) -> None:
        self.tf = TfBroadcaster()
        self.static_tf = StaticTf()
        self.frames = TfLookup()
        widen_accept_backlog()

    publisher = staticmethod(publisher)  # (`publish`, `get_num_connections`, `unregister`)

    def subscriber(
        self, name: str, ros_type: str, callback: Callable[[Any], None], *, queue_size: int
    ) -> Any:
        """A subscriber (`unregister`)."""
        return rospy.Subscriber(name, message_class(ros_type), callback, queue_size=queue_size)

    def service(self, name: str, srv_type: str, handler: Callable[[Any], Any]) -> tuple[Any, type]:
        """A service (`shutdown`) and its response class."""
        srv_class = message_class(srv_type, "srv")
        return rospy.Service(name, srv_class, handler), srv_class._response_class

    def now(self) -> Any:
        return rospy.Time.now()

    def param(self, name: str) -> Any:
        """The ROS parameter `name`'s value, None when it is not set."""
        return rospy.get_param(name, None)

    def send_tf(self, transforms: list[TransformStamped]) -> None:
        self.tf.send(transforms)

    def tf_wanted(self) -> bool:
        """Whether /tf has a subscriber (`TfBroadcaster.wanted`)."""
        return self.tf.wanted()

    def set_static_tf(self, transform: TransformStamped) -> None:
        """Add or replace (by child frame) a transform on /tf_static."""
        self.static_tf.set(transform)

    def remove_static_tf(self, child: str) -> None:
        self.static_tf.remove(child)

    def transform_pose(self, pose_stamped: Any, target: str) -> Any:
        """A PoseStamped in the `target` frame, through tf (FrameUnknown when tf cannot)."""
        return self.frames.transform_pose(pose_stamped, target)

    def forget_tf(self) -> None:
        """Simulation time started over: the transforms of the old time go (`TfLookup.clear`)."""
        self.frames.clear()

    def close(self) -> None:
        self.frames.close()


class TfLookup:
    """Transforms poses between tf frames. The tf listener is made on first use: a node whose goals all
    come in the world frame never subscribes to /tf."""

    def __init__(self, first_wait: float = 1.0, wait: float = 0.2) -> None:
        self.first_wait, self.wait = first_wait, wait
        self._buffer: tf2_ros.Buffer | None = None
        self._listener: tf2_ros.TransformListener | None = None
        self._lock = threading.Lock()

    def _ready(self) -> tuple[tf2_ros.Buffer, float]:
        with self._lock:
            if self._buffer is not None:
                return self._buffer, self.wait
            self._buffer = tf2_ros.Buffer()
            self._listener = tf2_ros.TransformListener(self._buffer)
            return self._buffer, self.first_wait  # an empty buffer: give /tf time to arrive

    def transform_pose(self, pose_stamped: Any, target: str) -> Any:
        """`pose_stamped` in `target`, at its stamp (the latest transform for a zero stamp, or when tf has
        none at that stamp: goals stamped with wall time meet transforms stamped with simulator time)."""
        buffer, wait = self._ready()
        # tf2 refuses names with a leading slash that tf1 accepted ("/Drone1"); both name the same frame
        source, stamp = pose_stamped.header.frame_id.removeprefix("/"), pose_stamped.header.stamp
        target = target.removeprefix("/")
        try:
            try:
                transform = buffer.lookup_transform(target, source, stamp, rospy.Duration(wait))
            except tf2_ros.ExtrapolationException:
                transform = buffer.lookup_transform(target, source, rospy.Time(0), rospy.Duration(wait))
        except tf2_ros.TransformException as exc:
            raise FrameUnknown(source, target, str(exc).splitlines()[0][:200]) from None
        return moved_pose(pose_stamped, transform)

    def clear(self) -> None:
        """Drop every transform, now and again after CLEAR_AGAIN_S: the node's own /tf messages of the old
        time still on their way would otherwise fill the buffer again, and tf refuses data more than its
        cache time older than what it holds (TF_OLD_DATA, on every new transform until the new time passes
        the old)."""
        with self._lock:
            buffer = self._buffer
        if buffer is None:
            return
        buffer.clear()
        again = threading.Timer(CLEAR_AGAIN_S, buffer.clear)
        again.daemon = True
        again.start()

    def close(self) -> None:
        with self._lock:
            if self._listener is not None:
                self._listener.unregister()
            self._listener = self._buffer = None
