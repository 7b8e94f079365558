"""Runners for expanded bridges: each takes a BridgeSpec and wires sim link <-> converter <-> ROS link.

Here: what every runner has (`Bridge`: a spec, its stats, a rate-limited warning channel, the engine's
`BridgeParts`), the simulator -> ROS runners (`SimToRos`, `StreamingImage`) and the catalogue's after-hooks.
The ROS -> simulator runners are in ros_to_sim.py; runners.py's `build` picks one from the catalogue
(`ConverterInfo.runner`, `after`, `action`), so adding a converter touches the catalogue and its own
module, never the engine.
"""

from __future__ import annotations

import dataclasses
import threading
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

from geometry_msgs.msg import TransformStamped

from airsim_mapper.common.geometry import q_conjugate, q_mul, q_rotate
from airsim_mapper.common.logs import RateLimitedLog, ros_logger, shorten
from airsim_mapper.convert import catalog, registry
from airsim_mapper.convert.context import ConvertContext
from airsim_mapper.convert.errors import ConversionError, OversizedData
from airsim_mapper.convert.flavour import ROS2
from airsim_mapper.convert.pose import camera_pose_key
from airsim_mapper.convert.transport_params import overridden
from airsim_mapper.engine.hub import StreamHub
from airsim_mapper.engine.mounts import CameraMounts
from airsim_mapper.engine.replays import LatchedReplays
from airsim_mapper.engine.sim_link import FrameCounts, SimLink
from airsim_mapper.engine.simtime import SimTimeWatch
from airsim_mapper.mapping.model import BridgeSpec

if ROS2:
    from airsim_mapper.engine.ros2_link import ClosedEndpoint, publish, transform_from_pose
    from airsim_mapper.engine.ros2_link import Ros2Link as RosLink
else:
    from airsim_mapper.engine.publish import publish
    from airsim_mapper.engine.ros_link import ClosedEndpoint, RosLink, transform_from_pose

log = ros_logger("airsim_mapper.bridge")
WARN_PERIOD_S = 5.0
SHOWN_ERROR = 500  # characters of a refusal that a log line and the status show


@dataclass
class BridgeStats:
    messages: int = 0  # converted and published / forwarded
    errors: int = 0  # rejected or failed
    last_stamp: Any = None  # header stamp (a genpy Time) of the last published message
    last_time: float = 0.0  # time.monotonic() of the last message
    last_error: str = ""
    stale_dropped: int = 0  # messages taken before a lazy bridge attached (the simulator's cached frame)
    clamped: int = 0  # commands changed to keep them within their limits


@dataclass
class BridgeParts:
    """The engine parts every runner is built from: the two links, the stream hub, the camera mounts, the
    engine's actions and the node-wide counts."""

    sim: SimLink
    hub: StreamHub
    ros: RosLink
    mounts: CameraMounts  # camera mounts moved by pose commands (engine/mounts.py)
    node_action: Callable[[str, dict], Any]  # an engine action by its catalogue name (load_scene)
    streaming: list[StreamingImage] = field(default_factory=list)  # the running streaming-image bridges
    counts: FrameCounts = field(default_factory=FrameCounts)  # refused simulator frames, node-wide
    sim_time: SimTimeWatch = field(default_factory=SimTimeWatch)  # simulation time going backwards
    # Per ROS topic, what its engine action (load_scene) last acted on: outlives a re-created subscriber.
    replays: dict[str, LatchedReplays] = field(default_factory=dict)


@dataclass(frozen=True)
class ClampCounter:
    """A bridge's `on_clamp`: a command clamped to its limits is counted, and warned like a refusal
    (throttled)."""

    stats: BridgeStats
    warn: Callable[[str], None]

    def __call__(self, what: str) -> None:
        self.stats.clamped += 1
        self.warn(shorten(what, SHOWN_ERROR))


def make_context(
    spec: BridgeSpec, parts: BridgeParts, on_clamp: Callable[[str], None] | None = None
) -> ConvertContext:
    return ConvertContext(
        frame_id=spec.frame_id or "",
        convention=spec.convention,
        stamp=spec.options.stamp,
        now=parts.ros.now,
        params=topic_params(spec, parts),
        source=spec.source,
        variables=spec.variables,
        options=spec.options,
        mounts=parts.mounts,
        on_clamp=on_clamp,
    )


