"""Sensor streams: when each sensor of a robot renders or measures, and where its messages go.

Cameras (`camera_stream.py`) render on the camera thread (through the render worker, which a busy machine
slows first), lidars and radars scan on the scan thread, so a slow render never holds a scan back;
instruments (IMU, GPS, ...) and rotor info are cheap and run on the simulation thread. Cameras render only
while someone subscribes (or a GetImages call waits). The other sensors sample on their schedule whether or
not anyone listens, as the real ones do: an unheard sample is offered to the topic hub, made only if a
subscriber comes before the next one, so a new subscriber always gets the latest sample.
The sensor models (`camera_model` and the renderers, `lidar_model`, `radar_model`, `instrument_models`)
are pure numpy (or OpenGL); this module only schedules them.
"""

from __future__ import annotations

import functools
import logging
import math
import threading
from collections.abc import Callable
from typing import Any, ClassVar

import numpy as np

from airsim_mapper.common.geometry import compose, quat_from_rpy, rpy_from_quat
from airsim_mapper.simserver.motion.motion import Body, Kinematic
from airsim_mapper.simserver.scene.config import SensorSpec
from airsim_mapper.simserver.sensors import instrument_models, lidar_model, radar_model
from airsim_mapper.simserver.sensors.battery import BatteryState
from airsim_mapper.simserver.wire import messages
from airsim_mapper.simserver.wire.topics import TopicHub
from airsim_mapper.simserver.world.world import World

LOG = logging.getLogger("airsim_mapper.simserver.sensor_streams")

# Between reports a lidar scans segments of at least this much sim time: a segment per physics tick would
# spend much of the server's time in numpy's per-call overhead; the report carries the same points.
LIDAR_MIN_SEGMENT_NS = 20_000_000


def mount_pose(
    kin: Kinematic, offset_position: np.ndarray, offset_orientation: np.ndarray, gimbal: dict | None = None
) -> tuple[np.ndarray, np.ndarray]:
    """World pose of a sensor mounted at an offset on the robot; gimbal locks drop robot roll/pitch."""
    body_q = kin.orientation
    if gimbal:
        roll, pitch, yaw = rpy_from_quat(body_q)
        body_q = quat_from_rpy(
            0.0 if gimbal.get("lock-roll") else roll,
            0.0 if gimbal.get("lock-pitch") else pitch,
            0.0 if gimbal.get("lock-yaw") else yaw,
        )
    return compose(kin.position, body_q, offset_position, offset_orientation)


class Schedule:
    """Fires every `period_ns` of sim time (the first time at once)."""

    def __init__(self, period_ns: int) -> None:
        self.period_ns = max(1, int(period_ns))
        self.next_ns: int | None = None

    def due(self, now_ns: int) -> bool:
        if self.next_ns is None or now_ns >= self.next_ns:
            base = now_ns if self.next_ns is None or now_ns - self.next_ns > self.period_ns else self.next_ns
            self.next_ns = base + self.period_ns
            return True
        return False


class ReportTimer:
    """When the real lidar and distance sensor report (UnrealLidar/UnrealDistanceSensor TickComponent).

    A `report-frequency` below 0.01 Hz (or none) reports on every tick; otherwise a tick reports once
    1/frequency of sim time has passed since the last report, and the last report time is set back by the
    overshoot (at most two periods) so the reports keep the frequency on average. Never twice at one time.
    """

    def __init__(self, frequency_hz: float | None) -> None:
        hz = float(frequency_hz or 0.0)
        self.period_ns = 0 if hz < 0.01 else round(1e9 / hz)
        self.last_ns: int | None = None  # the (set back) time of the last report
        self.reported_ns: int | None = None  # when it actually was

    def is_due(self, now_ns: int) -> bool:
        """Whether a report is due at `now_ns` (without taking it)."""
        if self.last_ns is None or self.reported_ns is None:
            return True
        return now_ns > self.reported_ns and now_ns - self.last_ns >= self.period_ns

    def due(self, now_ns: int) -> bool:
        """Whether a report is due at `now_ns`; if so, it is taken."""
        if not self.is_due(now_ns):
            return False
        if self.last_ns is None or self.reported_ns is None:
            self.last_ns = self.reported_ns = now_ns
            return True
        elapsed = now_ns - self.last_ns
        self.last_ns = now_ns - min(elapsed - self.period_ns, 2 * self.period_ns)
        self.reported_ns = now_ns
        return True


