"""One robot of a loaded scene: its kinematic body, its sensor streams and its service methods.

Motion commands (Takeoff, Move*, Rotate*, Land, GoHome, Hover) are served on the calling service worker:
the handler starts the command and waits until it ends, so the reply comes when the motion is finished,
`true` on success and `false` when pre-empted or timed out (protocol.md §3.3).

The kinematic state stays finite: numbers must be finite, speeds, yaw rates and positions are bounded
(SPEED_LIMIT_MPS, YAW_RATE_LIMIT, POSITION_LIMIT_M: far beyond any robot, but far from overflowing), and
a command that would leave those bounds is refused with a parameter error (code 2) before it starts.
"""

from __future__ import annotations

import functools
import logging
import math
import threading
from collections.abc import Callable
from typing import Any

import numpy as np

from airsim_mapper.geometry import quat_from_rpy, quat_multiply
from airsim_mapper.simserver import camera as camera_model
from airsim_mapper.simserver import messages
from airsim_mapper.simserver.clock import SimClock
from airsim_mapper.simserver.messages import MessageError
from airsim_mapper.simserver.motion import (
    APPROX_ZERO_VEL,
    FORWARD_ONLY,
    TAKEOFF_HEIGHT_M,
    TAKEOFF_SPEED,
    Body,
    Command,
    Drive,
    Heading,
    Hold,
    Land,
    Path,
    Rotate,
    Velocity,
    YawMode,
    body_to_world_velocity,
)
from airsim_mapper.simserver.scene import RobotSpec, SceneSpec, ned_to_geo
from airsim_mapper.simserver.services import Method, ServiceError
from airsim_mapper.simserver.streams import (
    CameraStream,
    InstrumentStream,
    LidarStream,
    RadarStream,
    Render,
    RotorStream,
    ground_truth,
)
from airsim_mapper.simserver.topics import TopicHub
from airsim_mapper.simserver.world import World

LOG = logging.getLogger("airsim_mapper.simserver")
SPEED_LIMIT_MPS = 1e5
YAW_RATE_LIMIT = 1e4  # rad/s
POSITION_LIMIT_M = 1e8  # |x|, |y|, |z| of any position, commanded or reached
COLLISION_RADIUS_M = 0.4
COLLISION_REPEAT_NS = 100_000_000
MAX_EVENTS = 1000  # collisions kept for the next Step call
GROUND_PROBE_M = 0.1  # ground rays start this far above the body, so a body resting on a surface sees it
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


def _parameter_error(key: str, message: str) -> ServiceError:
    return ServiceError(f"Parameter '{key}' {message}", code=2.0)


def _number(params: dict[str, Any], key: str) -> float:
    value = params[key]
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise _parameter_error(key, f"must be a number, got {value!r}")
    return float(value)


def _float(params: dict[str, Any], key: str, limit: float = math.inf) -> float:
    """A finite number parameter, at most `limit` in magnitude."""
    value = _number(params, key)
    if not math.isfinite(value):
        raise _parameter_error(key, f"must be finite, got {value}")
    if abs(value) > limit:
        raise _parameter_error(key, f"must be within +-{limit:g}, got {value:g}")
    return value


def _timeout(params: dict[str, Any]) -> float:
    value = _number(params, "timeout_sec")
    return value if value > 0 and math.isfinite(value) else math.inf


def _yaw_mode(params: dict[str, Any]) -> YawMode:
    is_rate = bool(params["yaw_is_rate"])
    yaw = _float(params, "yaw", YAW_RATE_LIMIT if is_rate else math.inf)
    return YawMode(is_rate, yaw, int(params["drivetrain"]))


def _within_world(key: str, position: np.ndarray) -> np.ndarray:
    """`position`, if every coordinate is finite and within POSITION_LIMIT_M; else a parameter error."""
    with np.errstate(over="ignore", invalid="ignore"):
        inside = np.all(np.abs(position) <= POSITION_LIMIT_M)
    if not inside:
        where = ", ".join(f"{v:g}" for v in position)
        raise _parameter_error(key, f"leads to ({where}), outside the +-{POSITION_LIMIT_M:g} m world")
    return position