def topic_params(spec: BridgeSpec, parts: BridgeParts) -> Any:
    """The rule's params, with those an image_transport plugin reads from ROS parameters named after the
    topic in their place (transport_params.py); read once, as the bridge is built."""
    if spec.ros is None:
        return spec.params
    found = overridden(spec.converter, spec.ros, spec.params, parts.ros.param)
    for refused in found.refused:
        log.warning("%s: %s", spec.name, refused)
    return found.params


class Bridge:
    """Base: a spec, its stats and a throttled warning channel."""

    def __init__(self, spec: BridgeSpec, parts: BridgeParts) -> None:
        self.spec = spec
        self.parts = parts
        self.info = catalog.CONVERTERS[spec.converter]
        self.stats = BridgeStats()
        self.warn = RateLimitedLog(log, WARN_PERIOD_S, prefix=spec.name).warn
        # The context is told of clamps through a counter, not a method of the bridge: a bridge that refers
        # to itself lives on after it stops, and in a frozen heap (engine/process_tuning.py) for good.
        self.ctx = make_context(spec, parts, ClampCounter(self.stats, self.warn))

    def after_call(self, params: dict, result: Any) -> None:
        """The catalogue's after-hook, once the simulator accepted a call (a result other than false)."""
        if self.info.after is not None and _accepted(result):
            AFTER_HOOKS[self.info.after](self, params, result)

    def start(self) -> None:
        raise NotImplementedError

    def stop(self) -> None:
        raise NotImplementedError

    def fail(self, message: str, exc: BaseException | None = None) -> None:
        """Count a bridge error and log it (rate-limited), cut to SHOWN_ERROR characters (a refused 10 MB
        frame name is not logged in full); `exc`, an unexpected exception, with its traceback."""
        message = shorten(message, SHOWN_ERROR)
        self.stats.errors += 1
        self.stats.last_error = message
        self.warn(message, exc)

    def failed(self, what: str, exc: BaseException) -> None:
        """An exception no converter should raise (a bug): a bridge error, logged with its traceback."""
        self.fail(f"{what}: {type(exc).__name__}: {exc}", exc)


def rule_qos(spec: BridgeSpec) -> dict[str, Any]:
    """The bridge's QoS as the ROS link's keyword, on ROS 2 (ROS1 has no QoS)."""
    return {"qos": spec.qos} if ROS2 else {}


