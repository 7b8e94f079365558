"""Kinematic robot motion: a body whose command turns into a velocity and yaw rate per tick (no aerodynamics).

A `Body` holds one robot's state and its active command (the commands are in `motion_commands.py`). A new
command pre-empts the running one, which then completes with `False`; a command completes with `True` when
it reaches its goal or duration. Time is sim time (seconds): while the clock is paused nothing moves and
nothing completes.
"""

from __future__ import annotations

import math
import threading
from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np

from airsim_mapper.common.geometry import quat_from_rpy, quat_multiply, quat_normalize

LANDED_HEIGHT_M = 0.15
MAX_WIND_MPS = 200.0  # wind speeds beyond this are refused (scene or SetWindVelocity)
# A body pushed by an external force drifts at force / mass x DRAG_TIME_S: the speed at which a linear drag
# that would stop it in about this time balances the force (the kinematic model has no aerodynamics).
DRAG_TIME_S = 1.0
DEFAULT_MASS_KG = 1.0

GroundFn = Callable[[np.ndarray], float]


def wrap_angle(angle: float) -> float:
    return (angle + math.pi) % (2 * math.pi) - math.pi


@dataclass
class Kinematic:
    """World NED state of a body: position (m), orientation (w,x,y,z), rates and accelerations."""

    position: np.ndarray
    orientation: np.ndarray
    linear_velocity: np.ndarray = field(default_factory=lambda: np.zeros(3))
    angular_velocity: np.ndarray = field(default_factory=lambda: np.zeros(3))
    linear_acceleration: np.ndarray = field(default_factory=lambda: np.zeros(3))
    angular_acceleration: np.ndarray = field(default_factory=lambda: np.zeros(3))

    def copy(self) -> Kinematic:
        return Kinematic(
            self.position.copy(),
            self.orientation.copy(),
            self.linear_velocity.copy(),
            self.angular_velocity.copy(),
            self.linear_acceleration.copy(),
            self.angular_acceleration.copy(),
        )


@dataclass
class Motion:
    """What a command wants for one tick: world velocity (m/s) and yaw rate (rad/s)."""

    velocity: np.ndarray
    yaw_rate: float = 0.0


class Command:
    """A motion command; subclasses implement `motion`. `wait` blocks the service worker until it ends."""

    name = "Command"
    duration = math.inf  # sim seconds of motion for time-boxed commands

    def __init__(self, timeout_s: float = math.inf) -> None:
        self.elapsed = 0.0
        self.timeout_s = timeout_s
        self.result: bool | None = None
        self.start_ns: int | None = None  # sim time the command was received; set by Body.run
        self._done = threading.Event()

    def motion(self, state: Kinematic, dt: float, ground_z: float) -> Motion | None:
        """The motion for this tick, or None when the goal is reached (the command succeeds)."""
        raise NotImplementedError

    def finish(self, result: bool) -> None:
        if self.result is None:
            self.result = result
            self._done.set()

    def wait(self, timeout_s: float | None = None) -> bool:
        self._done.wait(timeout_s)
        return bool(self.result)

    @property
    def done(self) -> bool:
        return self._done.is_set()


class Hold(Command):
    """Hover in place (velocity zero); completes at once."""

    name = "Hover"

    def motion(self, state: Kinematic, dt: float, ground_z: float) -> Motion | None:
        return None


