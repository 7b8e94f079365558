"""One robot of a loaded scene: its kinematic body, its sensor streams, its ticks and its collisions.

Its service methods are in `robot_services.py` (which assembles them), `camera_services.py` and
`motion_services.py`.
"""

from __future__ import annotations

import functools
import logging
import threading
from typing import Any

import numpy as np

from airsim_mapper.simserver.motion.motion import Body
from airsim_mapper.simserver.robot.robot_params import within_world
from airsim_mapper.simserver.scene.config import RobotSpec, SceneSpec
from airsim_mapper.simserver.scene.sim_clock import SimClock
from airsim_mapper.simserver.sensors.camera_stream import CameraStream, Render
from airsim_mapper.simserver.sensors.sensor_streams import (
    InstrumentStream,
    LidarStream,
    RadarStream,
    RotorStream,
    ground_truth,
)
from airsim_mapper.simserver.wire import messages
from airsim_mapper.simserver.wire.messages import MessageError
from airsim_mapper.simserver.wire.protocol import pack_plain
from airsim_mapper.simserver.wire.services import ServiceError
from airsim_mapper.simserver.wire.topics import TopicHub
from airsim_mapper.simserver.world.world import World

LOG = logging.getLogger("airsim_mapper.simserver")
COLLISION_RADIUS_M = 0.4
COLLISION_REPEAT_NS = 100_000_000
MAX_EVENTS = 1000  # collisions kept for the next Step call
GROUND_PROBE_M = 0.1  # ground rays start this far above the body, so a body resting on a surface sees it


class RobotRuntime:
    """A robot of the running scene."""

    def __init__(
        self,
        scene: SceneSpec,
        spec: RobotSpec,
        world: World,
        hub: TopicHub,
        clock: SimClock,
        render: Render | None = None,
    ) -> None:
        self.scene, self.spec, self.world, self.hub, self.clock = scene, spec, world, hub, clock
        self.prefix = scene.robot_prefix(spec.name)
        self.body = Body(spec.position, spec.orientation, self.ground_z, spec.rover, spec.mass_kg)
        self.pose_path = f"{self.prefix}/actual_pose"
        self.collision_path = f"{self.prefix}/collision_info"
        self.last_collision_ns: int | None = None
        self.in_contact: str | None = None
        self._events: list[dict[str, Any]] = []  # collisions since the last Step call
        self._events_lock = threading.Lock()
        self.parameters: dict[int, float] = {}
        start_ns = clock.now_ns()
        self.cameras: dict[str, CameraStream] = {}
        self.scanners: list[LidarStream | RadarStream] = []
        self.instruments: list[InstrumentStream] = []
        self.getters: dict[str, InstrumentStream] = {}
        for sensor in spec.sensors:
            sensor_prefix = scene.sensor_prefix(spec.name, sensor.id)
            if sensor.type == "camera":
                self.cameras[sensor.id] = CameraStream(sensor, sensor_prefix, self.body, world, hub, render)
            elif sensor.type == "lidar":
                self.scanners.append(
                    LidarStream(sensor, sensor_prefix, self.body, world, hub, scene.clock.step_ns)
                )
            elif sensor.type == "radar":
                self.scanners.append(RadarStream(sensor, sensor_prefix, self.body, world, hub))
            else:
                stream = InstrumentStream(
                    sensor, sensor_prefix, self.body, world, hub, scene.home_geo, start_ns
                )
                self.instruments.append(stream)
                self.getters[stream.path] = stream
        self.rotors = RotorStream(f"{self.prefix}/rotor_info", dict(spec.config), self.body, hub)

    # -- world queries

    def ground_z(self, position: np.ndarray) -> float:
        """z of the first surface straight below `position` (the ground plane if the world misses)."""
        surface = self.world.surface_below((position[0], position[1], position[2] - GROUND_PROBE_M), 1000.0)
        return surface if surface is not None else 0.0

    def _blocked(self, old: np.ndarray, new: np.ndarray) -> bool:
        """Veto a move that goes deeper into an object; report the collision on collision_info."""
        contact = self.world.collide_sphere(new, COLLISION_RADIUS_M)
        if contact is None:
            self.in_contact = None
            return False
        now = self.clock.now_ns()
        if (
            self.in_contact != contact.object_name
            or self.last_collision_ns is None
            or now - self.last_collision_ns >= COLLISION_REPEAT_NS
        ):
            message = messages.collision_info(now, contact)
            self.hub.publish(self.collision_path, message)
            with self._events_lock:
                self._events.append({"type": "collision", "sim_time_ns": now, **message})
                del self._events[:-MAX_EVENTS]
            self.last_collision_ns = now
        self.in_contact = contact.object_name
        before = self.world.collide_sphere(old, COLLISION_RADIUS_M)
        return before is None or contact.penetration_depth > before.penetration_depth

    def take_events(self) -> list[dict[str, Any]]:
        with self._events_lock:
            events, self._events = self._events, []
        return events

    # -- ticking

    def tick(self, dt_s: float, now_ns: int) -> None:
        self.body.tick(dt_s, self._blocked, now_ns)

    def publish_pose(self, now_ns: int) -> None:
        position, orientation = self.body.pose()
        self.hub.publish(
            self.pose_path, pack_plain(messages.pose_stamped_dict(now_ns, position, orientation))
        )

    def step_instruments(self, now_ns: int) -> None:
        """Step every instrument on one snapshot of the body, taken when the first one is due."""
        if self.instruments:
            state = functools.cache(lambda: ground_truth(self.body))
            for stream in self.instruments:
                stream.step(now_ns, state)
        if self.spec.multirotor:
            self.rotors.step(now_ns)

    def step_cameras(self, now_ns: int) -> bool:
        """Cameras due at `now_ns`; True if any rendered."""
        worked = False
        for camera in self.cameras.values():
            worked = camera.step(now_ns) or worked
        return worked

    def step_scans(self, now_ns: int, tick_ns: int) -> bool:
        """Radars at `now_ns`; lidars scan up to the latest physics tick, `tick_ns`. True if any worked."""
        worked = False
        for stream in self.scanners:
            worked = stream.step(tick_ns if isinstance(stream, LidarStream) else now_ns) or worked
        return worked

    def start(self) -> None:
        now = self.clock.now_ns()
        self.publish_pose(now)
        for camera in self.cameras.values():
            camera.publish_infos()
        self.step_instruments(now)

    def stop(self) -> None:
        self.body.cancel()

    def on_desired_pose(self, _path: str, message: Any) -> None:
        """A client MESSAGE on desired_pose teleports the robot (an invalid one is logged and ignored)."""
        try:
            position, orientation = messages.parse_pose_stamped(message)
            within_world("position", position)
        except (MessageError, ServiceError) as exc:
            LOG.warning("ignored a desired_pose for %s: %s", self.spec.name, exc)
            return
        self.body.teleport(position, orientation, True, self.clock.now_ns())
        self.publish_pose(self.clock.now_ns())