class SimToRos(Bridge):
    """Sim topic -> converter -> ROS publisher (and/or tf). Lazy bridges follow their ROS subscribers."""

    def __init__(self, spec: BridgeSpec, parts: BridgeParts) -> None:
        super().__init__(spec, parts)
        self.convert = registry.get(spec.converter)
        self.publisher: Any = None
        self._attached = False
        self._stopped = False
        self._lock = threading.Lock()
        self._min_period = 1.0 / spec.options.rate_limit_hz if spec.options.rate_limit_hz else 0.0
        self._last_publish = -1e9
        self.topic = spec.sim
        # Lazy and "fresh": after attaching, messages taken before this simulator time (ns) are dropped.
        self._fresh_after = 0
        # The stamp of the last transform sent: tf listeners refuse another at the same time (a robot reset
        # while the simulation is paused) with a TF_REPEATED_DATA warning each, so it is not sent.
        self._tf_stamp: Any = None

    @property
    def lazy(self) -> bool:
        return self.spec.options.lazy and self.spec.ros is not None

    def start(self) -> None:
        spec = self.spec
        if spec.ros is not None:
            self.publisher = self.parts.ros.publisher(
                spec.ros,
                spec.ros_type,
                queue_size=spec.options.queue_size,
                latch=spec.options.latch,
                on_peers=self._peers_changed if self.lazy else None,
                **rule_qos(spec),
            )
        if self.lazy:
            self._peers_changed()
        else:
            self._set_attached(True)

    def _peers_changed(self) -> None:
        publisher = self.publisher
        if publisher is not None and not self._stopped:
            self._set_attached(publisher.get_num_connections() > 0)

    def _set_attached(self, attached: bool) -> None:
        with self._lock:
            if self._stopped and attached:
                return
            if attached == self._attached or self.topic is None:
                return
            self._attached = attached
            if attached:
                if self.lazy and self.spec.options.first_message == "fresh":
                    self._fresh_after = self.parts.hub.sim_now()
                self.parts.hub.attach(self.topic, self.handle, inline=self.info.inline)
            else:
                self.parts.hub.detach(self.topic, self.handle)

    def handle(self, message: Any) -> list | None:
        """Convert one sim message, publish it; return the transforms it produces."""
        if self._fresh_after and self._stale(message):
            return None
        now = time.monotonic()
        if self._min_period and now - self._last_publish < self._min_period:
            return None
        try:
            out = self.convert(message, self.ctx)
        except ConversionError as exc:
            if isinstance(exc, OversizedData):
                self.parts.counts.oversized += 1
            self.fail(f"dropped a message from {self.topic}: {exc}")
            return None
        except Exception as exc:  # the stream and the node go on
            self.failed(f"converting a message from {self.topic} failed", exc)
            return None
        if out is None:
            return None
        self._last_publish = now
        if self._stopped:  # stopped while this message was being converted
            return None
        publisher = self.publisher
        if publisher is not None:
            try:
                publish(publisher, out)
            except ClosedEndpoint:  # unregistered by a concurrent stop
                return None
        self.stats.messages += 1
        self.stats.last_time = now
        header = getattr(out, "header", None)
        if header is not None:
            self.stats.last_stamp = header.stamp
        if self.spec.tf is None or not self.parts.ros.tf_wanted():
            return None
        try:
            transform = self._transform(out, message)
        except (ConversionError, KeyError, TypeError, AttributeError) as exc:  # no usable pose in it
            self.fail(f"no transform from a message on {self.topic}: {type(exc).__name__}: {exc}")
            return None
        stamp = transform.header.stamp
        if stamp == self._tf_stamp:
            return None
        self._tf_stamp = stamp
        return [transform]

    def new_session(self) -> None:
        """The simulator's time started over: a stale filter waiting for the old time stops waiting, and
        the next transform is sent whatever its stamp."""
        self._fresh_after = 0
        self._tf_stamp = None

    def _stale(self, message: Any) -> bool:
        """A message taken before the bridge attached (the simulator's cached last frame): dropped and
        counted. The first message taken since ends the check."""
        stamp = message.get("time_stamp") if isinstance(message, dict) else None
        if isinstance(stamp, int) and stamp < self._fresh_after:
            self.stats.stale_dropped += 1
            return True
        self._fresh_after = 0
        return False

    def _transform(self, out: Any, message: Any) -> Any:
        tf = self.spec.tf
        if hasattr(out, "pose") and hasattr(out.pose, "position"):  # a PoseStamped output
            return transform_from_pose(out, tf.parent, tf.child)
        # Otherwise the sensor message carries its own world pose under "pose".
        pose_msg = {"time_stamp": message.get("time_stamp", 0), **message["pose"]}
        pose = registry.get("pose")(pose_msg, self.ctx)
        return transform_from_pose(pose, tf.parent, tf.child)

    def stop(self) -> None:
        self._set_attached(False)
        self._stopped = True
        # The publisher's peer listener is a method of this bridge: dropped, the stopped bridge is freed by
        # reference counting (a cycle would outlive it in the frozen heap, engine/process_tuning.py)
        publisher, self.publisher = self.publisher, None
        if publisher is not None:
            publisher.unregister()


def _accepted(result: Any) -> bool:
    return result is not False and result is not None