def report_frequency(sensor: SensorSpec) -> float | None:
    """A sensor's `report-frequency` in Hz (checked by the scene parser), None if absent."""
    value = sensor.config.get("report-frequency")
    return None if value is None else float(value)


class LidarStream:
    """A lidar: each physics tick scans the segment of its pattern since the previous tick (from the pose at
    that tick, points in the sensor frame of that tick), and a report carries every segment since the
    previous report, stamped and posed at report time: on every tick, or at `report-frequency` (ReportTimer).

    `step` takes the time of the latest physics tick; in lock-step that is the step just simulated, free
    running the scan thread may see several ticks at once and scans them as one segment. Between reports,
    segments span at least LIDAR_MIN_SEGMENT_NS (each scanned from the pose at its end). Scans only
    while subscribed; unheard reports are offered (scanned if a subscriber comes before the next one).
    """

    CLOUDS = (
        "point_cloud",
        "azimuth_elevation_range_cloud",
        "segmentation_cloud",
        "intensity_cloud",
        "laser_index_cloud",
    )

    def __init__(
        self, sensor: SensorSpec, prefix: str, body: Body, world: World, hub: TopicHub, step_ns: int
    ) -> None:
        self.path = f"{prefix}/lidar"
        self.sensor, self.body, self.world, self.hub = sensor, body, world, hub
        self.model = lidar_model.LidarModel.from_config(dict(sensor.config))
        self.step_ns = max(1, int(step_ns))
        self.timer = ReportTimer(report_frequency(sensor))
        self.report_span_ns = max(self.step_ns, self.timer.period_ns)  # the sim time one report covers
        self.last_tick_ns: int | None = None  # the latest tick seen
        self.scanned_ns: int | None = None  # the tick scanned last (None while nobody listens)
        self.pending: list[dict[str, np.ndarray]] = []

    def step(self, tick_ns: int) -> bool:
        """Scan the segment up to this tick (if new) and report if due; True if it scanned."""
        if self.last_tick_ns is not None and tick_ns <= self.last_tick_ns:
            return False
        self.last_tick_ns = tick_ns
        if not self.hub.is_subscribed(self.path):
            # the real lidar scans whether or not anyone listens: a due report is offered, scanned only if a
            # subscription arrives before the next one, and a new subscriber's first report covers the
            # time since the last report, as if this one had been scanning too
            self.scanned_ns, self.pending = None, []
            if self.timer.due(tick_ns):
                position, orientation = self.world_pose()
                start = tick_ns - self.report_span_ns
                scan = functools.partial(self.model.scan, self.world, position, orientation, start, tick_ns)
                self.hub.offer(self.path, lambda: self.report(tick_ns, [scan()], position, orientation))
            return False
        if (
            self.scanned_ns is not None
            and tick_ns - self.scanned_ns < LIDAR_MIN_SEGMENT_NS
            and not self.timer.is_due(tick_ns)
        ):
            return False  # the next segment, or the report, covers this tick too
        position, orientation = self.world_pose()
        start = self.scanned_ns
        if start is None:
            reported = self.timer.reported_ns
            start = reported if reported is not None else tick_ns - self.report_span_ns
        self.scanned_ns = tick_ns
        self.pending.append(self.model.scan(self.world, position, orientation, start, tick_ns))
        if self.timer.due(tick_ns):
            self.hub.publish(self.path, self.report(tick_ns, self.pending, position, orientation))
            self.pending = []
        return True

    def world_pose(self) -> tuple[np.ndarray, np.ndarray]:
        """The lidar's world pose now, from the robot's."""
        return mount_pose(self.body.snapshot(), self.sensor.position, self.sensor.orientation)

    @classmethod
    def report(
        cls, tick_ns: int, scans: list[dict[str, np.ndarray]], position: np.ndarray, orientation: np.ndarray
    ) -> dict[str, Any]:
        """The lidar message at `tick_ns`: the clouds of `scans` joined, posed at the report."""
        message: dict[str, Any] = {"time_stamp": int(tick_ns)}
        for key in cls.CLOUDS:
            parts = [scan[key] for scan in scans if key in scan]
            message[key] = np.concatenate(parts) if parts else np.zeros(0, dtype=np.float32)
        message["pose"] = messages.pose(position, orientation)
        return message


