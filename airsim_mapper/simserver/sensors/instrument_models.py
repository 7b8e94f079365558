"""Instrument messages (imu, gps, barometer, magnetometer, distance sensor, battery, airspeed).

Keys follow the real Project AirSim messages (core_sim/src/message/*_message.cpp, MSGPACK_DEFINE_MAP):
  imu_kinematics  {time_stamp, orientation, angular_velocity, linear_acceleration}
  gps             {time_stamp, time_utc_millis, latitude, longitude, altitude, epv, eph,
                   position_cov_type, fix_type, velocity}
  barometer       {time_stamp, altitude, pressure, qnh}
  magnetometer    {time_stamp, magnetic_field_body, magnetic_field_covariance}
  distance_sensor {time_stamp, current_distance, pose}
  battery         {time_stamp, battery_pct_remaining, estimated_time_remaining, battery_charge_state}
  airspeed        {time_stamp, diff_pressure}
Values are noise-free ground truth derived from the kinematics (the configs' noise parameters are read
where they shape a value, e.g. GPS eph/epv convergence, magnetometer covariance). Vectors are
{x, y, z}, quaternions {w, x, y, z}; body vectors are FRD, world vectors NED.
"""

from __future__ import annotations

import functools
import math
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from airsim_mapper.common.geometry import compose, parse_origin, quat_to_matrix
from airsim_mapper.simserver.errors import SimServerError
from airsim_mapper.simserver.world.world import World

GRAVITY = 9.80665  # m/s^2, NED +z
EARTH_EQUATORIAL_RADIUS = 6378137.0
EARTH_FLATTENING = 1.0 / 298.257223563
SEA_LEVEL_PRESSURE = 101325.0  # Pa
SEA_LEVEL_DENSITY = 1.225  # kg/m^3
# Earth's magnetic field in gauss, NED, roughly that of the default home point (Redmond, WA)
MAGNETIC_FIELD_NED = np.array([0.186, 0.052, 0.497])
GNSS_FIX_NO_FIX, GNSS_FIX_2D_FIX, GNSS_FIX_3D_FIX = 0, 2, 3
BATTERY_OK, BATTERY_LOW, BATTERY_CRITICAL = (
    "BATTERY_CHARGE_STATE_OK",
    "BATTERY_CHARGE_STATE_LOW",
    "BATTERY_CHARGE_STATE_CRITICAL",
)


class InstrumentError(SimServerError, ValueError):
    """An instrument config value is invalid; the message names the sensor and the key."""


@dataclass
class Kinematics:
    """Ground-truth robot state, world NED: metres, m/s, m/s^2, rad/s, rad/s^2; orientation w, x, y, z."""

    position: np.ndarray = field(default_factory=lambda: np.zeros(3))
    orientation: np.ndarray = field(default_factory=lambda: np.array([1.0, 0.0, 0.0, 0.0]))
    linear_velocity: np.ndarray = field(default_factory=lambda: np.zeros(3))
    angular_velocity: np.ndarray = field(default_factory=lambda: np.zeros(3))
    linear_acceleration: np.ndarray = field(default_factory=lambda: np.zeros(3))
    angular_acceleration: np.ndarray = field(default_factory=lambda: np.zeros(3))


def _vec(v: np.ndarray) -> dict[str, float]:
    return {"x": float(v[0]), "y": float(v[1]), "z": float(v[2])}


def _quat(q: np.ndarray) -> dict[str, float]:
    return {"w": float(q[0]), "x": float(q[1]), "y": float(q[2]), "z": float(q[3])}


def _number(cfg: Mapping[str, Any], key: str, default: float) -> float:
    value = cfg.get(key, default)
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
        sensor = cfg.get("id", "<sensor>")
        raise InstrumentError(f"sensor {sensor!r}: {key!r} must be a finite number, got {value!r}")
    return float(value)


@functools.lru_cache(maxsize=256)
def _three_numbers(value: str) -> tuple[float, ...]:
    """The numbers of a config string (parsed once per distinct string: instruments publish every tick)."""
    try:
        return tuple(float(p) for p in value.split())
    except ValueError:
        return ()


