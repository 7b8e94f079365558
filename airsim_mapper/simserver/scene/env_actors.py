"""Environment actors: the scene's `environment-actors`, moved along imported trajectories.

`SetEnvActorTrajectory` makes an actor follow a trajectory imported with `ImportNEDTrajectory` (or the
geo variants), shifted by the call's offsets and optionally looped; an unknown trajectory name makes it
reply false and keep the trajectory it had, as the real server does. An actor whose config has a `script`
follows that trajectory from the scene's start, on sim time (core_sim `EnvActor::LoadEnvActorScript`): the
trajectory is imported under its own name, so other actors can be set to it. Its pose is interpolated linearly
over sim time and published on `<scene>/env_actors/<name>/actual_kinematics` (the Kinematics topic form,
protocol.md §5.2). Link rotations (`SetEnvActorLinkRotAngle`, `SetEnvActorLinkRotRate`) are kept per link:
the headless world has no link geometry for them to move.
"""

from __future__ import annotations

import logging
import math
import threading
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from airsim_mapper.common.geometry import quat_from_rpy, quat_multiply
from airsim_mapper.simserver.wire import messages
from airsim_mapper.simserver.wire.services import ServiceError

LOG = logging.getLogger("airsim_mapper.simserver.env_actors")

ENV_ACTOR_TYPES = ("env_actor", "env_car", "env_human")


# a script trajectory's keys (core_sim `Trajectory::Loader`) by the ImportNEDTrajectory key each fills
SCRIPT_KEYS = {
    "time": "time_sec",
    "pose_x": "pose_x",
    "pose_y": "pose_y",
    "pose_z": "pose_z",
    "pose_roll": "pose_roll",
    "pose_pitch": "pose_pitch",
    "pose_yaw": "pose_yaw",
    "vel_x_lin": "velocity_linear_x",
    "vel_y_lin": "velocity_linear_y",
    "vel_z_lin": "velocity_linear_z",
}
SCRIPT_REQUIRED = ("time_sec", "pose_x", "pose_y", "pose_z")


@dataclass(frozen=True)
class ActorScript:
    """An env actor config's `script`: a named trajectory (ImportNEDTrajectory's columns), and `loop`.

    `auto_start` is read and, as in the real server ("not used currently"), changes nothing: the actor
    follows its script from the scene's start."""

    name: str
    columns: Mapping[str, tuple[float, ...]]
    loop: bool
    auto_start: bool = True


def actor_script(config: Any, where: str, error: type[Exception]) -> ActorScript | None:
    """The `script` of an env actor config, or None without one; `error(message)` for a malformed one."""
    script = config.get("script") if isinstance(config, Mapping) else None
    if not script:
        return None
    trajectory = script.get("trajectory") if isinstance(script, Mapping) else None
    if not isinstance(trajectory, Mapping):
        raise error(f"{where} 'script' must have a 'trajectory' object")
    name = trajectory.get("name")
    if not isinstance(name, str) or not name:
        raise error(f"{where} script trajectory must have a non-empty 'name'")
    for key in SCRIPT_REQUIRED:
        if key not in trajectory:
            raise error(f"{where} script trajectory '{name}' has no '{key}'")
    length = len(trajectory["time_sec"]) if isinstance(trajectory["time_sec"], list) else -1
    columns = {}
    for column, key in SCRIPT_KEYS.items():
        values = trajectory.get(key, [0.0] * max(length, 0))
        finite = isinstance(values, list) and all(
            not isinstance(v, bool) and isinstance(v, (int, float)) and math.isfinite(v) for v in values
        )
        if not finite or len(values) != length or length == 0:
            raise error(
                f"{where} script trajectory '{name}' '{key}' must be a list of {max(length, 1)} numbers "
                "(as long as 'time_sec')"
            )
        columns[column] = tuple(float(v) for v in values)
    return ActorScript(name, columns, bool(script.get("loop", False)), bool(script.get("auto_start", True)))


@dataclass(frozen=True)
class EnvActorSpec:
    name: str
    position: np.ndarray
    orientation: np.ndarray
    links: tuple[str, ...] = ()
    script: ActorScript | None = None


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

    def __init__(
        self, specs: tuple[EnvActorSpec, ...], prefix: str, trajectories: Any, start_ns: int = 0
    ) -> None:
        self.prefix = prefix
        self.actors = {s.name: EnvActor(s) for s in specs}
        self.trajectories = trajectories
        self._lock = threading.Lock()
        for spec in specs:
            if spec.script is not None:
                self._follow_script(self.actors[spec.name], spec.script, start_ns)

    def _follow_script(self, actor: EnvActor, script: ActorScript, start_ns: int) -> None:
        """Import the script's trajectory (unless one of that name is there) and follow it from the scene's
        start: trajectory time t is `t` seconds after the scene started."""
        self.trajectories.import_ned(
            {"traj_name": script.name, **{k: list(v) for k, v in script.columns.items()}}
        )
        columns = self.trajectories.get(script.name)
        arrays = {k: np.asarray(v, dtype=float) for k, v in columns.items()}
        first = float(arrays["time"][0])
        actor.trajectory = FollowedTrajectory(
            arrays["time"], arrays, start_ns, -first, np.zeros(3), np.zeros(3), script.loop
        )

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
            LOG.warning(
                "SetTrajectory failed for EnvActor '%s'. The trajectory '%s' was not found. The previous "
                "trajectory will be used.",
                actor.spec.name,
                name,
            )
            return False
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
