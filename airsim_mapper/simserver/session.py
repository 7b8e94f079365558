"""A loaded scene: its clock, robots, scene-level service methods and topic handlers."""

from __future__ import annotations

import math
import threading
from typing import Any

import numpy as np

from airsim_mapper.simserver.robot.robot_services import robot_methods
from airsim_mapper.simserver.robot.robots import RobotRuntime
from airsim_mapper.simserver.scene.config import SceneSpec
from airsim_mapper.simserver.scene.env_actors import TRAJECTORY_OFFSETS, EnvActors
from airsim_mapper.simserver.scene.geo import EARTH_RADIUS_M
from airsim_mapper.simserver.scene.objects import LiveWorld, Pose, SceneObjects
from airsim_mapper.simserver.scene.sim_clock import SimClock
from airsim_mapper.simserver.scene.topic_table import topic_table
from airsim_mapper.simserver.scene.visual_noops import VisualSettings
from airsim_mapper.simserver.sensors.camera_stream import Render
from airsim_mapper.simserver.wire import messages
from airsim_mapper.simserver.wire.services import Method, ServiceError
from airsim_mapper.simserver.wire.topics import TopicHub, TopicInfo
from airsim_mapper.simserver.world.world import World

GEO_KEYS = ("latitudes", "longitudes", "altitudes")
GEO_ANGLES = ("pose_roll", "pose_pitch", "pose_yaw")
TRAJECTORY_KEYS = (
    "time",
    "pose_x",
    "pose_y",
    "pose_z",
    "pose_roll",
    "pose_pitch",
    "pose_yaw",
    "vel_x_lin",
    "vel_y_lin",
    "vel_z_lin",
)


class TrajectoryStore:
    """Imported NED trajectories by name; importing an existing name again returns False."""

    def __init__(self) -> None:
        self._lock = threading.Lock()
        self._items: dict[str, dict[str, list[float]]] = {}

    def import_ned(self, params: dict[str, Any]) -> bool:
        name = str(params["traj_name"])
        lengths = {len(params[k]) if isinstance(params[k], list) else -1 for k in TRAJECTORY_KEYS}
        if len(lengths) != 1 or -1 in lengths:
            raise ServiceError(
                f"trajectory '{name}' needs lists of equal length for {', '.join(TRAJECTORY_KEYS)}"
            )
        with self._lock:
            if name in self._items:
                return False
            self._items[name] = {k: [float(v) for v in params[k]] for k in TRAJECTORY_KEYS}
            return True

    def import_geo(self, params: dict[str, Any], home: tuple[float, float, float]) -> bool:
        """ImportGeoCoordinates / ImportGeoTrajectory: geo points become NED (flat earth at home)."""
        keys = ("latitudes", "longitudes", "altitudes")
        try:
            lat, lon, alt = (np.asarray(params[k], dtype=float).reshape(-1) for k in keys)
        except (TypeError, ValueError) as exc:
            raise ServiceError(
                f"latitudes, longitudes and altitudes must be lists of numbers ({exc})"
            ) from None
        if not (lat.size == lon.size == alt.size):
            raise ServiceError("latitudes, longitudes and altitudes must have equal lengths")
        north = np.radians(lat - home[0]) * EARTH_RADIUS_M
        east = np.radians(lon - home[1]) * EARTH_RADIUS_M * math.cos(math.radians(home[0]))
        zeros = [0.0] * lat.size
        ned = {
            "traj_name": params["traj_name"],
            "pose_x": north.tolist(),
            "pose_y": east.tolist(),
            "pose_z": (home[2] - alt).tolist(),
            **{k: params.get(k, zeros) for k in ("pose_roll", "pose_pitch", "pose_yaw")},
            **{k: params[k] for k in ("time", "vel_x_lin", "vel_y_lin", "vel_z_lin")},
        }
        return self.import_ned(ned)

    def get(self, name: str) -> dict[str, list[float]] | None:
        with self._lock:
            return self._items.get(name)