class RadarStream:
    """A radar: detections every detection-interval, tracks every track-interval (offered while unheard)."""

    def __init__(self, sensor: SensorSpec, prefix: str, body: Body, world: World, hub: TopicHub) -> None:
        self.detections_path = f"{prefix}/radar_detections"
        self.tracks_path = f"{prefix}/radar_tracks"
        self.sensor, self.body, self.world, self.hub = sensor, body, world, hub
        self.model = radar_model.RadarModel.from_config(dict(sensor.config))
        self.detect_schedule = Schedule(int(float(sensor.config.get("detection-interval", 0.1)) * 1e9))
        self.track_schedule = Schedule(int(float(sensor.config.get("track-interval", 0.2)) * 1e9))

    def step(self, now_ns: int) -> bool:
        """Detections and tracks when due, offered (made only if someone listens); True if any was made."""
        detect, track = self.detect_schedule.due(now_ns), self.track_schedule.due(now_ns)
        if not (detect or track):
            return False
        kin = self.body.snapshot()
        position, orientation = mount_pose(kin, self.sensor.position, self.sensor.orientation)
        velocity, pose = kin.linear_velocity, messages.pose(position, orientation)
        worked = False
        if detect:

            def detections() -> dict[str, Any]:
                found = self.model.detect(self.world.current, position, orientation, velocity, now_ns)
                return {"time_stamp": int(now_ns), "radar_detections": found, "pose": pose}

            worked = self.hub.offer(self.detections_path, detections)
        if track:

            def tracks() -> dict[str, Any]:
                found = self.model.track(self.world.current, position, orientation, velocity, now_ns)
                return {"time_stamp": int(now_ns), "radar_tracks": found, "pose": pose}

            worked = self.hub.offer(self.tracks_path, tracks) or worked
        return worked


def ground_truth(body: Body) -> instrument_models.Kinematics:
    """The body's state now, as the instrument models take it."""
    return instrument_models.Kinematics(**vars(body.snapshot()))


