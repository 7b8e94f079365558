"""IMU, GPS, barometer, magnetometer, distance, battery and airspeed conversions."""

from __future__ import annotations

import math

import pytest
from sensor_msgs.msg import BatteryState, NavSatFix, NavSatStatus, Range

from airsim_mapper.convert.context import ConvertContext
from airsim_mapper.convert.errors import ConversionError
from airsim_mapper.convert.instruments import airspeed, barometer, battery, distance, gps, imu, magnetometer

CTX = ConvertContext(frame_id="airsim_node/Drone1/sensor")
ENU = ConvertContext(convention="enu")
H = math.sqrt(0.5)


def imu_msg(**over):
    msg = {
        "time_stamp": 2_000_000_000,
        "orientation": {"w": 1.0, "x": 0.0, "y": 0.0, "z": 0.0},
        "angular_velocity": {"x": 0.1, "y": 0.2, "z": 0.3},
        "linear_acceleration": {"x": 0.0, "y": 0.5, "z": -9.8},
    }
    msg.update(over)
    return msg


def gps_msg(**over):
    msg = {
        "time_stamp": 1,
        "time_utc_millis": 1_700_000_000_000,
        "latitude": 47.641468,
        "longitude": -122.140165,
        "altitude": 122.0,
        "epv": 0.2,
        "eph": 0.1,
        "position_cov_type": 0,
        "fix_type": 3,
        "velocity": {"x": 0.0, "y": 0.0, "z": 0.0},
    }
    msg.update(over)
    return msg


def test_imu_ned_passes_values_through_with_unknown_covariances(roundtrip):
    msg = imu(imu_msg(), CTX)
    o, w, a = msg.orientation, msg.angular_velocity, msg.linear_acceleration
    assert (o.w, o.x, o.y, o.z) == (1.0, 0.0, 0.0, 0.0)
    assert (w.x, w.y, w.z) == (0.1, 0.2, 0.3)
    assert (a.x, a.y, a.z) == (0.0, 0.5, -9.8)
    assert list(msg.orientation_covariance) == [0.0] * 9
    assert msg.header.stamp.secs == 2 and msg.header.frame_id == CTX.frame_id
    assert roundtrip(msg) == msg


def test_imu_enu_converts_attitude_and_body_vectors_to_flu():
    msg = imu(imu_msg(), ENU)
    o, w, a = msg.orientation, msg.angular_velocity, msg.linear_acceleration
    assert (o.w, o.x, o.y, o.z) == pytest.approx((H, 0.0, 0.0, H))  # north-facing: ENU yaw +90
    assert (w.x, w.y, w.z) == pytest.approx((0.1, -0.2, -0.3))
    assert (a.x, a.y, a.z) == pytest.approx((0.0, -0.5, 9.8))


def test_imu_covariance_lists_are_fresh_per_message_and_field():
    first, second = imu(imu_msg(), CTX), imu(imu_msg(), CTX)
    assert first.orientation_covariance is not second.orientation_covariance
    assert first.orientation_covariance is not first.angular_velocity_covariance
    first.angular_velocity_covariance[0] = 5.0
    assert second.angular_velocity_covariance[0] == 0.0 and first.linear_acceleration_covariance[0] == 0.0


def test_imu_without_orientation_marks_it_not_provided():
    msg = imu(imu_msg(), ConvertContext(params={"orientation": False}))
    assert msg.orientation_covariance[0] == -1.0
    assert (msg.orientation.x, msg.orientation.w) == (0.0, 0.0)


def test_imu_variances_fill_diagonals():
    msg = imu(imu_msg(), ConvertContext(params={"angular_velocity_variance": 0.01}))
    assert list(msg.angular_velocity_covariance) == [0.01, 0, 0, 0, 0.01, 0, 0, 0, 0.01]


def test_imu_without_angular_velocity_is_rejected():
    msg = imu_msg()
    del msg["angular_velocity"]
    with pytest.raises(ConversionError, match=r"imu: message has no 'angular_velocity'"):
        imu(msg, CTX)