class Session:
    """Everything that exists while one scene is loaded."""

    def __init__(self, spec: SceneSpec, world: World, hub: TopicHub, render: Render | None = None) -> None:
        self.spec = spec
        self.hub = hub
        self.clock = SimClock(spec.clock.type, spec.clock.step_ns, spec.clock.pause_on_start, lock_step=True)
        self.world = world = world if isinstance(world, LiveWorld) else LiveWorld(world)
        self.robots = {r.name: RobotRuntime(spec, r, world, hub, self.clock, render) for r in spec.robots}
        self.trajectories = TrajectoryStore()
        self.env_actors = EnvActors(spec.env_actors, spec.prefix, self.trajectories, self.clock.now_ns())
        self.objects = SceneObjects(self.world, self._actor_poses, spec.home_geo)
        self.visuals = VisualSettings(self._set_wind, list(spec.wind))
        self._set_wind(list(spec.wind))
        self.last_tick_ns = self.clock.now_ns()
        self.started_ns = self.last_tick_ns
        self.last_pose_ns = self.last_tick_ns  # `start` publishes the first pose at this time

    def topics(self) -> list[TopicInfo]:
        return topic_table(self.spec)

    def topic_handlers(self) -> dict[str, Any]:
        return {f"{r.prefix}/desired_pose": r.on_desired_pose for r in self.robots.values()}

    def methods(self) -> list[Method]:
        p = self.spec.prefix
        clock = self.clock
        table = [
            Method(f"{p}/GetSimClockType", (), lambda _: clock.kind),
            Method(f"{p}/GetSimTime", (), lambda _: clock.now_ns()),
            Method(f"{p}/Pause", ("do_pause",), lambda a: clock.pause(bool(a["do_pause"]))),
            Method(f"{p}/IsPaused", (), lambda _: clock.is_paused()),
            Method(
                f"{p}/ContinueForSimTime",
                ("delta_time", "wait_until_complete"),
                lambda a: clock.continue_for(int(a["delta_time"]), bool(a["wait_until_complete"])),
            ),
            Method(
                f"{p}/ContinueUntilSimTime",
                ("target_time", "wait_until_complete"),
                lambda a: clock.continue_until(int(a["target_time"]), bool(a["wait_until_complete"])),
            ),
            Method(
                f"{p}/ContinueForNSteps",
                ("n_steps", "wait_until_complete"),
                lambda a: clock.continue_for(
                    int(a["n_steps"]) * clock.step_ns, bool(a["wait_until_complete"]), "ContinueForNSteps"
                ),
            ),
            Method(
                f"{p}/ContinueForSingleStep",
                ("wait_until_complete",),
                lambda a: clock.continue_for(
                    clock.step_ns, bool(a["wait_until_complete"]), "ContinueForSingleStep"
                ),
            ),
            Method(f"{p}/ListActors", (), lambda _: list(self.robots)),
            Method(f"{p}/ImportNEDTrajectory", ("traj_name", *TRAJECTORY_KEYS), self.trajectories.import_ned),
            Method(f"{p}/SwitchStreamingView", (), lambda _: True),
            Method(f"{p}/Step", ("dt_ns",), self.step),
            Method(
                f"{p}/ImportGeoCoordinates",
                ("traj_name", "time", *GEO_KEYS, "vel_x_lin", "vel_y_lin", "vel_z_lin"),
                lambda a: self.trajectories.import_geo(a, self.spec.home_geo),
            ),
            Method(
                f"{p}/ImportGeoTrajectory",
                ("traj_name", "time", *GEO_KEYS, *GEO_ANGLES, "vel_x_lin", "vel_y_lin", "vel_z_lin"),
                lambda a: self.trajectories.import_geo(a, self.spec.home_geo),
            ),
            Method(
                f"{p}/SetEnvActorTrajectory",
                ("env_actor_name", "traj_name", *TRAJECTORY_OFFSETS, "to_loop"),
                lambda a: self.env_actors.set_trajectory(a, clock.now_ns()),
            ),
            Method(
                f"{p}/SetEnvActorLinkRotAngle",
                ("env_actor_name", "link_name", "angle_deg"),
                self.env_actors.set_link_angle,
            ),
            Method(
                f"{p}/SetEnvActorLinkRotRate",
                ("env_actor_name", "link_name", "rotation_deg_per_sec"),
                self.env_actors.set_link_rate,
            ),
        ]
        table += self.visuals.methods(p)
        table += self.objects.methods(p)
        for robot in self.robots.values():
            table += robot_methods(robot)
        return table

    def _actor_poses(self) -> dict[str, Pose]:
        """Every robot's and env actor's pose now, by name (the actors of ListObjects and GetObjectPose)."""
        poses = {}
        for name, robot in self.robots.items():
            kin = robot.body.snapshot()
            poses[name] = (kin.position, kin.orientation)
        now = self.clock.now_ns()
        for name, actor in self.env_actors.actors.items():
            poses[name] = actor.state(now)[:2]
        return poses

    def _set_wind(self, wind: list[float]) -> None:
        for robot in self.robots.values():
            with robot.body.lock:
                robot.body.wind = np.array(wind, dtype=float)

    def step(self, params: dict[str, Any]) -> dict[str, Any]:
        """The 1.1.0 `Step(dt_ns)`: advance the steppable clock and return each robot's state and events.

        Events are the collisions published since the previous Step, oldest first.
        """
        dt_ns = params["dt_ns"]
        if isinstance(dt_ns, bool) or not isinstance(dt_ns, int) or dt_ns < 0:
            raise ServiceError(f"Parameter 'dt_ns' must be a non-negative integer, got {dt_ns!r}", code=2.0)
        now = self.clock.continue_for(dt_ns, True, "Step")
        robots = {}
        for name, robot in self.robots.items():
            kin = robot.body.snapshot()
            robots[name] = {
                "state": {
                    "position": messages.vector3(kin.position),
                    "orientation": messages.quaternion(kin.orientation),
                    "linear_velocity": messages.vector3(kin.linear_velocity),
                    "angular_velocity": messages.vector3(kin.angular_velocity),
                },
                "events": robot.take_events(),
            }
        return {"sim_time_ns": now, "robots": robots}

    # -- running

    def start(self) -> None:
        for robot in self.robots.values():
            robot.start()

    def stop(self) -> None:
        self.clock.cancel_stepping()
        for robot in self.robots.values():
            robot.stop()

    def tick(self, publish_pose: bool) -> None:
        """Simulation thread: integrate motion by the sim time elapsed, publish pose and instruments.

        A pose goes out only for a new sim time, as the real server publishes one per physics tick: a
        paused clock sends none, and a lock-step step sends one (a teleport publishes its own).
        """
        now = self.clock.now_ns()
        dt = (now - self.last_tick_ns) / 1e9
        self.last_tick_ns = now
        publish_pose = publish_pose and now != self.last_pose_ns
        if publish_pose:
            self.last_pose_ns = now
        for robot in self.robots.values():
            robot.tick(dt, now)
            if publish_pose:
                robot.publish_pose(now)
            robot.step_instruments(now)
        if publish_pose and self.env_actors.actors:
            self.env_actors.publish(self.hub, now)

    def camera_tick(self) -> bool:
        """Camera thread: render what is due; True if anything was rendered."""
        now = self.clock.now_ns()
        return any([robot.step_cameras(now) for robot in self.robots.values()])

    def scan_tick(self) -> bool:
        """Scan thread: lidar and radar samples that are due; True if anything was scanned."""
        now, tick = self.clock.now_ns(), self.last_tick_ns
        return any([robot.step_scans(now, tick) for robot in self.robots.values()])
