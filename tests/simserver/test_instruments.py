"""Instrument messages: keys of the real Project AirSim messages and physically plausible values."""

from __future__ import annotations

import math

import numpy as np
import pytest
from simconfigs import EXAMPLES, PROJECT, both_configs, robot_sensors

from airsim_mapper.common.geometry import quat_from_rpy
from airsim_mapper.simserver.sensors.instrument_models import (
    GRAVITY,
    MAGNETIC_FIELD_NED,
    InstrumentError,
    Kinematics,
    airspeed_message,
    barometer_message,
    battery_message,
    distance_message,
    gps_message,
    imu_message,
    magnetometer_message,
)
from airsim_mapper.simserver.world.world_file import load_world

HOME = (47.641468, -122.140165, 122.0)  # the scenes' home-geo-point
# robot configs carrying every instrument
INSTRUMENT_ROBOT = {
    PROJECT: "robot_quadrotor_survey.jsonc",
    EXAMPLES: "robot_quadrotor_fastphysics_sensors.jsonc",
}
# each battery at start: percent remaining, and seconds left at its drain rate (the example's battery
# gives no drain rate: the server's default is 0.02 per second)
BATTERY_AT_START = {
    PROJECT: (100 * 45000 / 50000, int(45000 / 2.5)),
    EXAMPLES: (100 * 30000 / 36000, int(30000 / 0.02)),
}


@pytest.fixture(scope="module", params=both_configs())
def real_sensors(request: pytest.FixtureRequest) -> tuple[str, dict[str, dict]]:
    """The survey quadrotor's instruments by type, and the example sensor quadrotor's where present."""
    return request.param, {s["type"]: s for s in robot_sensors(request.param, INSTRUMENT_ROBOT)}


@pytest.fixture
def sensors(real_sensors) -> dict[str, dict]:
    return real_sensors[1]


def kin(position=(0.0, 0.0, -4.0), rpy=(0.0, 0.0, 0.0), velocity=(0, 0, 0), rates=(0, 0, 0), accel=(0, 0, 0)):
    return Kinematics(
        position=np.array(position, float),
        orientation=quat_from_rpy(*rpy),
        linear_velocity=np.array(velocity, float),
        angular_velocity=np.array(rates, float),
        linear_acceleration=np.array(accel, float),
    )


def test_imu_at_rest_and_level_reads_minus_g_on_z_and_no_rotation(sensors):
    msg = imu_message(kin(), sensors["imu"], 123)
    assert set(msg) == {"time_stamp", "orientation", "angular_velocity", "linear_acceleration"}
    assert msg["time_stamp"] == 123
    assert msg["linear_acceleration"] == pytest.approx({"x": 0.0, "y": 0.0, "z": -GRAVITY})
    assert msg["angular_velocity"] == pytest.approx({"x": 0.0, "y": 0.0, "z": 0.0})
    assert msg["orientation"] == pytest.approx({"w": 1.0, "x": 0.0, "y": 0.0, "z": 0.0})


def test_imu_reports_body_frame_rates_and_specific_force(sensors):
    state = kin(rpy=(0.0, 0.0, math.pi / 2), rates=(0.0, 0.0, 0.5), accel=(0.0, 2.0, 0.0))
    msg = imu_message(state, sensors["imu"], 0)
    assert msg["angular_velocity"] == pytest.approx({"x": 0.0, "y": 0.0, "z": 0.5}, abs=1e-12)
    # facing east, an eastward acceleration is forward in the body frame
    assert msg["linear_acceleration"] == pytest.approx({"x": 2.0, "y": 0.0, "z": -GRAVITY}, abs=1e-12)
    pitched = imu_message(kin(rpy=(0.0, math.radians(30), 0.0)), sensors["imu"], 0)["linear_acceleration"]
    assert pitched["x"] == pytest.approx(GRAVITY * math.sin(math.radians(30)))  # nose up: gravity pulls back


def test_gps_at_home_reports_the_home_point_and_converges_to_a_3d_fix(sensors):
    cfg = sensors["gps"]
    early = gps_message(kin(position=(0, 0, 0)), HOME, cfg, 0)
    assert set(early) == {
        "time_stamp",
        "time_utc_millis",
        "latitude",
        "longitude",
        "altitude",
        "epv",
        "eph",
        "position_cov_type",
        "fix_type",
        "velocity",
    }
    assert (early["latitude"], early["longitude"], early["altitude"]) == pytest.approx(HOME)
    assert early["eph"] == pytest.approx(cfg["eph-initial"]) and early["fix_type"] == 0
    late = gps_message(kin(position=(0, 0, 0)), HOME, cfg, 20 * 10**9)
    assert late["eph"] == pytest.approx(cfg["eph-final"], abs=1e-6) and late["fix_type"] == 3
    assert late["time_utc_millis"] == 20_000