def _speed(key: str, velocity: np.ndarray) -> np.ndarray:
    with np.errstate(over="ignore", invalid="ignore"):
        speed = float(np.linalg.norm(velocity))
    if not speed <= SPEED_LIMIT_MPS:
        raise _parameter_error(key, f"asks for {speed:g} m/s; at most {SPEED_LIMIT_MPS:g} m/s")
    return velocity


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
        self.body = Body(spec.position, spec.orientation, self.ground_z)
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
        kin = self.body.snapshot()
        self.hub.publish(self.pose_path, messages.pose_stamped(now_ns, kin.position, kin.orientation))

    def step_instruments(self, now_ns: int) -> None:
        """Step every instrument on one snapshot of the body, taken when the first one is due."""
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

    # -- service methods

    def methods(self) -> list[Method]:
        p = self.prefix
        table: list[Method] = [
            Method(f"{p}/GetGroundTruthKinematics", (), self._get_kinematics),
            Method(f"{p}/GetEstimatedKinematics", (), self._get_kinematics),
            Method(f"{p}/SetGroundTruthKinematics", ("kinematics",), self._set_kinematics),
            Method(f"{p}/GetGroundTruthPose", (), self._get_pose),
            Method(f"{p}/SetPose", ("pose", "reset_kinematics"), self._set_pose),
            Method(f"{p}/GetGroundTruthGeoLocation", (), self._get_geo),
            Method(f"{p}/GetEstimatedGeoLocation", (), self._get_geo),
            Method(f"{p}/SetExternalForce", ("ext_force",), lambda _: True),
            Method(f"{p}/GetReadyState", (), self._ready_state),
            Method(f"{p}/CancelLastTask", (), lambda _: self.body.cancel()),
            Method(f"{p}/SetParameter", ("index", "value"), self._set_parameter),
        ]
        for path, stream in self.getters.items():
            table.append(Method(path, (), self._getter(stream)))
            if stream.battery is not None:
                table += self._battery_methods(path.rsplit("/", 1)[0], stream)
        for camera_id, camera in self.cameras.items():
            table += self._camera_methods(self.scene.sensor_prefix(self.spec.name, camera_id), camera)
        table.append(Method(f"{p}/GetCameraRay", ("camera_id", "image_type", "x", "y"), self._camera_ray))
        table += self._actuator_methods()
        if self.spec.multirotor:
            table += self._multirotor_methods()
        if self.spec.rover:
            table += self._rover_methods()
        return table

    def _set_parameter(self, params: dict[str, Any]) -> bool:
        """UnrealRobot's SetParameter(index, value): stored; the kinematic body has no such inputs."""
        self.parameters[int(_float(params, "index"))] = _float(params, "value")
        return True

    # -- battery, actuators, JSBSim

    def _battery_methods(self, path: str, stream: InstrumentStream) -> list[Method]:
        battery = stream.battery
        assert battery is not None
        now = self.clock.now_ns
        return [
            Method(f"{path}/GetBatteryStatus", (), lambda _: battery.message(now())),
            Method(
                f"{path}/SetBatteryRemaining",
                ("desired_battery_remaining",),
                lambda a: battery.set_remaining(a["desired_battery_remaining"], now()),
            ),
            Method(f"{path}/GetBatteryDrainRate", (), lambda _: battery.drain_rate),
            Method(
                f"{path}/SetBatteryDrainRate",
                ("desired_drain_rate",),
                lambda a: battery.set_drain_rate(a["desired_drain_rate"], now()),
            ),
            Method(
                f"{path}/SetBatteryHealthStatus",
                ("battery_health_indicator",),
                lambda a: battery.set_healthy(bool(a["battery_health_indicator"])),
            ),
        ]

    def _actuator_methods(self) -> list[Method]:
        p = self.prefix
        table = [
            Method(f"{p}/SetControlSignals", ("control_signal_map",), self._set_control_signals),
            Method(f"{p}/GetJSBSimProperty", ("_property_name",), self._no_jsbsim),
            Method(f"{p}/SetJSBSimProperty", ("_property_name", "_value"), self._no_jsbsim),
        ]
        for actuator in self.spec.actuator_ids():
            table.append(Method(f"{p}/actuators/{actuator}/ToggleFault", ("enable",), self._fault(actuator)))
        return table

    def _set_control_signals(self, params: dict[str, Any]) -> bool:
        """Manual-controller outputs by actuator id (0..1 drives a rotor); False if an id is unknown."""
        signals = params["control_signal_map"]
        if not isinstance(signals, dict):
            raise _parameter_error("control_signal_map", f"must map actuator ids to numbers, got {signals!r}")
        values = {str(k): _float(signals, k) for k in signals}
        known = set(self.spec.actuator_ids())
        self.rotors.set_signals({k: v for k, v in values.items() if k in known})
        return set(values) <= known

    def _fault(self, actuator: str) -> Callable[[dict[str, Any]], bool]:
        def toggle(params: dict[str, Any]) -> bool:
            self.rotors.set_fault(actuator, bool(params["enable"]))
            return True

        return toggle

    def _no_jsbsim(self, _: dict[str, Any]) -> Any:
        raise ServiceError(
            f"Robot '{self.spec.name}' has no JSBSim model (physics-type '{self.spec.physics_type}'); "
            "the headless server does not run JSBSim"
        )

    def _camera_ray(self, params: dict[str, Any]) -> dict[str, Any]:
        """GetCameraRay: the pose of the ray through pixel (x, y) of a camera's image type (world NED)."""
        camera_id = str(params["camera_id"])
        stream = self.cameras.get(camera_id)
        if stream is None:
            raise ServiceError(f"Robot '{self.spec.name}' has no enabled camera '{camera_id}'")
        image_type = int(_float(params, "image_type"))
        capture = stream.captures.get(image_type)
        if capture is None:
            raise ServiceError(f"Camera '{camera_id}' has no capture-enabled image type {image_type}")
        x, y = _float(params, "x"), _float(params, "y")
        f = camera_model.focal_length(capture.width, stream.fov[image_type])
        right, down = (x - capture.width / 2.0) / f, (y - capture.height / 2.0) / f
        local = quat_from_rpy(0.0, -math.atan2(down, math.hypot(1.0, right)), math.atan2(right, 1.0))
        position, orientation = stream.world_pose()
        return messages.pose(position, quat_multiply(orientation, local))

    def _getter(self, stream: InstrumentStream) -> Callable[[dict[str, Any]], dict[str, Any]]:
        return lambda _: stream.message(self.clock.now_ns())

    def _get_kinematics(self, _: dict[str, Any]) -> dict[str, Any]:
        return messages.kinematics(self.clock.now_ns(), self.body.snapshot())

    def _set_kinematics(self, params: dict[str, Any]) -> bool:
        try:
            kin = messages.parse_kinematics(params["kinematics"])
        except MessageError as exc:
            raise ServiceError(str(exc), code=2.0) from exc
        _within_world("kinematics", kin.position)
        _speed("kinematics", kin.linear_velocity)
        if not float(np.linalg.norm(kin.angular_velocity)) <= YAW_RATE_LIMIT:
            raise _parameter_error("kinematics", f"angular velocity must be within {YAW_RATE_LIMIT:g} rad/s")
        self.body.teleport(kin.position, kin.orientation, reset_kinematics=True)
        with self.body.lock:
            self.body.state.linear_velocity = kin.linear_velocity
            self.body.state.angular_velocity = kin.angular_velocity
        return True

    def _get_pose(self, _: dict[str, Any]) -> dict[str, Any]:
        kin = self.body.snapshot()
        return messages.transform(kin.position, kin.orientation)

    def _set_pose(self, params: dict[str, Any]) -> bool:
        try:
            position, orientation = messages.parse_transform(params["pose"])
        except MessageError as exc:
            raise ServiceError(str(exc), code=2.0) from exc
        _within_world("pose", position)
        self.body.teleport(position, orientation, bool(params["reset_kinematics"]))
        self.publish_pose(self.clock.now_ns())
        return True

    def on_desired_pose(self, _path: str, message: Any) -> None:
        """A client MESSAGE on desired_pose teleports the robot (an invalid one is logged and ignored)."""
        try:
            position, orientation = messages.parse_pose_stamped(message)
            _within_world("position", position)
        except (MessageError, ServiceError) as exc:
            LOG.warning("ignored a desired_pose for %s: %s", self.spec.name, exc)
            return
        self.body.teleport(position, orientation, reset_kinematics=True)
        self.publish_pose(self.clock.now_ns())

    def _get_geo(self, _: dict[str, Any]) -> dict[str, float]:
        lat, lon, alt = ned_to_geo(self.body.snapshot().position, self.scene.home_geo)
        return {"latitude": lat, "longitude": lon, "altitude": alt}

    def _ready_state(self, _: dict[str, Any]) -> dict[str, Any]:
        return {"time_stamp": self.clock.now_ns(), "ready_val": True, "ready_message": ""}

    # -- cameras

    def _camera_methods(self, path: str, camera: CameraStream) -> list[Method]:
        def get_images(params: dict[str, Any]) -> dict[str, Any]:
            ids = params["image_type_ids"]
            if not isinstance(ids, list):
                raise ServiceError(f"image_type_ids must be a list, got {ids!r}", code=2.0)
            return camera.get_images(ids, self.clock.now_ns)

        def set_pose(params: dict[str, Any]) -> bool:
            try:
                position, orientation = messages.parse_transform(params["pose"])
            except MessageError as exc:
                raise ServiceError(str(exc), code=2.0) from exc
            camera.set_pose(_within_world("pose", position), orientation)
            return True

        def reset_pose(_: dict[str, Any]) -> bool:
            camera.reset_pose()
            return True

        def set_fov(params: dict[str, Any]) -> bool:
            image_type = int(params["image_type_id"])
            if image_type in camera.fov:
                camera.fov[image_type] = _float(params, "field_of_view")
            return True

        def look_at(params: dict[str, Any]) -> bool:
            return self.world.object_named(str(params["object_name"])) is not None

        accept = lambda _: True  # noqa: E731 - settings this renderer does not model
        return [
            Method(f"{path}/GetImages", ("image_type_ids",), get_images),
            Method(f"{path}/SetPose", ("pose", "wait_for_pose_update"), set_pose),
            Method(f"{path}/ResetCameraPose", ("wait_for_pose_update",), reset_pose),
            Method(f"{path}/LookAtObject", ("object_name", "wait_for_pose_update"), look_at),
            Method(f"{path}/DrawFrustum", ("image_type", "to_enable"), accept),
            Method(f"{path}/SetFieldOfView", ("image_type_id", "field_of_view"), set_fov),
            Method(f"{path}/SetFocalLength", ("image_type_id", "focal_length"), accept),
            Method(f"{path}/SetChromaticAberrationIntensity", ("image_type_id", "intensity"), accept),
            Method(f"{path}/SetDepthOfFieldFocalRegion", ("image_type_id", "focal_length"), accept),
            Method(
                f"{path}/SetDepthOfFieldTransitionRegion", ("image_type_id", "transition_threshold"), accept
            ),
        ]

    # -- multirotor

    def _run(self, command: Command) -> bool:
        self.body.run(command, self.clock.now_ns())
        return command.wait()

    def _flag(self, name: str, value: bool) -> Callable[[dict[str, Any]], bool]:
        def set_flag(_: dict[str, Any]) -> bool:
            setattr(self.body, name, value)
            return True

        return set_flag

    def _takeoff(self, params: dict[str, Any]) -> bool:
        """Climb TAKEOFF_HEIGHT_M from where the robot is; false while it moves (the real controller's)."""
        kin = self.body.snapshot()
        if float(np.linalg.norm(kin.linear_velocity)) > APPROX_ZERO_VEL:
            return False
        target = np.array([kin.position[0], kin.position[1], kin.position[2] - TAKEOFF_HEIGHT_M])
        return self._run(Path([target], TAKEOFF_SPEED, YawMode(True, 0.0), _timeout(params)))

    def _go_home(self, params: dict[str, Any]) -> bool:
        speed = _float(params, "velocity", SPEED_LIMIT_MPS)
        return self._run(
            Path([self.body.home], speed if speed > 0 else 5.0, YawMode(True, 0.0), _timeout(params))
        )

    def _velocity(self, body_frame: bool, hold_z: bool) -> Callable[[dict[str, Any]], bool]:
        def move(params: dict[str, Any]) -> bool:
            vx, vy = _float(params, "vx"), _float(params, "vy")
            vz = 0.0 if hold_z else _float(params, "vz")
            _speed("vx, vy, vz", np.array([vx, vy, vz]))
            kin = self.body.snapshot()
            velocity = np.array([vx, vy, vz])
            if body_frame:
                velocity = body_to_world_velocity(kin.orientation, vx, vy, vz)
            z = _float(params, "z", POSITION_LIMIT_M) if hold_z else None
            duration = _float(params, "duration")
            _within_world("duration", kin.position + velocity * max(duration, 0.0))
            return self._run(Velocity(velocity, duration, _yaw_mode(params), z))

        return move

    def _move_to(self, params: dict[str, Any]) -> bool:
        target = [_float(params, key, POSITION_LIMIT_M) for key in ("x", "y", "z")]
        speed = _float(params, "velocity", SPEED_LIMIT_MPS)
        return self._run(Path([target], speed, _yaw_mode(params), _timeout(params)))

    def _move_on_path(self, params: dict[str, Any]) -> bool:
        path = params["path"]
        if not isinstance(path, list) or not all(isinstance(p, list) and len(p) == 3 for p in path):
            raise ServiceError(f"path must be a list of [x, y, z] points, got {path!r}", code=2.0)
        try:
            points = np.array(path, dtype=float).reshape(-1, 3)
        except (TypeError, ValueError) as exc:
            raise _parameter_error("path", f"must hold numbers ({exc})") from None
        for point in points:
            _within_world("path", point)
        speed = _float(params, "velocity", SPEED_LIMIT_MPS)
        return self._run(Path(list(points), speed, _yaw_mode(params), _timeout(params)))

    def _rotate_to(self, params: dict[str, Any]) -> bool:
        command = Rotate(
            _float(params, "yaw"),
            _float(params, "yaw_rate", YAW_RATE_LIMIT),
            margin=_float(params, "margin"),
            timeout_s=_timeout(params),
        )
        return self._run(command)

    def _rotate_by(self, params: dict[str, Any]) -> bool:
        rate = _float(params, "yaw_rate", YAW_RATE_LIMIT)
        return self._run(Rotate(None, rate, duration=_float(params, "duration")))

    def _move_by_heading(self, params: dict[str, Any]) -> bool:
        """Drone (with `vz`) and rover (without) MoveByHeading."""
        speed = _float(params, "speed", SPEED_LIMIT_MPS)
        vz = _float(params, "vz", SPEED_LIMIT_MPS) if "vz" in params else 0.0
        _speed("speed, vz", np.array([speed, 0.0, vz]))
        duration = _float(params, "duration")
        kin = self.body.snapshot()
        _within_world("duration", kin.position + np.array([speed, speed, vz]) * max(duration, 0.0))
        command = Heading(
            _float(params, "heading"),
            speed,
            vz,
            duration,
            _float(params, "heading_margin"),
            _float(params, "yaw_rate", YAW_RATE_LIMIT),
            _timeout(params),
        )
        return self._run(command)

    # -- rover

    def _rover_controls(self, params: dict[str, Any]) -> bool:
        """SetRoverControls: replies at once; the drive lasts until the next command."""
        engine, steering, brake = (_float(params, k) for k in ("engine", "steering_angle", "brake"))
        with self.body.lock:
            previous = self.body.active
        speed = previous.speed if isinstance(previous, Drive) else 0.0
        self.body.run(Drive(engine, steering, brake, speed), self.clock.now_ns())
        return True

    def _rover_move_to(self, params: dict[str, Any]) -> bool:
        z = self.body.snapshot().position[2]
        target = [_float(params, "x", POSITION_LIMIT_M), _float(params, "y", POSITION_LIMIT_M), z]
        speed = _float(params, "velocity", SPEED_LIMIT_MPS)
        return self._run(Path([target], speed, YawMode(False, 0.0, FORWARD_ONLY), _timeout(params)))

    def _rover_move_on_path(self, params: dict[str, Any]) -> bool:
        path = params["path"]
        if not isinstance(path, list) or not all(isinstance(p, list) and len(p) in (2, 3) for p in path):
            raise _parameter_error("path", f"must be a list of [x, y(, z)] points, got {path!r}")
        z = self.body.snapshot().position[2]
        try:
            points = [_within_world("path", np.array([float(p[0]), float(p[1]), z])) for p in path]
        except (TypeError, ValueError) as exc:
            raise _parameter_error("path", f"must hold numbers ({exc})") from None
        speed = _float(params, "velocity", SPEED_LIMIT_MPS)
        return self._run(Path(points, speed, YawMode(False, 0.0, FORWARD_ONLY), _timeout(params)))

    def _control_methods(self) -> list[Method]:
        """API control and arming, which rovers and multirotors answer alike."""
        p = self.prefix
        return [
            Method(f"{p}/EnableApiControl", (), self._flag("api_control", True)),
            Method(f"{p}/DisableApiControl", (), self._flag("api_control", False)),
            Method(f"{p}/IsApiControlEnabled", (), lambda _: self.body.api_control),
            Method(f"{p}/Arm", (), self._flag("armed", True)),
            Method(f"{p}/Disarm", (), self._flag("armed", False)),
            Method(f"{p}/CanArm", (), lambda _: True),
        ]

    def _rover_methods(self) -> list[Method]:
        p = self.prefix
        return [
            *self._control_methods(),
            Method(f"{p}/SetRoverControls", ("engine", "steering_angle", "brake"), self._rover_controls),
            Method(f"{p}/MoveByHeading", HEADING_PARAMS, self._move_by_heading),
            Method(f"{p}/MoveToPosition", ("x", "y", *ROVER_PATH_PARAMS), self._rover_move_to),
            Method(f"{p}/MoveOnPath", ("path", *ROVER_PATH_PARAMS), self._rover_move_on_path),
        ]

    def _multirotor_methods(self) -> list[Method]:
        p = self.prefix
        ok = lambda _: True  # noqa: E731 - modes this kinematic model does not distinguish
        return [
            *self._control_methods(),
            Method(f"{p}/GetLandedState", (), lambda _: 0 if self.body.landed() else 1),
            Method(f"{p}/Takeoff", ("timeout_sec",), self._takeoff),
            Method(f"{p}/Land", ("timeout_sec",), lambda params: self._run(Land(_timeout(params)))),
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