def test_imu_with_nan_acceleration_is_rejected():
    with pytest.raises(ConversionError, match=r"imu: linear_acceleration.y must be finite, got nan"):
        imu(imu_msg(linear_acceleration={"x": 0, "y": float("nan"), "z": 0}), CTX)


def test_gps_3d_fix_with_covariance_from_eph_and_epv(roundtrip):
    msg = gps(gps_msg(), CTX)
    assert msg.status.status == NavSatStatus.STATUS_FIX
    assert msg.status.service == NavSatStatus.SERVICE_GPS
    assert (msg.latitude, msg.longitude, msg.altitude) == (47.641468, -122.140165, 122.0)
    assert list(msg.position_covariance) == pytest.approx([0.01, 0, 0, 0, 0.01, 0, 0, 0, 0.04])
    assert msg.position_covariance_type == NavSatFix.COVARIANCE_TYPE_APPROXIMATED
    assert roundtrip(msg) == msg


@pytest.mark.parametrize(("fix_type", "status"), [(0, -1), (1, -1), (2, 0), (3, 0)])
def test_gps_status_follows_fix_type(fix_type, status):
    assert gps(gps_msg(fix_type=fix_type), CTX).status.status == status


def test_gps_without_eph_has_unknown_covariance():
    msg = gps_msg()
    del msg["eph"]
    out = gps(msg, CTX)
    assert out.position_covariance_type == NavSatFix.COVARIANCE_TYPE_UNKNOWN
    assert list(out.position_covariance) == [0.0] * 9


def test_gps_with_zero_eph_has_unknown_covariance():
    assert gps(gps_msg(eph=0.0), CTX).position_covariance_type == NavSatFix.COVARIANCE_TYPE_UNKNOWN


def test_gps_without_latitude_is_rejected():
    msg = gps_msg()
    del msg["latitude"]
    with pytest.raises(ConversionError, match=r"gps: message has no 'latitude'"):
        gps(msg, CTX)


def test_gps_with_non_integer_fix_type_is_rejected():
    with pytest.raises(ConversionError, match=r"gps: fix_type must be an integer, got '3D'"):
        gps(gps_msg(fix_type="3D"), CTX)


def test_barometer_pressure_is_in_pascals(roundtrip):
    msg = barometer({"time_stamp": 3, "altitude": 120.0, "pressure": 99_887.5, "qnh": 1013.25}, CTX)
    assert (msg.fluid_pressure, msg.variance) == (99_887.5, 0.0)
    assert roundtrip(msg) == msg


def test_barometer_variance_comes_from_params():
    msg = barometer({"time_stamp": 3, "pressure": 1.0}, ConvertContext(params={"variance": 7.29}))
    assert msg.variance == 7.29


def test_barometer_without_pressure_is_rejected():
    with pytest.raises(ConversionError, match=r"barometer: message has no 'pressure'"):
        barometer({"time_stamp": 3, "altitude": 1.0}, CTX)


def test_airspeed_differential_pressure_in_pascals():
    assert airspeed({"time_stamp": 3, "diff_pressure": 61.25}, CTX).fluid_pressure == 61.25


def test_airspeed_with_infinite_pressure_is_rejected():
    with pytest.raises(ConversionError, match=r"airspeed: diff_pressure must be finite, got inf"):
        airspeed({"time_stamp": 3, "diff_pressure": float("inf")}, CTX)


def mag_msg(cov=None):
    return {
        "time_stamp": 4,
        "magnetic_field_body": {"x": 0.2, "y": -0.05, "z": 0.4},
        "magnetic_field_covariance": [0.0] * 9 if cov is None else cov,
    }


def test_magnetometer_converts_gauss_to_tesla(roundtrip):
    msg = magnetometer(mag_msg([1e-4, 0, 0, 0, 2e-4, 0, 0, 0, 3e-4]), CTX)
    f = msg.magnetic_field
    assert (f.x, f.y, f.z) == pytest.approx((2e-5, -5e-6, 4e-5))
    assert list(msg.magnetic_field_covariance) == pytest.approx([1e-12, 0, 0, 0, 2e-12, 0, 0, 0, 3e-12])
    assert roundtrip(msg) == msg


