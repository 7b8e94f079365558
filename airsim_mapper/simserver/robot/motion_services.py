"""The service methods of a robot's motion: API control and arming, multirotor and rover commands.

Motion commands (Takeoff, Move*, Rotate*, Land, GoHome, Hover) are served on the calling service worker:
the handler starts the command and waits until it ends, so the reply comes when the motion is finished,
`true` on success and `false` when pre-empted or timed out (protocol.md §3.3).
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np

from airsim_mapper.simserver.motion.motion import Command, Hold
from airsim_mapper.simserver.motion.motion_commands import (
    APPROX_ZERO_VEL,
    FORWARD_ONLY,
    TAKEOFF_HEIGHT_M,
    TAKEOFF_SPEED,
    Drive,
    Heading,
    Land,
    Path,
    Rotate,
    Velocity,
    YawMode,
    body_to_world_velocity,
)
from airsim_mapper.simserver.robot.robot_params import (
    POSITION_LIMIT_M,
    SPEED_LIMIT_MPS,
    YAW_RATE_LIMIT,
    check_speed,
    finite,
    parameter_error,
    timeout,
    within_world,
    yaw_mode,
)
from airsim_mapper.simserver.robot.robots import RobotRuntime
from airsim_mapper.simserver.wire.services import Method, ServiceError

MOVE_PARAMS = ("duration", "drivetrain", "yaw_is_rate", "yaw")
HEADING_PARAMS = ("heading", "speed", "duration", "heading_margin", "yaw_rate", "timeout_sec")
ROVER_PATH_PARAMS = ("velocity", "timeout_sec", "yaw_rate_max", "lookahead", "adaptive_lookahead")
PATH_PARAMS = (
    "velocity",
    "timeout_sec",
    "drivetrain",
    "yaw_is_rate",
    "yaw",
    "lookahead",
    "adaptive_lookahead",
)


class MotionServices:
    """A robot's motion commands as service methods (none for a robot that is neither kind)."""

    def __init__(self, robot: RobotRuntime) -> None:
        self.robot = robot

    def methods(self) -> list[Method]:
        table: list[Method] = []
        if self.robot.spec.multirotor:
            table += self._multirotor_methods()
        if self.robot.spec.rover:
            table += self._rover_methods()
        return table

    def _run(self, command: Command) -> bool:
        self.robot.body.run(command, self.robot.clock.now_ns())
        return command.wait()

    def _flag(self, name: str, value: bool) -> Callable[[dict[str, Any]], bool]:
        def set_flag(_: dict[str, Any]) -> bool:
            setattr(self.robot.body, name, value)
            return True

        return set_flag

    def _takeoff(self, params: dict[str, Any]) -> bool:
        """Climb TAKEOFF_HEIGHT_M from where the robot is; false while it moves (the real controller's)."""
        kin = self.robot.body.snapshot()
        if float(np.linalg.norm(kin.linear_velocity)) > APPROX_ZERO_VEL:
            return False
        target = np.array([kin.position[0], kin.position[1], kin.position[2] - TAKEOFF_HEIGHT_M])
        return self._run(Path([target], TAKEOFF_SPEED, YawMode(True, 0.0), timeout(params)))

    def _go_home(self, params: dict[str, Any]) -> bool:
        speed = finite(params, "velocity", SPEED_LIMIT_MPS)
        return self._run(
            Path([self.robot.body.home], speed if speed > 0 else 5.0, YawMode(True, 0.0), timeout(params))
        )

    def _velocity(self, body_frame: bool, hold_z: bool) -> Callable[[dict[str, Any]], bool]:
        def move(params: dict[str, Any]) -> bool:
            vx, vy = finite(params, "vx"), finite(params, "vy")
            vz = 0.0 if hold_z else finite(params, "vz")
            check_speed("vx, vy, vz", np.array([vx, vy, vz]))
            kin = self.robot.body.snapshot()
            velocity = np.array([vx, vy, vz])
            if body_frame:
                velocity = body_to_world_velocity(kin.orientation, vx, vy, vz)
            z = finite(params, "z", POSITION_LIMIT_M) if hold_z else None
            duration = finite(params, "duration")
            within_world("duration", kin.position + velocity * max(duration, 0.0))
            return self._run(Velocity(velocity, duration, yaw_mode(params), z))

        return move

    def _move_to(self, params: dict[str, Any]) -> bool:
        target = [finite(params, key, POSITION_LIMIT_M) for key in ("x", "y", "z")]
        speed = finite(params, "velocity", SPEED_LIMIT_MPS)
        return self._run(Path([target], speed, yaw_mode(params), timeout(params)))

    def _move_on_path(self, params: dict[str, Any]) -> bool:
        path = params["path"]
        if not isinstance(path, list) or not all(isinstance(p, list) and len(p) == 3 for p in path):
            raise ServiceError(f"path must be a list of [x, y, z] points, got {path!r}", code=2.0)
        try:
            points = np.array(path, dtype=float).reshape(-1, 3)
        except (TypeError, ValueError) as exc:
            raise parameter_error("path", f"must hold numbers ({exc})") from None
        for point in points:
            within_world("path", point)
        speed = finite(params, "velocity", SPEED_LIMIT_MPS)
        return self._run(Path(list(points), speed, yaw_mode(params), timeout(params)))

    def _rotate_to(self, params: dict[str, Any]) -> bool:
        command = Rotate(
            finite(params, "yaw"),
            finite(params, "yaw_rate", YAW_RATE_LIMIT),
            margin=finite(params, "margin"),
            timeout_s=timeout(params),
        )
        return self._run(command)

    def _rotate_by(self, params: dict[str, Any]) -> bool:
        rate = finite(params, "yaw_rate", YAW_RATE_LIMIT)
        return self._run(Rotate(None, rate, duration=finite(params, "duration")))

    def _move_by_heading(self, params: dict[str, Any]) -> bool:
        """Drone (with `vz`) and rover (without) MoveByHeading."""
        speed = finite(params, "speed", SPEED_LIMIT_MPS)
        vz = finite(params, "vz", SPEED_LIMIT_MPS) if "vz" in params else 0.0
        check_speed("speed, vz", np.array([speed, 0.0, vz]))
        duration = finite(params, "duration")
        kin = self.robot.body.snapshot()
        within_world("duration", kin.position + np.array([speed, speed, vz]) * max(duration, 0.0))
        command = Heading(
            finite(params, "heading"),
            speed,
            vz,
            duration,
            finite(params, "heading_margin"),
            finite(params, "yaw_rate", YAW_RATE_LIMIT),
            timeout(params),
        )
        return self._run(command)

    # -- rover

    def _rover_controls(self, params: dict[str, Any]) -> bool:
        """SetRoverControls: replies at once; the drive lasts until the next command."""
        engine, steering, brake = (finite(params, k) for k in ("engine", "steering_angle", "brake"))
        with self.robot.body.lock:
            previous = self.robot.body.active
        speed = previous.speed if isinstance(previous, Drive) else 0.0
        self.robot.body.run(Drive(engine, steering, brake, speed), self.robot.clock.now_ns())
        return True

    def _rover_move_to(self, params: dict[str, Any]) -> bool:
        z = self.robot.body.snapshot().position[2]
        target = [finite(params, "x", POSITION_LIMIT_M), finite(params, "y", POSITION_LIMIT_M), z]
        speed = finite(params, "velocity", SPEED_LIMIT_MPS)
        return self._run(Path([target], speed, YawMode(False, 0.0, FORWARD_ONLY), timeout(params)))

    def _rover_move_on_path(self, params: dict[str, Any]) -> bool:
        path = params["path"]
        if not isinstance(path, list) or not all(isinstance(p, list) and len(p) in (2, 3) for p in path):
            raise parameter_error("path", f"must be a list of [x, y(, z)] points, got {path!r}")
        z = self.robot.body.snapshot().position[2]
        try:
            points = [within_world("path", np.array([float(p[0]), float(p[1]), z])) for p in path]
        except (TypeError, ValueError) as exc:
            raise parameter_error("path", f"must hold numbers ({exc})") from None
        speed = finite(params, "velocity", SPEED_LIMIT_MPS)
        return self._run(Path(points, speed, YawMode(False, 0.0, FORWARD_ONLY), timeout(params)))

    def _control_methods(self) -> list[Method]:
        """API control and arming, which rovers and multirotors answer alike."""
        p = self.robot.prefix
        return [
            Method(f"{p}/EnableApiControl", (), self._flag("api_control", True)),
            Method(f"{p}/DisableApiControl", (), self._flag("api_control", False)),
            Method(f"{p}/IsApiControlEnabled", (), lambda _: self.robot.body.api_control),
            Method(f"{p}/Arm", (), self._flag("armed", True)),
            Method(f"{p}/Disarm", (), self._flag("armed", False)),
            Method(f"{p}/CanArm", (), lambda _: True),
        ]

    def _rover_methods(self) -> list[Method]:
        p = self.robot.prefix
        return [
            *self._control_methods(),
            Method(f"{p}/SetRoverControls", ("engine", "steering_angle", "brake"), self._rover_controls),
            Method(f"{p}/MoveByHeading", HEADING_PARAMS, self._move_by_heading),
            Method(f"{p}/MoveToPosition", ("x", "y", *ROVER_PATH_PARAMS), self._rover_move_to),
            Method(f"{p}/MoveOnPath", ("path", *ROVER_PATH_PARAMS), self._rover_move_on_path),
        ]

    def _multirotor_methods(self) -> list[Method]:
        p = self.robot.prefix
        ok = lambda _: True  # noqa: E731 - modes this kinematic model does not distinguish
        return [
            *self._control_methods(),
            Method(f"{p}/GetLandedState", (), lambda _: 0 if self.robot.body.landed() else 1),
            Method(f"{p}/Takeoff", ("timeout_sec",), self._takeoff),
            Method(f"{p}/Land", ("timeout_sec",), lambda params: self._run(Land(timeout(params)))),
            Method(f"{p}/GoHome", ("timeout_sec", "velocity"), self._go_home),
            Method(f"{p}/Hover", (), lambda _: self._run(Hold())),
            Method(f"{p}/MoveByVelocity", ("vx", "vy", "vz", *MOVE_PARAMS), self._velocity(False, False)),
            Method(f"{p}/MoveByVelocityZ", ("vx", "vy", "z", *MOVE_PARAMS), self._velocity(False, True)),
            Method(
                f"{p}/MoveByVelocityBodyFrame", ("vx", "vy", "vz", *MOVE_PARAMS), self._velocity(True, False)
            ),
            Method(
                f"{p}/MoveByVelocityBodyFrameZ", ("vx", "vy", "z", *MOVE_PARAMS), self._velocity(True, True)
            ),
            Method(f"{p}/MoveToPosition", ("x", "y", "z", *PATH_PARAMS), self._move_to),
            Method(f"{p}/MoveOnPath", ("path", *PATH_PARAMS), self._move_on_path),
            Method(f"{p}/RotateToYaw", ("yaw", "timeout_sec", "margin", "yaw_rate"), self._rotate_to),
            Method(f"{p}/RotateByYawRate", ("yaw_rate", "duration"), self._rotate_by),
            Method(f"{p}/MoveByHeading", HEADING_PARAMS, self._move_by_heading),
            Method(f"{p}/RequestControl", (), ok),
            Method(f"{p}/SetMissionMode", (), ok),
            Method(f"{p}/SetVTOLMode", ("vtol_mode",), ok),
        ]
