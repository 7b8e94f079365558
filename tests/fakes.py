"""Fake links for engine unit tests: a simulator link and a ROS link that record what the runners do.

They implement the interfaces the runners and the engine use (engine/sim_link.SimLink and
engine/ros_link.RosLink), so the engine runs in-process without a simulator or a ROS master.
"""

from __future__ import annotations

import concurrent.futures
import json
import threading
import types
from dataclasses import dataclass, field
from typing import Any

import genpy
from harness import SIM_CONFIG

from airsim_mapper.engine.ros_link import ClosedEndpoint, FrameUnknown, message_class

IMU_MESSAGE = {  # a simulator IMU message, as the receive loop decodes it
    "time_stamp": 5_000_000_000,
    "orientation": {"w": 1.0, "x": 0.0, "y": 0.0, "z": 0.0},
    "angular_velocity": {"x": 0.1, "y": 0.0, "z": 0.0},
    "linear_acceleration": {"x": 0.0, "y": 0.0, "z": -9.8},
}


def fake_client() -> Any:
    """What the engine touches of a projectairsim client when the link is fake."""
    return types.SimpleNamespace(socket_topics=None, socket_services=None, subs={}, topics={}, state=True)


@dataclass
class FakeSimLink:
    """The simulator link: every call answers `result`; topics are delivered by `deliver`."""

    client: Any = None
    counts: Any = None  # the engine's FrameCounts
    result: Any = True
    answering: bool = True  # probes are answered
    dropped: bool = False  # the connection dropped
    dead: bool = False
    bad_frames: int = 0
    fast_frames: int = 0
    calls: list[tuple[str, dict]] = field(default_factory=list)
    published: list[tuple[str, dict]] = field(default_factory=list)
    subscriptions: dict[str, list] = field(default_factory=dict)
    closed: bool = False

    def __post_init__(self) -> None:
        self.lock = threading.Lock()

    def ensure_receiver(self) -> bool:
        return False

    def connected(self) -> bool:
        return not self.dead and not self.dropped

    def probe(self, timeout: float) -> bool:
        return self.answering

    def mark_dead(self) -> None:
        self.dead = True

    def abandon(self) -> None:
        self.dead = self.closed = True

    def subscribe(self, topic: str, callback: Any) -> None:
        with self.lock:
            self.subscriptions.setdefault(topic, []).append(callback)

    def unsubscribe(self, topic: str, callback: Any) -> None:
        with self.lock:
            callbacks = [cb for cb in self.subscriptions.get(topic, []) if cb != callback]
            if callbacks:
                self.subscriptions[topic] = callbacks
            else:
                self.subscriptions.pop(topic, None)

    def forget_all(self) -> None:
        with self.lock:
            self.subscriptions.clear()

    def deliver(self, topic: str, message: Any) -> int:
        """Hand a message to every callback on `topic`, as the receive loop would; how many got it."""
        with self.lock:
            callbacks = list(self.subscriptions.get(topic, []))
        for callback in callbacks:
            callback(types.SimpleNamespace(path=topic), message)
        return len(callbacks)

    def publish(self, topic: str, message: dict) -> None:
        self.published.append((topic, message))

    def call(self, method: str, params: dict, timeout: float = 30.0) -> Any:
        self.calls.append((method, params))
        return self.result

    def call_async(self, method: str, params: dict) -> concurrent.futures.Future:
        future: concurrent.futures.Future = concurrent.futures.Future()
        future.set_result(self.call(method, params))
        return future

    def begin_close(self) -> None:
        pass

    def close(self, timeout: float = 10.0, client_topics: bool = False) -> bool:
        self.closed = True
        return True

    def stop_loop(self) -> None:
        pass


@dataclass
class FakePublisher:
    name: str
    ros_type: str
    latch: bool
    on_peers: Any
    messages: list = field(default_factory=list)
    connections: int = 0
    unregistered: bool = False

    def publish(self, message: Any) -> None:
        if self.unregistered:
            raise ClosedEndpoint(f"publish() to an unregistered publisher {self.name}")
        self.messages.append(message)

    def get_num_connections(self) -> int:
        return self.connections

    def unregister(self) -> None:
        self.unregistered = True
        self.on_peers = None  # rospy's publisher forgets its listeners when it closes

    def subscribers(self, count: int) -> None:
        """`count` subscribers are connected now (the peer listener fires, as rospy's would)."""
        self.connections = count
        if self.on_peers is not None:
            self.on_peers()