def test_magnetometer_enu_is_flu_and_covariance_cross_terms_follow():
    msg = magnetometer(mag_msg([1.0, 0.5, 0, 0.5, 1.0, 0, 0, 0, 1.0]), ENU)
    f = msg.magnetic_field
    assert (f.x, f.y, f.z) == pytest.approx((2e-5, 5e-6, -4e-5))
    assert msg.magnetic_field_covariance[1] == pytest.approx(-0.5e-8)


def test_magnetometer_without_covariance_reports_unknown():
    msg = mag_msg()
    del msg["magnetic_field_covariance"]
    assert list(magnetometer(msg, CTX).magnetic_field_covariance) == [0.0] * 9


def test_magnetometer_with_a_short_covariance_is_rejected():
    with pytest.raises(ConversionError, match=r"magnetometer: magnetic_field_covariance must hold 9 numbers"):
        magnetometer(mag_msg([1.0, 2.0]), CTX)


def test_magnetometer_without_field_is_rejected():
    with pytest.raises(ConversionError, match=r"magnetometer: message has no 'magnetic_field_body'"):
        magnetometer({"time_stamp": 1}, CTX)


def test_distance_uses_sensor_limits(roundtrip):
    ctx = ConvertContext(source={"min-distance": 0.5, "max-distance": 50.0})
    msg = distance({"time_stamp": 9, "current_distance": 12.5, "pose": {}}, ctx)
    assert (msg.range, msg.min_range, msg.max_range) == (12.5, 0.5, 50.0)
    assert msg.radiation_type == Range.INFRARED and msg.field_of_view == 0.0
    assert roundtrip(msg) == msg


def test_distance_defaults_limits_and_allows_infinite_no_return():
    msg = distance({"time_stamp": 9, "current_distance": float("inf")}, CTX)
    assert (msg.min_range, msg.max_range) == (0.2, 40.0)
    assert math.isinf(msg.range)


def test_distance_nan_is_rejected():
    with pytest.raises(ConversionError, match=r"distance: current_distance must not be NaN"):
        distance({"time_stamp": 9, "current_distance": float("nan")}, CTX)


def battery_msg(state="BATTERY_CHARGE_STATE_OK", pct=83.0):
    return {
        "time_stamp": 5,
        "battery_pct_remaining": pct,
        "estimated_time_remaining": 1200,
        "battery_charge_state": state,
    }


def test_battery_percentage_is_a_fraction_and_unmeasured_values_are_nan(roundtrip):
    ctx = ConvertContext(variables={"sensor_name": "Battery"})
    msg = battery(battery_msg(), ctx)
    assert msg.percentage == pytest.approx(0.83)
    assert math.isnan(msg.voltage) and math.isnan(msg.current) and math.isnan(msg.capacity)
    assert msg.power_supply_status == BatteryState.POWER_SUPPLY_STATUS_DISCHARGING
    assert msg.power_supply_health == BatteryState.POWER_SUPPLY_HEALTH_GOOD
    assert msg.present is True and msg.location == "Battery"
    copy = roundtrip(msg)
    assert copy.percentage == pytest.approx(0.83)


@pytest.mark.parametrize(
    ("state", "health"),
    [
        ("BATTERY_CHARGE_STATE_LOW", BatteryState.POWER_SUPPLY_HEALTH_GOOD),
        ("BATTERY_CHARGE_STATE_UNHEALTHY", BatteryState.POWER_SUPPLY_HEALTH_UNSPEC_FAILURE),
        ("INVALID_STATE", BatteryState.POWER_SUPPLY_HEALTH_UNKNOWN),
    ],
)
def test_battery_health_follows_the_charge_state(state, health):
    assert battery(battery_msg(state), CTX).power_supply_health == health


def test_battery_with_a_numeric_state_is_rejected():
    with pytest.raises(ConversionError, match=r"battery: battery_charge_state must be a string, got 1"):
        battery(battery_msg(state=1), CTX)


def test_battery_with_nan_percentage_is_rejected():
    with pytest.raises(ConversionError, match=r"battery: battery_pct_remaining must be finite, got nan"):
        battery(battery_msg(pct=float("nan")), CTX)