def test_gps_latitude_and_longitude_move_with_north_and_east_offsets(sensors):
    msg = gps_message(kin(position=(1000.0, 1000.0, -50.0), velocity=(1, 2, 3)), HOME, sensors["gps"], 0)
    assert msg["latitude"] - HOME[0] == pytest.approx(1000.0 / 111_200.0, rel=5e-3)
    east_deg = 1000.0 / (111_320.0 * math.cos(math.radians(HOME[0])))
    assert msg["longitude"] - HOME[1] == pytest.approx(east_deg, rel=5e-3)
    assert msg["altitude"] == pytest.approx(172.0)
    assert msg["velocity"] == {"x": 1.0, "y": 2.0, "z": 3.0}


def test_barometer_reports_altitude_standard_pressure_and_the_configured_qnh(sensors):
    cfg = sensors["barometer"]
    msg = barometer_message(kin(position=(0, 0, -10.0)), HOME, cfg, 5)
    assert set(msg) == {"time_stamp", "altitude", "pressure", "qnh"}
    assert msg["altitude"] == pytest.approx(132.0) and msg["qnh"] == cfg["qnh"]
    assert 99_500 < msg["pressure"] < 100_000
    sea = barometer_message(kin(position=(0, 0, 0)), (0.0, 0.0, 0.0), cfg, 0)
    assert sea["pressure"] == pytest.approx(101325.0)
    higher = barometer_message(kin(position=(0, 0, -110.0)), HOME, cfg, 0)
    assert msg["pressure"] - higher["pressure"] == pytest.approx(100 * 1.18 * GRAVITY, rel=0.05)


def test_magnetometer_rotates_the_earth_field_into_the_body_frame(sensors):
    cfg = sensors["magnetometer"]
    level = magnetometer_message(kin(), cfg, 0)
    assert set(level) == {"time_stamp", "magnetic_field_body", "magnetic_field_covariance"}
    assert level["magnetic_field_body"] == pytest.approx(dict(zip("xyz", MAGNETIC_FIELD_NED)))
    east = magnetometer_message(kin(rpy=(0, 0, math.pi / 2)), cfg, 0)["magnetic_field_body"]
    north, eastward, down = MAGNETIC_FIELD_NED
    assert east == pytest.approx({"x": eastward, "y": -north, "z": down}, abs=1e-12)
    sigma = np.array(cfg["noise-sigma"].split(), dtype=float)
    assert level["magnetic_field_covariance"] == pytest.approx(np.diag(sigma**2).ravel().tolist())


def test_the_downward_distance_sensor_measures_the_height_above_the_ground(sensors):
    world = load_world()
    cfg = sensors["distance-sensor"]  # pitched -90 deg, mounted 0.15 m (project) or 0.2 m below the body
    assert cfg["origin"]["rpy-deg"].split() == ["0", "-90", "0"]
    below = float(cfg["origin"]["xyz"].split()[2])
    msg = distance_message(world, kin(position=(-40.0, 40.0, -4.0)), cfg, 7)
    assert set(msg) == {"time_stamp", "current_distance", "pose"}
    assert msg["current_distance"] == pytest.approx(4.0 - below, abs=1e-4)
    assert msg["pose"]["position"] == pytest.approx({"x": -40.0, "y": 40.0, "z": -4.0 + below})
    far = distance_message(world, kin(position=(-40.0, 40.0, -80.0)), cfg, 7)
    assert far["current_distance"] == cfg["max-distance"]
    near = distance_message(world, kin(position=(-40.0, 40.0, -0.3)), cfg, 7)
    assert near["current_distance"] == cfg["min-distance"]


def test_battery_discharges_linearly_and_changes_state_when_low(real_sensors):
    source, sensors = real_sensors
    cfg = sensors["battery"]
    percent, seconds = BATTERY_AT_START[source]
    start = battery_message(0, cfg, 0.0)
    assert set(start) == {
        "time_stamp",
        "battery_pct_remaining",
        "estimated_time_remaining",
        "battery_charge_state",
    }
    assert start["battery_pct_remaining"] == pytest.approx(percent)
    assert start["battery_charge_state"] == "BATTERY_CHARGE_STATE_OK"
    assert start["estimated_time_remaining"] == seconds
    simple = {
        "total-battery-capacity": 100,
        "battery-capacity-on-start": 30,
        "battery-drain-rate-on-start": 1.0,
    }
    assert battery_message(0, simple, 15.0)["battery_pct_remaining"] == pytest.approx(15.0)
    assert battery_message(0, simple, 15.0)["battery_charge_state"] == "BATTERY_CHARGE_STATE_LOW"
    assert battery_message(0, simple, 27.0)["battery_charge_state"] == "BATTERY_CHARGE_STATE_CRITICAL"
    assert battery_message(0, simple, 99.0)["battery_pct_remaining"] == 0.0