def _three(cfg: Mapping[str, Any], key: str, default: str) -> np.ndarray:
    value = cfg.get(key, default)
    numbers = np.array(_three_numbers(value) if isinstance(value, str) else ())
    if numbers.size != 3 or not np.isfinite(numbers).all():
        sensor = cfg.get("id", "<sensor>")
        raise InstrumentError(f"sensor {sensor!r}: {key!r} must be a string of three numbers, got {value!r}")
    return numbers


def body_vector(kin: Kinematics, world_vector: np.ndarray) -> np.ndarray:
    """A world NED vector expressed in the body FRD frame."""
    return np.asarray(world_vector, dtype=float) @ quat_to_matrix(kin.orientation)


def altitude_of(kin: Kinematics, home_geo: tuple[float, float, float]) -> float:
    """Metres above mean sea level (home altitude minus NED z)."""
    return float(home_geo[2] - kin.position[2])


def ned_to_geodetic(position: np.ndarray, home_geo: tuple[float, float, float]) -> tuple[float, float, float]:
    """Latitude, longitude (deg) and altitude (m) of a NED offset from the home point (local ellipsoid)."""
    lat0 = math.radians(home_geo[0])
    e2 = EARTH_FLATTENING * (2.0 - EARTH_FLATTENING)
    w = math.sqrt(1.0 - e2 * math.sin(lat0) ** 2)
    meridian = EARTH_EQUATORIAL_RADIUS * (1.0 - e2) / w**3
    normal = EARTH_EQUATORIAL_RADIUS / w
    lat = home_geo[0] + math.degrees(position[0] / meridian)
    lon = home_geo[1] + math.degrees(position[1] / (normal * math.cos(lat0)))
    return lat, lon, float(home_geo[2] - position[2])


def pressure_at(altitude_m: float) -> float:
    """International Standard Atmosphere static pressure (Pa) at an altitude above sea level."""
    return SEA_LEVEL_PRESSURE * (1.0 - 2.25577e-5 * altitude_m) ** 5.25588


def density_at(altitude_m: float) -> float:
    """International Standard Atmosphere air density (kg/m^3) at an altitude above sea level."""
    return SEA_LEVEL_DENSITY * (1.0 - 2.25577e-5 * altitude_m) ** 4.25588


def imu_message(kin: Kinematics, sensor_cfg: Mapping[str, Any], t_ns: int) -> dict:
    """Orientation, body angular velocity and body specific force (reads -g on z when at rest, level)."""
    rotation = quat_to_matrix(kin.orientation)  # world vectors in the body frame: v @ rotation
    specific_force = (np.asarray(kin.linear_acceleration, dtype=float) - [0.0, 0.0, GRAVITY]) @ rotation
    return {
        "time_stamp": int(t_ns),
        "orientation": _quat(kin.orientation),
        "angular_velocity": _vec(np.asarray(kin.angular_velocity, dtype=float) @ rotation),
        "linear_acceleration": _vec(specific_force),
    }


def gps_message(
    kin: Kinematics, home_geo: tuple[float, float, float], sensor_cfg: Mapping[str, Any], t_ns: int
) -> dict:
    """Position fix; eph/epv converge from their initial to final values with their time constants."""
    seconds = int(t_ns) / 1e9

    def converge(kind: str) -> float:
        initial = _number(sensor_cfg, f"{kind}-initial", 100.0)
        final = _number(sensor_cfg, f"{kind}-final", 0.1)
        tau = _number(sensor_cfg, f"{kind}-time-constant", 0.9)
        return final + (initial - final) * math.exp(-seconds / tau) if tau > 0 else final

    eph, epv = converge("eph"), converge("epv")
    if eph <= _number(sensor_cfg, "eph-min_3d", 3.0):
        fix = GNSS_FIX_3D_FIX
    elif eph <= _number(sensor_cfg, "eph-min_2d", 4.0):
        fix = GNSS_FIX_2D_FIX
    else:
        fix = GNSS_FIX_NO_FIX
    lat, lon, alt = ned_to_geodetic(kin.position, home_geo)
    return {
        "time_stamp": int(t_ns),
        "time_utc_millis": int(t_ns) // 1_000_000,
        "latitude": lat,
        "longitude": lon,
        "altitude": alt,
        "epv": epv,
        "eph": eph,
        "position_cov_type": 0,
        "fix_type": fix,
        "velocity": _vec(kin.linear_velocity),
    }