@dataclass
class FakeEndpoint:
    name: str
    handler: Any
    closed: bool = False

    def unregister(self) -> None:
        self.closed = True

    def shutdown(self) -> None:
        self.closed = True


@dataclass
class FakeRos:
    """The ROS link: publishers, subscribers and services by name, and every transform sent."""

    publishers: dict[str, FakePublisher] = field(default_factory=dict)
    subscribers: dict[str, FakeEndpoint] = field(default_factory=dict)
    services: dict[str, FakeEndpoint] = field(default_factory=dict)
    transforms: list = field(default_factory=list)
    static_transforms: dict = field(default_factory=dict)  # /tf_static, by child frame
    closed: bool = False
    tf_cleared: int = 0  # forget_tf calls
    refused: set[str] = field(default_factory=set)  # topics whose publisher fails, as rospy's may
    made: list[FakePublisher] = field(default_factory=list)  # every publisher ever made, in order
    tf_subscribed: bool = True  # /tf has a subscriber: transforms are built and sent
    params: dict = field(default_factory=dict)  # ROS parameters, by full name

    def publisher(self, name: str, ros_type: str, *, queue_size: int, latch: bool = False, on_peers=None):
        message_class(ros_type)  # the type must exist, as rospy would require
        if name in self.refused:
            raise ValueError(f"{name} is already advertised with another type")
        self.publishers[name] = FakePublisher(name, ros_type, latch, on_peers)
        self.made.append(self.publishers[name])
        return self.publishers[name]

    def subscriber(self, name: str, ros_type: str, callback: Any, *, queue_size: int) -> FakeEndpoint:
        message_class(ros_type)
        self.subscribers[name] = FakeEndpoint(name, callback)
        return self.subscribers[name]

    def service(self, name: str, srv_type: str, handler: Any) -> tuple[FakeEndpoint, type]:
        self.services[name] = FakeEndpoint(name, handler)
        return self.services[name], message_class(srv_type, "srv")._response_class

    def now(self) -> genpy.Time:
        return genpy.Time(100, 0)

    def param(self, name: str) -> Any:
        return self.params.get(name)

    def tf_wanted(self) -> bool:
        return self.tf_subscribed

    def send_tf(self, transforms: list) -> None:
        self.transforms.extend(transforms)

    def set_static_tf(self, transform: Any) -> None:
        self.static_transforms[transform.child_frame_id] = transform

    def remove_static_tf(self, child: str) -> None:
        self.static_transforms.pop(child, None)

    def forget_tf(self) -> None:
        self.tf_cleared += 1

    def transform_pose(self, pose_stamped: Any, target: str) -> Any:
        """tf knows no frames here."""
        raise FrameUnknown(pose_stamped.header.frame_id, target, "the fake ROS link has no tf")

    def close(self) -> None:
        self.closed = True


class EngineRig:
    """An engine whose every simulator link and world load is recorded."""

    def __init__(self, reconnect: bool = True, mapping: Any = None, ros_name: str | None = None) -> None:
        from airsim_mapper.engine import Engine, NodeNames, SimAccess
        from airsim_mapper.mapping.loader import load_mapping

        self.links: list[FakeSimLink] = []
        self.worlds: list[str] = []
        self.ros = FakeRos()
        self.engine = Engine(
            fake_client(),
            mapping or load_mapping("default"),
            NodeNames("node", ros=ros_name or ""),
            SimAccess(
                SIM_CONFIG,
                load_world=self._load_world,
                client_factory=fake_client if reconnect else None,
                link=self._link,
            ),
            ros=self.ros,
        )
        self.engine.start()

    def _link(self, client, counts) -> FakeSimLink:
        self.links.append(FakeSimLink(client, counts))
        return self.links[-1]

    def _load_world(self, client, scene, _path) -> str:
        self.worlds.append(scene.file)
        return f"world of {scene.file}"

    def statuses(self) -> list[dict]:
        from airsim_mapper.engine.status import status_topic

        return [json.loads(m.data) for m in self.ros.publishers[status_topic("node")].messages]
