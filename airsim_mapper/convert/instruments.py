"""Project AirSim instrument messages -> sensor_msgs (IMU, GPS, barometer, magnetometer, distance,
battery, airspeed).

Sim fields (core_sim/src/message/*_message.cpp):
- IMU ``{time_stamp, orientation{w,x,y,z}, angular_velocity{x,y,z}, linear_acceleration{x,y,z}}``:
  orientation body->world NED; rates and accelerations in the body (FRD) frame.
- GPS ``{time_stamp, time_utc_millis, latitude, longitude, altitude, epv, eph, position_cov_type,
  fix_type, velocity}``: fix_type 0 none, 1 time only, 2 2D, 3 3D.
- Barometer ``{time_stamp, altitude, pressure (Pa), qnh (hPa)}``.
- Magnetometer ``{time_stamp, magnetic_field_body{x,y,z} (gauss), magnetic_field_covariance[9] (gauss²)}``.
- DistanceSensor ``{time_stamp, current_distance (m), pose}``; limits from the sensor config.
- Battery ``{time_stamp, battery_pct_remaining (0-100), estimated_time_remaining (s),
  battery_charge_state ("BATTERY_CHARGE_STATE_OK|LOW|CRITICAL|UNHEALTHY")}``.
- Airspeed ``{time_stamp, diff_pressure (Pa)}``.

Covariances follow REP-145: all zeros = unknown; -1 in element 0 = the quantity is not provided. Every
message gets freshly built lists (never a shared mutable default). Body vectors become FLU and the IMU
orientation ENU/FLU with the ENU convention.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import Any

import numpy as np
from geometry_msgs.msg import Quaternion, Vector3
from sensor_msgs.msg import BatteryState, FluidPressure, Imu, MagneticField, NavSatFix, NavSatStatus, Range

from airsim_mapper.convert import frames, sim_fields
from airsim_mapper.convert.context import ConvertContext
from airsim_mapper.convert.errors import ConversionError
from airsim_mapper.convert.stamps import sim_header

TESLA_PER_GAUSS = 1e-4
DEFAULT_MIN_RANGE_M = 0.2
DEFAULT_MAX_RANGE_M = 40.0
GNSS_FIX_2D = 2
CHARGE_STATE_HEALTH = {
    "BATTERY_CHARGE_STATE_OK": BatteryState.POWER_SUPPLY_HEALTH_GOOD,
    "BATTERY_CHARGE_STATE_LOW": BatteryState.POWER_SUPPLY_HEALTH_GOOD,
    "BATTERY_CHARGE_STATE_CRITICAL": BatteryState.POWER_SUPPLY_HEALTH_GOOD,
    "BATTERY_CHARGE_STATE_UNHEALTHY": BatteryState.POWER_SUPPLY_HEALTH_UNSPEC_FAILURE,
}


def unknown_covariance() -> list[float]:
    """REP-145 'covariance unknown': a fresh list of nine zeros."""
    return [0.0] * 9


def not_provided_covariance() -> list[float]:
    """REP-145 'quantity not provided': a fresh list with -1 in element 0."""
    return [-1.0] + [0.0] * 8


def diagonal_covariance(variance: Any, where: str) -> list[float]:
    """A fresh 3x3 diagonal covariance of a variance parameter (None = unknown)."""
    if variance is None:
        return unknown_covariance()
    value = sim_fields.number(variance, where)
    return [value, 0.0, 0.0, 0.0, value, 0.0, 0.0, 0.0, value]


def _vector(values: np.ndarray) -> Vector3:
    x, y, z = (float(v) for v in values)
    return Vector3(x=x, y=y, z=z)


def _body(values: np.ndarray, ctx: ConvertContext) -> np.ndarray:
    return frames.frd_to_flu(values) if ctx.enu else values


@sim_fields.converter("imu")
def imu(msg: Mapping[str, Any], ctx: ConvertContext) -> Imu:
    """sim IMU -> Imu. params: orientation (bool, default true), *_variance (diagonal covariances)."""
    q = sim_fields.quaternion(msg, "orientation")
    angular = sim_fields.vector3(msg, "angular_velocity")
    linear = sim_fields.vector3(msg, "linear_acceleration")
    has_orientation = bool(ctx.params.get("orientation", True))
    if ctx.enu:
        q = frames.ned_frd_to_enu_flu(q)
    w, x, y, z = (float(v) for v in q)
    return Imu(
        header=sim_header(msg, ctx),
        orientation=Quaternion(x=x, y=y, z=z, w=w)
        if has_orientation
        else Quaternion(x=0.0, y=0.0, z=0.0, w=0.0),
        orientation_covariance=(
            diagonal_covariance(ctx.params.get("orientation_variance"), "orientation_variance")
            if has_orientation
            else not_provided_covariance()
        ),
        angular_velocity=_vector(_body(angular, ctx)),
        angular_velocity_covariance=diagonal_covariance(
            ctx.params.get("angular_velocity_variance"), "angular_velocity_variance"
        ),
        linear_acceleration=_vector(_body(linear, ctx)),
        linear_acceleration_covariance=diagonal_covariance(
            ctx.params.get("linear_acceleration_variance"), "linear_acceleration_variance"
        ),
    )


def _gps_covariance(msg: Mapping[str, Any]) -> tuple[list[float], int]:
    """Diagonal (eph², eph², epv²) when both are present, finite and positive; else unknown."""
    if "eph" not in msg or "epv" not in msg:
        return unknown_covariance(), NavSatFix.COVARIANCE_TYPE_UNKNOWN
    eph = sim_fields.number(msg["eph"], "eph", finite=False)
    epv = sim_fields.number(msg["epv"], "epv", finite=False)
    if not (math.isfinite(eph) and math.isfinite(epv) and eph > 0.0 and epv > 0.0):
        return unknown_covariance(), NavSatFix.COVARIANCE_TYPE_UNKNOWN
    h, v = eph * eph, epv * epv
    return [h, 0.0, 0.0, 0.0, h, 0.0, 0.0, 0.0, v], NavSatFix.COVARIANCE_TYPE_APPROXIMATED


@sim_fields.converter("gps")
def gps(msg: Mapping[str, Any], ctx: ConvertContext) -> NavSatFix:
    """sim GPS -> NavSatFix: STATUS_FIX for a 2D/3D fix, else STATUS_NO_FIX; covariance from eph/epv."""
    latitude = sim_fields.number_field(msg, "latitude")
    longitude = sim_fields.number_field(msg, "longitude")
    altitude = sim_fields.number_field(msg, "altitude")
    fix_type = sim_fields.integer(sim_fields.field(msg, "fix_type"), "fix_type")
    covariance, covariance_type = _gps_covariance(msg)
    status = NavSatStatus(
        status=NavSatStatus.STATUS_FIX if fix_type >= GNSS_FIX_2D else NavSatStatus.STATUS_NO_FIX,
        service=NavSatStatus.SERVICE_GPS,
    )
    return NavSatFix(
        header=sim_header(msg, ctx),
        status=status,
        latitude=latitude,
        longitude=longitude,
        altitude=altitude,
        position_covariance=covariance,
        position_covariance_type=covariance_type,
    )


def _pressure(msg: Mapping[str, Any], ctx: ConvertContext, key: str) -> FluidPressure:
    variance = sim_fields.number(ctx.params.get("variance", 0.0), "variance")
    return FluidPressure(
        header=sim_header(msg, ctx), fluid_pressure=sim_fields.number_field(msg, key), variance=variance
    )


@sim_fields.converter("barometer")
def barometer(msg: Mapping[str, Any], ctx: ConvertContext) -> FluidPressure:
    """sim Barometer -> FluidPressure (static pressure, Pa); variance from params (0 = unknown)."""
    return _pressure(msg, ctx, "pressure")


@sim_fields.converter("airspeed")
def airspeed(msg: Mapping[str, Any], ctx: ConvertContext) -> FluidPressure:
    """sim Airspeed -> FluidPressure (differential pressure, Pa); variance from params (0 = unknown)."""
    return _pressure(msg, ctx, "diff_pressure")


@sim_fields.converter("magnetometer")
def magnetometer(msg: Mapping[str, Any], ctx: ConvertContext) -> MagneticField:
    """sim Magnetometer (gauss, body FRD) -> MagneticField (tesla); covariance scaled to T²."""
    field_gauss = sim_fields.vector3(msg, "magnetic_field_body")
    raw = msg.get("magnetic_field_covariance") or []
    if isinstance(raw, (str, Mapping)) or np.ndim(raw) != 1 or len(raw) not in (0, 9):
        raise ConversionError("magnetic_field_covariance must hold 9 numbers (or none)")
    covariance = np.zeros(9)
    if len(raw):
        covariance = np.array([sim_fields.number(v, "magnetic_field_covariance") for v in raw])
    covariance = covariance * (TESLA_PER_GAUSS**2)
    field_tesla = field_gauss * TESLA_PER_GAUSS
    if ctx.enu:
        field_tesla = frames.frd_to_flu(field_tesla)
        covariance = frames.frd_to_flu_covariance(covariance)
    return MagneticField(
        header=sim_header(msg, ctx),
        magnetic_field=_vector(field_tesla),
        magnetic_field_covariance=[float(v) for v in covariance],
    )


@sim_fields.converter("distance")
def distance(msg: Mapping[str, Any], ctx: ConvertContext) -> Range:
    """sim DistanceSensor -> Range (INFRARED, a single ray: field_of_view from params, default 0)."""
    current = sim_fields.number_field(msg, "current_distance", finite=False)
    if math.isnan(current):
        raise ConversionError("current_distance must not be NaN")
    min_range = sim_fields.number(ctx.source.get("min-distance", DEFAULT_MIN_RANGE_M), "min-distance")
    max_range = sim_fields.number(ctx.source.get("max-distance", DEFAULT_MAX_RANGE_M), "max-distance")
    fov = sim_fields.number(ctx.params.get("field_of_view", 0.0), "field_of_view")
    return Range(
        header=sim_header(msg, ctx),
        radiation_type=Range.INFRARED,
        field_of_view=fov,
        min_range=min_range,
        max_range=max_range,
        range=current,
    )


@sim_fields.converter("battery")
def battery(msg: Mapping[str, Any], ctx: ConvertContext) -> BatteryState:
    """sim Battery -> BatteryState: percentage 0..1, discharging; unmeasured quantities NaN."""
    percent = sim_fields.number_field(msg, "battery_pct_remaining")
    state = sim_fields.field(msg, "battery_charge_state")
    if not isinstance(state, str):
        raise ConversionError(f"battery_charge_state must be a string, got {state!r}")
    nan = float("nan")
    return BatteryState(
        header=sim_header(msg, ctx),
        voltage=nan,
        temperature=nan,
        current=nan,
        charge=nan,
        capacity=nan,
        design_capacity=nan,
        percentage=percent / 100.0,
        power_supply_status=BatteryState.POWER_SUPPLY_STATUS_DISCHARGING,
        power_supply_health=CHARGE_STATE_HEALTH.get(state, BatteryState.POWER_SUPPLY_HEALTH_UNKNOWN),
        power_supply_technology=BatteryState.POWER_SUPPLY_TECHNOLOGY_UNKNOWN,
        present=True,
        cell_voltage=[],
        cell_temperature=[],
        location=str(ctx.variables.get("sensor_name", "")),
        serial_number="",
    )
