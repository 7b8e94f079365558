"""The motion commands of multirotors and rovers: each turns into a velocity and a yaw rate per tick.

A command runs on a `motion.Body` (`Body.run`); it completes with `True` when it reaches its goal or its
duration, and with `False` when pre-empted or timed out.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from airsim_mapper.common.geometry import quat_from_rpy, rotate, yaw_of
from airsim_mapper.simserver.motion.motion import Command, Kinematic, Motion, wrap_angle

# Takeoff and landing follow Project AirSim's multirotor API (vehicle_apis/multirotor_api):
# Takeoff refuses (false) while moving faster than approx_zero_vel_ and otherwise runs
# MoveToPosition(x, y, z + GetTakeoffZ(), 0.5 m/s) from where the robot is (multirotor_api_base.cpp
# Takeoff); GetTakeoffZ() is -3 m ("3 meters is probably safe enough to get out of the backwash").
TAKEOFF_HEIGHT_M = 3.0
TAKEOFF_SPEED = 0.5
APPROX_ZERO_VEL = 0.05  # approx_zero_vel_, multirotor_api_base.hpp
# Land descends at landing_vel_ = 0.2 m/s (multirotor_api_base.hpp); it first waits up to 10 s for the
# descent to start (so a robot already on the ground replies after 10 s more), then confirms touchdown
# after kSecNearZeroVelRequired = 1 s of near-zero vertical speed (multirotor_api_base.cpp Land).
LAND_SPEED = 0.2
LAND_START_WAIT_S = 10.0
LAND_CONFIRM_S = 1.0
VERTICAL_GAIN = 5.0
MAX_VERTICAL_SPEED = 5.0
MAX_YAW_RATE = math.pi
ARRIVAL_M = 1e-6
FORWARD_ONLY = 1


@dataclass
class YawMode:
    """Yaw control: a rate (rad/s) or an absolute yaw (rad); ForwardOnly faces the direction of travel."""

    is_rate: bool = True
    value: float = 0.0
    drivetrain: int = 0

    def rate(self, current_yaw: float, velocity: np.ndarray, dt: float) -> float:
        if self.is_rate:
            target = None if self.drivetrain != FORWARD_ONLY else self._forward(velocity, 0.0)
            if target is None:
                return self.value
        else:
            target = self._forward(velocity, self.value) if self.drivetrain == FORWARD_ONLY else self.value
            if target is None:
                target = self.value
        return turn_rate(current_yaw, target, MAX_YAW_RATE, dt)

    @staticmethod
    def _forward(velocity: np.ndarray, offset: float) -> float | None:
        if math.hypot(velocity[0], velocity[1]) < 0.1:
            return None
        return math.atan2(velocity[1], velocity[0]) + offset


def turn_rate(current: float, target: float, max_rate: float, dt: float) -> float:
    """Yaw rate that reaches `target` without overshoot within one tick, capped at `max_rate`."""
    error = wrap_angle(target - current)
    if dt <= 0:
        return 0.0
    return float(np.clip(error / dt, -max_rate, max_rate))


class Velocity(Command):
    """Constant world velocity for `duration` s; `z` (if set) replaces vz by an altitude hold."""

    name = "MoveByVelocity"

    def __init__(
        self, velocity: Sequence[float], duration: float, yaw: YawMode, z: float | None = None
    ) -> None:
        super().__init__()
        self.velocity = np.asarray(velocity, dtype=float)
        self.duration = max(0.0, float(duration))
        self.yaw = yaw
        self.z = z

    def motion(self, state: Kinematic, dt: float, ground_z: float) -> Motion | None:
        if self.elapsed >= self.duration:
            return None
        velocity = self.velocity.copy()
        if self.z is not None:
            velocity[2] = np.clip(
                VERTICAL_GAIN * (self.z - state.position[2]), -MAX_VERTICAL_SPEED, MAX_VERTICAL_SPEED
            )
        return Motion(velocity, self.yaw.rate(yaw_of(state.orientation), velocity, dt))


class Path(Command):
    """Fly straight through each waypoint in turn at `speed`."""

    name = "MoveOnPath"

    def __init__(
        self, waypoints: Sequence[Sequence[float]], speed: float, yaw: YawMode, timeout_s: float
    ) -> None:
        super().__init__(timeout_s)
        self.waypoints = [np.asarray(p, dtype=float) for p in waypoints]
        self.speed = max(1e-3, abs(float(speed)))
        self.yaw = yaw

    def motion(self, state: Kinematic, dt: float, ground_z: float) -> Motion | None:
        while self.waypoints and np.linalg.norm(self.waypoints[0] - state.position) < ARRIVAL_M:
            self.waypoints.pop(0)
        if not self.waypoints:
            return None
        offset = self.waypoints[0] - state.position
        distance = float(np.linalg.norm(offset))
        speed = min(self.speed, distance / dt) if dt > 0 else self.speed
        velocity = offset / distance * speed
        return Motion(velocity, self.yaw.rate(yaw_of(state.orientation), velocity, dt))


class Land(Command):
    """Descend at LAND_SPEED to the surface below, then confirm touchdown for LAND_CONFIRM_S."""

    name = "Land"

    def __init__(self, timeout_s: float = math.inf) -> None:
        super().__init__(timeout_s)
        self.descended = False
        self.resting = 0.0  # seconds at rest on the ground so far

    def motion(self, state: Kinematic, dt: float, ground_z: float) -> Motion | None:
        height = ground_z - state.position[2]
        if height > 1e-3:
            self.descended = True
            self.resting = 0.0
            speed = min(LAND_SPEED, height / dt) if dt > 0 else LAND_SPEED
            return Motion(np.array([0.0, 0.0, speed]))
        if not self.descended and self.elapsed < LAND_START_WAIT_S:
            return Motion(np.zeros(3))  # waiting for a descent that cannot start: already down
        if self.resting >= LAND_CONFIRM_S:
            return None
        self.resting += dt
        return Motion(np.zeros(3))


class Rotate(Command):
    """Turn to an absolute yaw (within `margin`) or at a rate for a duration."""

    name = "Rotate"

    def __init__(
        self,
        target: float | None,
        rate: float,
        duration: float = math.inf,
        margin: float = 0.01,
        timeout_s: float = math.inf,
    ) -> None:
        super().__init__(timeout_s)
        self.target = target
        self.rate = rate
        self.duration = duration
        self.margin = max(margin, 1e-4)

    def motion(self, state: Kinematic, dt: float, ground_z: float) -> Motion | None:
        yaw = yaw_of(state.orientation)
        if self.target is None:
            return None if self.elapsed >= self.duration else Motion(np.zeros(3), self.rate)
        if abs(wrap_angle(self.target - yaw)) <= self.margin:
            return None
        max_rate = abs(self.rate) if self.rate > 0 else MAX_YAW_RATE
        return Motion(np.zeros(3), turn_rate(yaw, self.target, max_rate, dt))


def body_to_world_velocity(orientation: np.ndarray, vx: float, vy: float, vz: float) -> np.ndarray:
    """Velocity given in the yaw-rotated body frame (forward, right, down) in world NED."""
    return rotate(quat_from_rpy(0.0, 0.0, yaw_of(orientation)), np.array([vx, vy, vz], dtype=float))


class Heading(Command):
    """MoveByHeading: turn to `heading`, then fly along it at `speed` (and `vz`) for `duration` s.

    The duration counts from the moment the yaw is within `margin` of the heading, as the real
    controller's countdown does; `yaw_rate` <= 0 turns as fast as the body can (MAX_YAW_RATE).
    """

    name = "MoveByHeading"

    def __init__(
        self,
        heading: float,
        speed: float,
        vz: float,
        duration: float,
        margin: float,
        yaw_rate: float,
        timeout_s: float = math.inf,
    ) -> None:
        super().__init__(timeout_s)
        self.heading = wrap_angle(heading)
        self.speed = speed
        self.vz = vz
        self.flight = max(0.0, duration)
        self.margin = max(abs(margin), 1e-4)
        self.max_rate = abs(yaw_rate) if yaw_rate > 0 else MAX_YAW_RATE
        self.flown: float | None = None  # seconds flown along the heading, once aligned

    def motion(self, state: Kinematic, dt: float, ground_z: float) -> Motion | None:
        yaw = yaw_of(state.orientation)
        rate = turn_rate(yaw, self.heading, self.max_rate, dt)
        if self.flown is None:
            if abs(wrap_angle(self.heading - yaw)) > self.margin:
                return Motion(np.zeros(3), rate)
            self.flown = 0.0
        if self.flown >= self.flight:
            return None
        self.flown += dt
        velocity = np.array(
            [self.speed * math.cos(self.heading), self.speed * math.sin(self.heading), self.vz]
        )
        return Motion(velocity, rate)


# A kinematic bicycle for SetRoverControls (no tyre model; constants of a small ground robot)
ROVER_MAX_SPEED = 5.0  # m/s at engine 1
ROVER_ACCELERATION = 2.0  # m/s^2 towards the engine's speed
ROVER_BRAKE_DECELERATION = 8.0  # m/s^2 at brake 1
ROVER_WHEELBASE_M = 0.5
ROVER_MAX_STEERING = 0.6  # rad


class Drive(Command):
    """SetRoverControls: engine (-1..1) sets a target speed, brake (0..1) slows, steering (rad) turns.

    It never completes by itself: it runs until the next command replaces it (its reply is sent at once).
    """

    name = "SetRoverControls"

    def __init__(self, engine: float, steering: float, brake: float, speed: float = 0.0) -> None:
        super().__init__()
        self.engine = float(np.clip(engine, -1.0, 1.0))
        self.steering = float(np.clip(steering, -ROVER_MAX_STEERING, ROVER_MAX_STEERING))
        self.brake = float(np.clip(brake, 0.0, 1.0))
        self.speed = speed

    def motion(self, state: Kinematic, dt: float, ground_z: float) -> Motion | None:
        target = self.engine * ROVER_MAX_SPEED
        step = ROVER_ACCELERATION * dt
        self.speed += float(np.clip(target - self.speed, -step, step))
        brake = self.brake * ROVER_BRAKE_DECELERATION * dt
        self.speed = math.copysign(max(0.0, abs(self.speed) - brake), self.speed)
        yaw = yaw_of(state.orientation)
        velocity = np.array([self.speed * math.cos(yaw), self.speed * math.sin(yaw), 0.0])
        return Motion(velocity, self.speed * math.tan(self.steering) / ROVER_WHEELBASE_M)