def barometer_message(
    kin: Kinematics, home_geo: tuple[float, float, float], cfg: Mapping[str, Any], t_ns: int
) -> dict:
    """Altitude above sea level (m), standard-atmosphere pressure (Pa) and the configured QNH (hPa)."""
    altitude = altitude_of(kin, home_geo)
    return {
        "time_stamp": int(t_ns),
        "altitude": altitude,
        "pressure": pressure_at(altitude),
        "qnh": _number(cfg, "qnh", 1013.25),
    }


def magnetometer_message(kin: Kinematics, cfg: Mapping[str, Any], t_ns: int) -> dict:
    """Earth's field in the body frame (gauss), scaled and biased; covariance = noise-sigma squared."""
    scale = _number(cfg, "scale-factor", 1.0)
    bias = _three(cfg, "noise-bias", "0 0 0")
    sigma = _three(cfg, "noise-sigma", "0.005 0.005 0.005")
    field_body = body_vector(kin, MAGNETIC_FIELD_NED) * scale + bias
    covariance = np.diag(sigma**2).ravel()
    return {
        "time_stamp": int(t_ns),
        "magnetic_field_body": _vec(field_body),
        "magnetic_field_covariance": [float(v) for v in covariance],
    }


def distance_message(world: World, kin: Kinematics, cfg: Mapping[str, Any], t_ns: int) -> dict:
    """Range along the sensor's +x from its mount (config `origin`), clamped to [min, max]-distance.

    Nothing within `max-distance` reads `max-distance`. `pose` is the sensor's world pose.
    """
    low = _number(cfg, "min-distance", 0.2)
    high = _number(cfg, "max-distance", 40.0)
    mount_position, mount_orientation = parse_origin(cfg.get("origin"))
    position, orientation = compose(kin.position, kin.orientation, mount_position, mount_orientation)
    beam = quat_to_matrix(orientation)[:, 0]
    distance = world.range_along(position, beam, high)
    if distance is None:
        distance = high
    return {
        "time_stamp": int(t_ns),
        "current_distance": min(high, max(low, distance)),
        "pose": {"position": _vec(position), "orientation": _quat(orientation)},
    }


def battery_message(t_ns: int, cfg: Mapping[str, Any], elapsed_s: float) -> dict:
    """Linear discharge since the start (real server's simple-discharge model).

    `battery-drain-rate-on-start` (capacity units per second) sets the rate; the rotor-power mode, which
    needs rotor power, drains at the same default rate (0.02 units/s, as the real server defaults).
    """
    capacity = _number(cfg, "total-battery-capacity", 100.0)
    start = _number(cfg, "battery-capacity-on-start", capacity)
    rate = _number(cfg, "battery-drain-rate-on-start", 0.02)
    if capacity <= 0:
        raise InstrumentError(
            f"sensor {cfg.get('id', '<sensor>')!r}: 'total-battery-capacity' must be positive"
        )
    remaining = max(0.0, start - rate * max(0.0, elapsed_s))
    percent = 100.0 * remaining / capacity
    state = BATTERY_CRITICAL if percent < 5.0 else BATTERY_LOW if percent < 20.0 else BATTERY_OK
    return {
        "time_stamp": int(t_ns),
        "battery_pct_remaining": percent,
        "estimated_time_remaining": int(remaining / rate) if rate > 0 else 0,
        "battery_charge_state": state,
    }


def airspeed_message(kin: Kinematics, cfg: Mapping[str, Any], t_ns: int) -> dict:
    """Pitot differential pressure (Pa) = 1/2 rho v^2 of the still-air speed along `forward-xyz` (body)."""
    forward = _three(cfg, "forward-xyz", "1 0 0")
    norm = np.linalg.norm(forward)
    forward = forward / norm if norm > 0 else np.array([1.0, 0.0, 0.0])
    speed = max(0.0, float(body_vector(kin, kin.linear_velocity) @ forward))
    altitude = -float(kin.position[2])
    return {"time_stamp": int(t_ns), "diff_pressure": 0.5 * density_at(altitude) * speed * speed}
