"""Environment actors: the scene's `environment-actors`, moved along imported trajectories.

`SetEnvActorTrajectory` makes an actor follow a trajectory imported with `ImportNEDTrajectory` (or the
geo variants), shifted by the call's offsets and optionally looped; its pose is interpolated linearly
over sim time and published on `<scene>/env_actors/<name>/actual_kinematics` (the Kinematics topic form,
protocol.md §5.2). Link rotations (`SetEnvActorLinkRotAngle`, `SetEnvActorLinkRotRate`) are kept per link:
the headless world has no link geometry for them to move.
"""

from __future__ import annotations

import math
import threading
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from airsim_mapper.geometry import quat_from_rpy, quat_multiply
from airsim_mapper.simserver import messages
from airsim_mapper.simserver.services import ServiceError

ENV_ACTOR_TYPES = ("env_actor", "env_car", "env_human")


@dataclass(frozen=True)
class EnvActorSpec:
    name: str
    position: np.ndarray
    orientation: np.ndarray
    links: tuple[str, ...] = ()


@dataclass
class FollowedTrajectory:
    """A trajectory (columns of the NED import) with the offsets and loop flag it was set with."""

    time: np.ndarray
    columns: dict[str, np.ndarray]
    start_ns: int
    time_offset: float
    offset: np.ndarray
    rpy_offset: np.ndarray
    loop: bool

    def sample(self, now_ns: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Position, orientation and linear velocity at sim time `now_ns`."""
        t = (now_ns - self.start_ns) / 1e9 + self.time_offset + float(self.time[0])
        if self.loop and self.time[-1] > self.time[0]:
            t = self.time[0] + (t - self.time[0]) % (self.time[-1] - self.time[0])
        c = self.columns

        def at(key: str) -> float:
            return float(np.interp(t, self.time, c[key]))

        position = np.array([at("pose_x"), at("pose_y"), at("pose_z")]) + self.offset
        rpy = np.array([at("pose_roll"), at("pose_pitch"), at("pose_yaw")]) + self.rpy_offset
        velocity = np.array([at("vel_x_lin"), at("vel_y_lin"), at("vel_z_lin")])
        return position, quat_from_rpy(*rpy), velocity


@dataclass
class EnvActor:
    spec: EnvActorSpec
    link_angles_deg: dict[str, float] = field(default_factory=dict)
    link_rates_deg_s: dict[str, float] = field(default_factory=dict)
    trajectory: FollowedTrajectory | None = None

    def state(self, now_ns: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        if self.trajectory is None:
            return self.spec.position.copy(), self.spec.orientation.copy(), np.zeros(3)
        position, orientation, velocity = self.trajectory.sample(now_ns)
        return position, quat_multiply(orientation, self.spec.orientation), velocity


def kinematics_message(now_ns: int, position: np.ndarray, orientation: np.ndarray, velocity: np.ndarray):
    """The Kinematics topic form: `{time_stamp, kinematics: {pose, twist, accels}}`."""
    zero = messages.vector3(np.zeros(3))
    return {
        "time_stamp": int(now_ns),
        "kinematics": {
            "pose": messages.pose(position, orientation),
            "twist": {"linear": messages.vector3(velocity), "angular": zero},
            "accels": {"linear": zero, "angular": zero},
        },
    }


class EnvActors:
    """The env actors of one scene and their scene-level service methods."""

    def __init__(self, specs: tuple[EnvActorSpec, ...], prefix: str, trajectories: Any) -> None:
        self.prefix = prefix
        self.actors = {s.name: EnvActor(s) for s in specs}
        self.trajectories = trajectories
        self._lock = threading.Lock()

    def topic(self, name: str) -> str:
        return f"{self.prefix}/env_actors/{name}/actual_kinematics"

    def _actor(self, params: Mapping[str, Any]) -> EnvActor:
        name = str(params["env_actor_name"])
        actor = self.actors.get(name)
        if actor is None:
            raise ServiceError(f"Env actor '{name}' not found in the scene")
        return actor

    def _link(self, actor: EnvActor, params: Mapping[str, Any]) -> str:
        link = str(params["link_name"])
        if actor.spec.links and link not in actor.spec.links:
            raise ServiceError(f"Env actor '{actor.spec.name}' has no link '{link}'")
        return link

    @staticmethod
    def _finite(params: Mapping[str, Any], key: str) -> float:
        value = params[key]
        if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
            raise ServiceError(f"Parameter '{key}' must be a finite number, got {value!r}", code=2.0)
        return float(value)

    def set_link_angle(self, params: Mapping[str, Any]) -> bool:
        actor = self._actor(params)
        with self._lock:
            actor.link_angles_deg[self._link(actor, params)] = self._finite(params, "angle_deg")
        return True

    def set_link_rate(self, params: Mapping[str, Any]) -> bool:
        actor = self._actor(params)
        with self._lock:
            actor.link_rates_deg_s[self._link(actor, params)] = self._finite(params, "rotation_deg_per_sec")
        return True

    def set_trajectory(self, params: Mapping[str, Any], now_ns: int) -> bool:
        actor = self._actor(params)
        name = str(params["traj_name"])
        columns = self.trajectories.get(name)
        if columns is None:
            raise ServiceError(f"Trajectory '{name}' has not been imported")
        f = {k: self._finite(params, k) for k in TRAJECTORY_OFFSETS}
        arrays = {k: np.asarray(v, dtype=float) for k, v in columns.items()}
        if arrays["time"].size == 0:
            raise ServiceError(f"Trajectory '{name}' is empty")
        with self._lock:
            actor.trajectory = FollowedTrajectory(
                arrays["time"],
                arrays,
                now_ns,
                f["time_offset"],
                np.array([f["x_offset"], f["y_offset"], f["z_offset"]]),
                np.array([f["roll_offset"], f["pitch_offset"], f["yaw_offset"]]),
                bool(params["to_loop"]),
            )
        return True

    def publish(self, hub: Any, now_ns: int) -> None:
        with self._lock:
            states = [(name, actor.state(now_ns)) for name, actor in self.actors.items()]
        for name, (position, orientation, velocity) in states:
            hub.publish(self.topic(name), kinematics_message(now_ns, position, orientation, velocity))


TRAJECTORY_OFFSETS = (
    "time_offset",
    "x_offset",
    "y_offset",
    "z_offset",
    "roll_offset",
    "pitch_offset",
    "yaw_offset",
)
