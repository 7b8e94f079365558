"""The service methods of one robot, assembled by `robot_methods`; here those of its state and devices.

Handlers are grouped by job: the robot's state, instruments, batteries and actuators here; its cameras in
`camera_services.py`; its motion commands in `motion_services.py`. Each group holds the RobotRuntime it
serves and reads and changes it through the runtime's own objects (its body, clock and streams).
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np

from airsim_mapper.simserver.motion.motion import DRAG_TIME_S
from airsim_mapper.simserver.robot.camera_services import CameraServices
from airsim_mapper.simserver.robot.motion_services import MotionServices
from airsim_mapper.simserver.robot.robot_params import (
    YAW_RATE_LIMIT,
    check_speed,
    finite,
    parameter_error,
    within_world,
)
from airsim_mapper.simserver.robot.robots import RobotRuntime
from airsim_mapper.simserver.scene.geo import ned_to_geo
from airsim_mapper.simserver.sensors.sensor_streams import InstrumentStream
from airsim_mapper.simserver.wire import messages
from airsim_mapper.simserver.wire.messages import MessageError
from airsim_mapper.simserver.wire.services import Method, ServiceError


def robot_methods(robot: RobotRuntime) -> list[Method]:
    """Every service method of `robot`."""
    return [
        *RobotServices(robot).methods(),
        *CameraServices(robot).methods(),
        *MotionServices(robot).methods(),
    ]


class RobotServices:
    """A robot's state, instruments, batteries and actuators, as service methods."""

    def __init__(self, robot: RobotRuntime) -> None:
        self.robot = robot

    def methods(self) -> list[Method]:
        """Kinematics, pose, geo location, readiness, parameters, instruments, batteries, actuators."""
        p = self.robot.prefix
        table: list[Method] = [
            Method(f"{p}/GetGroundTruthKinematics", (), self._get_kinematics),
            Method(f"{p}/GetEstimatedKinematics", (), self._get_kinematics),
            Method(f"{p}/SetGroundTruthKinematics", ("kinematics",), self._set_kinematics),
            Method(f"{p}/GetGroundTruthPose", (), self._get_pose),
            Method(f"{p}/SetPose", ("pose", "reset_kinematics"), self._set_pose),
            Method(f"{p}/GetGroundTruthGeoLocation", (), self._get_geo),
            Method(f"{p}/GetEstimatedGeoLocation", (), self._get_geo),
            Method(f"{p}/SetExternalForce", ("ext_force",), self._set_external_force),
            Method(f"{p}/GetReadyState", (), self._ready_state),
            Method(f"{p}/CancelLastTask", (), lambda _: self.robot.body.cancel()),
            Method(f"{p}/SetParameter", ("index", "value"), self._set_parameter),
        ]
        for path, stream in self.robot.getters.items():
            table.append(Method(path, (), self._getter(stream)))
            if stream.battery is not None:
                table += self._battery_methods(path.rsplit("/", 1)[0], stream)
        table += self._actuator_methods()
        return table

    def _set_external_force(self, params: dict[str, Any]) -> bool:
        """SetExternalForce: a constant force (N, world NED) on the body until set again; an idle airborne
        body drifts with it (`Body.drift`)."""
        force = params["ext_force"]
        if not isinstance(force, list) or len(force) != 3:
            raise parameter_error("ext_force", f"must be a list of 3 numbers, got {force!r}")
        vector = np.array([finite({"ext_force": f}, "ext_force") for f in force])
        body = self.robot.body
        check_speed("ext_force", vector * (DRAG_TIME_S / body.mass_kg))
        with body.lock:
            body.external_force = vector
        return True

    def _set_parameter(self, params: dict[str, Any]) -> bool:
        """UnrealRobot's SetParameter(index, value): stored; the kinematic body has no such inputs."""
        self.robot.parameters[int(finite(params, "index"))] = finite(params, "value")
        return True

    # -- battery, actuators, JSBSim

    def _battery_methods(self, path: str, stream: InstrumentStream) -> list[Method]:
        battery = stream.battery
        assert battery is not None
        now = self.robot.clock.now_ns
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
        p = self.robot.prefix
        table = [
            Method(f"{p}/SetControlSignals", ("control_signal_map",), self._set_control_signals),
            Method(f"{p}/GetJSBSimProperty", ("_property_name",), self._no_jsbsim),
            Method(f"{p}/SetJSBSimProperty", ("_property_name", "_value"), self._no_jsbsim),
        ]
        for actuator in self.robot.spec.actuator_ids():
            table.append(Method(f"{p}/actuators/{actuator}/ToggleFault", ("enable",), self._fault(actuator)))
        return table

    def _set_control_signals(self, params: dict[str, Any]) -> bool:
        """Manual-controller outputs by actuator id (0..1 drives a rotor); False if an id is unknown."""
        signals = params["control_signal_map"]
        if not isinstance(signals, dict):
            raise parameter_error("control_signal_map", f"must map actuator ids to numbers, got {signals!r}")
        values = {str(k): finite(signals, k) for k in signals}
        known = set(self.robot.spec.actuator_ids())
        self.robot.rotors.set_signals({k: v for k, v in values.items() if k in known})
        return set(values) <= known

    def _fault(self, actuator: str) -> Callable[[dict[str, Any]], bool]:
        def toggle(params: dict[str, Any]) -> bool:
            self.robot.rotors.set_fault(actuator, bool(params["enable"]))
            return True

        return toggle

    def _no_jsbsim(self, _: dict[str, Any]) -> Any:
        spec = self.robot.spec
        raise ServiceError(
            f"Robot '{spec.name}' has no JSBSim model (physics-type '{spec.physics_type}'); "
            "the headless server does not run JSBSim"
        )

    def _getter(self, stream: InstrumentStream) -> Callable[[dict[str, Any]], dict[str, Any]]:
        return lambda _: stream.message(self.robot.clock.now_ns())

    def _get_kinematics(self, _: dict[str, Any]) -> dict[str, Any]:
        return messages.kinematics(self.robot.clock.now_ns(), self.robot.body.snapshot())

    def _set_kinematics(self, params: dict[str, Any]) -> bool:
        try:
            kin = messages.parse_kinematics(params["kinematics"])
        except MessageError as exc:
            raise ServiceError(str(exc), code=2.0) from exc
        within_world("kinematics", kin.position)
        check_speed("kinematics", kin.linear_velocity)
        if not float(np.linalg.norm(kin.angular_velocity)) <= YAW_RATE_LIMIT:
            raise parameter_error("kinematics", f"angular velocity must be within {YAW_RATE_LIMIT:g} rad/s")
        self.robot.body.teleport(kin.position, kin.orientation, True, self.robot.clock.now_ns())
        with self.robot.body.lock:
            self.robot.body.state.linear_velocity = kin.linear_velocity
            self.robot.body.state.angular_velocity = kin.angular_velocity
        return True

    def _get_pose(self, _: dict[str, Any]) -> dict[str, Any]:
        kin = self.robot.body.snapshot()
        return messages.transform(kin.position, kin.orientation)

    def _set_pose(self, params: dict[str, Any]) -> bool:
        try:
            position, orientation = messages.parse_transform(params["pose"])
        except MessageError as exc:
            raise ServiceError(str(exc), code=2.0) from exc
        within_world("pose", position)
        now = self.robot.clock.now_ns()
        self.robot.body.teleport(position, orientation, bool(params["reset_kinematics"]), now)
        self.robot.publish_pose(self.robot.clock.now_ns())
        return True

    def _get_geo(self, _: dict[str, Any]) -> dict[str, float]:
        lat, lon, alt = ned_to_geo(self.robot.body.snapshot().position, self.robot.scene.home_geo)
        return {"latitude": lat, "longitude": lon, "altitude": alt}

    def _ready_state(self, _: dict[str, Any]) -> dict[str, Any]:
        return {"time_stamp": self.robot.clock.now_ns(), "ready_val": True, "ready_message": ""}