class StreamingImage(SimToRos):
    """`/airsim_streaming_camera/image_raw`: the scene image of the active streaming camera."""

    def __init__(self, spec: BridgeSpec, parts: BridgeParts) -> None:
        super().__init__(spec, parts)
        self.cameras = list(spec.source.get("cameras", []))
        self.active = 0
        self.topic = self.cameras[0]["sim"] if self.cameras else None

    def start(self) -> None:
        super().start()
        self.parts.streaming.append(self)

    def stop(self) -> None:
        if self in self.parts.streaming:
            self.parts.streaming.remove(self)
        super().stop()

    def next_camera(self) -> None:
        if len(self.cameras) < 2:
            return
        with self._lock:
            was_attached = self._attached
        self._set_attached(False)
        self.active = (self.active + 1) % len(self.cameras)
        camera = self.cameras[self.active]
        self.topic = camera["sim"]
        if camera.get("frame_id") is not None:
            self.ctx = dataclasses.replace(self.ctx, frame_id=camera["frame_id"])
        if was_attached:
            self._set_attached(True)


# The robot at the world origin, level: what a mount's converter composes to give the mount itself.
ROBOT_AT_ORIGIN = {
    "time_stamp": 0,
    "position": {"x": 0.0, "y": 0.0, "z": 0.0},
    "orientation": {"w": 1.0, "x": 0.0, "y": 0.0, "z": 0.0},
}


class MountTransform(Bridge):
    """A frame mounted on a robot (a camera's, a sensor's), on /tf_static relative to the robot's frame.

    For a rule with `tf: {static: true}`: the transform is sent once at start and again whenever a camera
    pose command moves the camera, never per pose message. It is what the rule's converter gives for the
    robot at the world origin, taken relative to the robot's own pose there (the `pose` converter's, in the
    same convention), so map -> robot (the robot's pose) -> mount is the frame the converter gives per pose.
    """

    def __init__(self, spec: BridgeSpec, parts: BridgeParts) -> None:
        super().__init__(spec, parts)
        self.convert = registry.get(spec.converter)
        variables = spec.variables
        self.key = camera_pose_key(variables.get("robot_name"), variables.get("camera_name"))

    def start(self) -> None:
        self.parts.mounts.listen(self.key, self.send)
        self.send()

    def send(self) -> None:
        try:
            transform = self._transform()
        except ConversionError as exc:
            self.fail(f"no static transform for {self.spec.tf.child}: {exc}")
            return
        self.parts.ros.set_static_tf(transform)
        self.stats.messages += 1
        self.stats.last_time = time.monotonic()

    def _transform(self) -> Any:
        robot = registry.get("pose")(ROBOT_AT_ORIGIN, self.ctx).pose
        mount = self.convert(ROBOT_AT_ORIGIN, self.ctx).pose
        robot_q = _wxyz(robot.orientation)
        inverse = q_conjugate(robot_q)
        offset = [getattr(mount.position, a) - getattr(robot.position, a) for a in "xyz"]
        position = q_rotate(inverse, offset)
        q = q_mul(inverse, _wxyz(mount.orientation))
        t = TransformStamped()
        t.header.stamp = self.parts.ros.now()
        t.header.frame_id, t.child_frame_id = self.spec.tf.parent, self.spec.tf.child
        translation, rotation = t.transform.translation, t.transform.rotation
        translation.x, translation.y, translation.z = position
        rotation.w, rotation.x, rotation.y, rotation.z = q
        return t

    def stop(self) -> None:
        self.parts.mounts.unlisten(self.key, self.send)
        self.parts.ros.remove_static_tf(self.spec.tf.child)


def _wxyz(q: Any) -> tuple[float, float, float, float]:
    return (q.w, q.x, q.y, q.z)


def remember_camera_pose(bridge: Bridge, params: dict, _result: Any) -> None:
    """A camera pose command took effect: the camera's pose and image frames follow it."""
    from airsim_mapper.convert.pose import camera_pose_override

    variables = bridge.spec.variables
    key = camera_pose_key(variables.get("robot_name"), variables.get("camera_name"))
    bridge.parts.mounts.set(key, camera_pose_override(params))


def next_streaming_camera(bridge: Bridge, _params: dict, _result: Any) -> None:
    """The simulator switched its streaming view: the streaming image follows the next camera."""
    for streaming in bridge.parts.streaming:
        streaming.next_camera()


AFTER_HOOKS: dict[str, Callable[[Bridge, dict, Any], None]] = {
    "remember_camera_pose": remember_camera_pose,
    "next_streaming_camera": next_streaming_camera,
}