def test_airspeed_is_the_dynamic_pressure_of_the_forward_speed(sensors):
    cfg = sensors["airspeed"]
    msg = airspeed_message(
        kin(position=(0, 0, 0), rpy=(0, 0, math.pi / 2), velocity=(0.0, 10.0, 0.0)), cfg, 1
    )
    assert set(msg) == {"time_stamp", "diff_pressure"}
    assert msg["diff_pressure"] == pytest.approx(0.5 * 1.225 * 100.0)
    backwards = airspeed_message(kin(velocity=(-10.0, 0.0, 0.0)), cfg, 1)
    assert backwards["diff_pressure"] == 0.0


@pytest.mark.parametrize(
    ("call", "message"),
    [
        (
            lambda: magnetometer_message(kin(), {"id": "Mag", "noise-sigma": "0.1 0.1"}, 0),
            "sensor 'Mag': 'noise-sigma' must be a string of three numbers, got '0.1 0.1'",
        ),
        (
            lambda: barometer_message(kin(), HOME, {"id": "Baro", "qnh": "high"}, 0),
            "sensor 'Baro': 'qnh' must be a finite number, got 'high'",
        ),
        (
            lambda: battery_message(0, {"id": "Bat", "total-battery-capacity": 0}, 0.0),
            "sensor 'Bat': 'total-battery-capacity' must be positive",
        ),
    ],
)
def test_invalid_instrument_configs_are_refused_naming_sensor_and_key(call, message):
    with pytest.raises(InstrumentError) as caught:
        call()
    assert str(caught.value) == message


class RecordingHub:
    """The part of TopicHub an instrument stream uses: everything is subscribed, publishes are kept."""

    def __init__(self) -> None:
        self.published: list[tuple[str, dict]] = []

    def is_subscribed(self, _path: str) -> bool:
        return True

    def publish(self, path: str, message: dict) -> None:
        self.published.append((path, message))

    def offer(self, path: str, make) -> bool:
        self.publish(path, make())
        return True


def test_a_robots_instruments_publish_every_tick_from_one_snapshot_of_the_body(monkeypatch):
    from types import SimpleNamespace

    from airsim_mapper.simserver.motion.motion import Body
    from airsim_mapper.simserver.robot.robots import RobotRuntime
    from airsim_mapper.simserver.scene.config import SensorSpec
    from airsim_mapper.simserver.sensors.sensor_streams import InstrumentStream

    body = Body(np.array([0.0, 0.0, -4.0]), quat_from_rpy(0.0, 0.0, 0.0), lambda _p: 0.0)
    snapshots = []
    original = body.snapshot
    monkeypatch.setattr(body, "snapshot", lambda: snapshots.append(1) or original())
    hub = RecordingHub()
    world = load_world(None)
    configs = {
        "imu": {"update-frequency": 10},  # read by the real barometer only, and unused there: ignored
        "gps": {},
        "barometer": {"update-frequency": 10},
        "distance-sensor": {"report-frequency": 50},  # the distance sensor does keep its report rate
    }
    robot = SimpleNamespace(
        body=body,
        spec=SimpleNamespace(multirotor=False),
        instruments=[
            InstrumentStream(SensorSpec(k, k, cfg), "/r", body, world, hub, HOME, 0)
            for k, cfg in configs.items()
        ],
    )
    RobotRuntime.step_instruments(robot, 0)  # the first tick: everything reports, from one snapshot
    assert (len(hub.published), len(snapshots)) == (4, 1)
    RobotRuntime.step_instruments(robot, 3_000_000)  # a 3 ms tick: all but the 50 Hz distance sensor
    assert [path for path, _ in hub.published[4:]] == ["/r/imu_kinematics", "/r/gps", "/r/barometer"]
    assert len(snapshots) == 2
    RobotRuntime.step_instruments(robot, 3_000_000)  # the same time again: nothing, the body is not read
    assert (len(hub.published), len(snapshots)) == (7, 2)
    for k in range(2, 8):  # the distance sensor reports once 20 ms have passed
        RobotRuntime.step_instruments(robot, k * 3_000_000)
    distance = [m["time_stamp"] for path, m in hub.published if path == "/r/distance_sensor"]
    assert distance == [0, 21_000_000]


def test_the_report_timer_keeps_the_real_sensors_rate_on_average():
    from airsim_mapper.simserver.sensors.sensor_streams import ReportTimer

    every = ReportTimer(None)
    assert [every.due(t) for t in (0, 3, 3, 6)] == [True, True, False, True]
    ten_hz = ReportTimer(10.0)
    reports = [t for t in range(0, 1_000_000_001, 3_000_000) if ten_hz.due(t)]
    # set back by each overshoot: 0, 102, 201, 300, ..., 900 ms: ten a second, none at a 3 ms gap
    assert [r // 1_000_000 for r in reports[:4]] == [0, 102, 201, 300]
    assert len(reports) == 10 and min(b - a for a, b in zip(reports, reports[1:])) >= 99_000_000