class Body:
    """One robot's kinematic state, its active command and its API flags (all thread-safe)."""

    def __init__(
        self,
        position: np.ndarray,
        orientation: np.ndarray,
        ground: GroundFn,
        grounded: bool = False,
        mass_kg: float = DEFAULT_MASS_KG,
    ) -> None:
        self.lock = threading.RLock()
        self.ground = ground
        self.grounded = grounded  # a ground vehicle: it rests on the surface below it, wherever it is put
        self.state = Kinematic(self._rested(position), quat_normalize(orientation))
        self.home = self.state.position.copy()
        self.mass_kg = float(mass_kg)
        self.api_control = False
        self.armed = False
        self.active: Command | None = None
        self.placed_ns: int | None = None  # sim time of the last teleport, until a tick has passed it
        self.wind = np.zeros(3)  # world NED m/s: an idle, armed, airborne body drifts with it
        self.external_force = np.zeros(3)  # world NED N (SetExternalForce): it drifts with this too

    def _rested(self, position: np.ndarray) -> np.ndarray:
        """`position`, moved onto the surface below it for a ground vehicle."""
        position = np.array(position, dtype=float)
        if self.grounded:
            position[2] = self.ground(position)
        return position

    def drift(self) -> np.ndarray:
        """The velocity of an idle, armed, airborne body: the wind's, plus what the external force adds."""
        return self.wind + self.external_force * (DRAG_TIME_S / self.mass_kg)

    # -- commands

    def run(self, command: Command, now_ns: int | None = None) -> Command:
        """Make `command` the active one; the previous one (if running) completes with False.

        `now_ns` is the sim time the command arrived: sim time before it is not spent on it.
        """
        command.start_ns = now_ns
        with self.lock:
            previous, self.active = self.active, command
        if previous is not None:
            previous.finish(False)
        return command

    def cancel(self) -> bool:
        with self.lock:
            previous, self.active = self.active, None
        if previous is not None:
            previous.finish(False)
            return True
        return False

    def snapshot(self) -> Kinematic:
        with self.lock:
            return self.state.copy()

    def pose(self) -> tuple[list[float], list[float]]:
        """Position and orientation of one instant, as floats: a snapshot's pose without its rates."""
        with self.lock:
            return self.state.position.tolist(), self.state.orientation.tolist()

    def teleport(
        self, position: np.ndarray, orientation: np.ndarray, reset_kinematics: bool, now_ns: int | None = None
    ) -> None:
        """SetPose / desired_pose: jump there; the running command is cancelled (it replies False).

        `now_ns` is the sim time of the jump: the tick that follows moves the body only for the time since.
        """
        self.cancel()
        with self.lock:
            self.placed_ns = now_ns
            self.state.position = self._rested(position)
            self.state.orientation = quat_normalize(orientation)
            if reset_kinematics:
                for name in (
                    "linear_velocity",
                    "angular_velocity",
                    "linear_acceleration",
                    "angular_acceleration",
                ):
                    setattr(self.state, name, np.zeros(3))

    def height_above_ground(self) -> float:
        with self.lock:
            position = self.state.position.copy()
        return self.ground(position) - position[2]

    def landed(self) -> bool:
        with self.lock:
            moving = self.active is not None and not isinstance(self.active, Hold)
            speed = float(np.linalg.norm(self.state.linear_velocity))
        return not moving and speed < 0.1 and self.height_above_ground() < LANDED_HEIGHT_M

    # -- integration

    def _at_rest(self) -> bool:
        state = self.state
        return not (
            state.linear_velocity.any()
            or state.angular_velocity.any()
            or state.linear_acceleration.any()
            or state.angular_acceleration.any()
        )

    def _stop_unbounded(self, command: Command | None) -> None:
        """A step would make the state non-finite: end the command (False) and come to rest here."""
        if command is not None and self.active is command:
            self.active = None
            command.finish(False)
        for name in ("linear_velocity", "angular_velocity", "linear_acceleration", "angular_acceleration"):
            setattr(self.state, name, np.zeros(3))

    def tick(
        self,
        dt: float,
        blocked: Callable[[np.ndarray, np.ndarray], bool] | None = None,
        now_ns: int | None = None,
    ) -> None:
        """Advance by `dt` sim seconds (ending at `now_ns`); `blocked(old, new)` may veto a move."""
        if dt <= 0:
            return
        with self.lock:
            state = self.state
            command = self.active
            drift = self.drift()
            drifting = (
                command is None
                and self.armed  # a disarmed robot is held where it is, as on a stand
                and bool(np.any(drift))
                and self.ground(state.position) - state.position[2] > LANDED_HEIGHT_M
            )
            if command is None and not drifting and self._at_rest():
                return  # nothing moves: skip the world queries (an idle server stays cheap)
            if self.placed_ns is not None and now_ns is not None:
                dt = min(dt, (now_ns - self.placed_ns) / 1e9)  # time before the jump is not spent here
                if dt <= 0:
                    return
                self.placed_ns = None
            if command is not None and command.start_ns is not None and now_ns is not None:
                dt = min(dt, (now_ns - command.start_ns) / 1e9)
                if dt <= 0:
                    return
            ground_z = self.ground(state.position) if command is not None else 0.0
            motion = None
            step = dt  # the part of this tick the command's motion lasts
            if command is not None:
                if command.elapsed >= command.timeout_s:
                    self.active = None
                    command.finish(False)
                    command = None
                else:
                    motion = command.motion(state, dt, ground_z)
                    step = min(dt, max(0.0, command.duration - command.elapsed))
                    command.elapsed += dt
                    if motion is None:
                        self.active = None
                        command.finish(True)
            velocity = motion.velocity if motion is not None else drift if drifting else np.zeros(3)
            yaw_rate = motion.yaw_rate if motion is not None else 0.0
            new_position = state.position + velocity * step
            if np.any(new_position != state.position):
                # the surface below the new x, y as seen from the higher of the old and new heights
                probe = np.array([new_position[0], new_position[1], min(new_position[2], state.position[2])])
                surface = self.ground(probe)
                new_position[2] = surface if self.grounded else min(new_position[2], surface)
                if blocked is not None and blocked(state.position, new_position):
                    new_position = state.position.copy()
            with np.errstate(over="ignore", invalid="ignore"):
                actual_velocity = (new_position - state.position) / dt
                angular = np.array([0.0, 0.0, yaw_rate])
                linear_acceleration = (actual_velocity - state.linear_velocity) / dt
                angular_acceleration = (angular - state.angular_velocity) / dt
            new_state = np.concatenate((new_position, linear_acceleration, angular_acceleration))
            if not np.isfinite(new_state).all():
                self._stop_unbounded(command)  # never reached through the checked service methods
                return
            state.linear_acceleration = linear_acceleration
            state.angular_acceleration = angular_acceleration
            state.linear_velocity = actual_velocity
            state.angular_velocity = angular
            state.position = new_position
            if yaw_rate:
                state.orientation = quat_normalize(
                    quat_multiply(quat_from_rpy(0.0, 0.0, yaw_rate * step), state.orientation)
                )