class InstrumentStream:
    """IMU, GPS, barometer, magnetometer, distance sensor, battery or airspeed of one robot."""

    LEAVES: ClassVar[dict[str, str]] = {
        "imu": "imu_kinematics",
        "gps": "gps",
        "barometer": "barometer",
        "magnetometer": "magnetometer",
        "distance-sensor": "distance_sensor",
        "battery": "battery",
        "airspeed": "airspeed",
    }

    def __init__(
        self,
        sensor: SensorSpec,
        prefix: str,
        body: Body,
        world: World,
        hub: TopicHub,
        home_geo: tuple[float, float, float],
        start_ns: int,
    ) -> None:
        self.path = f"{prefix}/{self.LEAVES[sensor.type]}"
        self.sensor, self.body, self.world, self.hub, self.home_geo = sensor, body, world, hub, home_geo
        self.config = dict(sensor.config)  # read on every tick: copied once
        self.start_ns = start_ns
        # the real instruments publish on every physics update (core_sim sensors' Update; the barometer
        # reads `update-frequency` but never uses it); the distance sensor at its `report-frequency`
        self.timer = ReportTimer(report_frequency(sensor) if sensor.type == "distance-sensor" else None)
        self.battery = BatteryState.from_config(sensor.config, start_ns) if sensor.type == "battery" else None

    def message(self, now_ns: int, kin: instrument_models.Kinematics | None = None) -> dict[str, Any]:
        """This instrument's message at `now_ns`, from `kin` (read from the body if not given)."""
        kin = kin if kin is not None else ground_truth(self.body)
        cfg = self.config
        kind = self.sensor.type
        if kind == "imu":
            return instrument_models.imu_message(kin, cfg, now_ns)
        if kind == "gps":
            return instrument_models.gps_message(kin, self.home_geo, cfg, now_ns)
        if kind == "barometer":
            return instrument_models.barometer_message(kin, self.home_geo, cfg, now_ns)
        if kind == "magnetometer":
            return instrument_models.magnetometer_message(kin, cfg, now_ns)
        if kind == "distance-sensor":
            return instrument_models.distance_message(self.world, kin, cfg, now_ns)
        if self.battery is not None:
            return self.battery.message(now_ns)
        return instrument_models.airspeed_message(kin, cfg, now_ns)

    def step(self, now_ns: int, state: Callable[[], instrument_models.Kinematics] | None = None) -> None:
        """Publish if due (offered: made only if someone listens); `state` gives the tick's ground truth,
        shared by a robot's instrument_models."""
        if self.timer.due(now_ns):
            kin = state() if state is not None else ground_truth(self.body)
            self.hub.offer(self.path, functools.partial(self.message, now_ns, kin))


class RotorStream:
    """rotor_info of a robot's rotors: a hover speed while armed or flying, unless SetControlSignals set
    a rotor's output (0..1 of its max rpm) or ToggleFault stopped it."""

    def __init__(self, path: str, config: dict, body: Body, hub: TopicHub) -> None:
        self.path, self.body, self.hub = path, body, hub
        self.rotors = [
            (str(a.get("name", f"rotor{i}")), dict(a.get("rotor-settings", {})))
            for i, a in enumerate(config.get("actuators", []) or [])
            if isinstance(a, dict) and a.get("type") == "rotor"
        ]
        self.schedule = Schedule(50_000_000)
        self.angle = 0.0
        self._lock = threading.Lock()
        self._signals: dict[str, float] = {}
        self._faults: set[str] = set()

    def set_signals(self, signals: dict[str, float]) -> None:
        with self._lock:
            self._signals.update(signals)

    def set_fault(self, actuator: str, enable: bool) -> None:
        with self._lock:
            if enable:
                self._faults.add(actuator)
            else:
                self._faults.discard(actuator)

    def message(self, now_ns: int) -> dict[str, Any]:
        spinning = self.body.armed or not self.body.landed()
        with self._lock:
            signals, faults = dict(self._signals), set(self._faults)
        vec = []
        for rotor_id, settings in self.rotors:
            level = signals.get(rotor_id, 0.6 if spinning else 0.0)
            level = 0.0 if rotor_id in faults else min(1.0, max(0.0, level))
            max_rpm = float(settings.get("max-rpm", 6000.0))
            direction = -1.0 if settings.get("turning-direction") == "counter-clock-wise" else 1.0
            vec.append(
                {
                    "rotor_id": rotor_id,
                    "speed": level * max_rpm * 2 * math.pi / 60,
                    "angle": math.fmod(self.angle * direction, 2 * math.pi),
                    "torque": float(settings.get("coeff-of-torque", 0.04)) * level * direction,
                    "thrust": float(settings.get("coeff-of-thrust", 0.1)) * level * 4.0,
                }
            )
        return {"time_stamp": int(now_ns), "rotor_info_vec": vec}

    def step(self, now_ns: int) -> None:
        if self.schedule.due(now_ns):
            self.angle += 0.3
            self.hub.offer(self.path, functools.partial(self.message, now_ns))
