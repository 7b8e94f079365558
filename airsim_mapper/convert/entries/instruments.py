"""The catalogue's clock and instrument entries: the sim clock, IMU, GPS, barometer, magnetometer,
distance sensor, battery and airspeed (all light, converted on the receive thread)."""

from __future__ import annotations

from airsim_mapper.convert.entries.model import (
    PUBLISH,
    SENSOR_DATA,
    SIM_TO_ROS,
    STAMP,
    Example,
    converter_info,
)

INSTRUMENTS = (
    converter_info(
        "clock",
        SIM_TO_ROS,
        ["rosgraph_msgs/Clock"],
        PUBLISH,
        "clock",
        "clock",
        "any stamped sim message -> Clock at its sim time",
        qos=SENSOR_DATA,
        inline=True,
        example=Example(STAMP),
    ),
    converter_info(
        "imu",
        SIM_TO_ROS,
        ["sensor_msgs/Imu"],
        PUBLISH,
        "instruments",
        "imu",
        "sim IMU -> Imu",
        qos=SENSOR_DATA,
        inline=True,
        example=Example(
            {
                **STAMP,
                "orientation": {"w": 1.0, "x": 0.0, "y": 0.0, "z": 0.0},
                "angular_velocity": {"x": 0.0, "y": 0.0, "z": 0.0},
                "linear_acceleration": {"x": 0.0, "y": 0.0, "z": -9.8},
            }
        ),
    ),
    converter_info(
        "gps",
        SIM_TO_ROS,
        ["sensor_msgs/NavSatFix"],
        PUBLISH,
        "instruments",
        "gps",
        "sim GPS -> NavSatFix",
        qos=SENSOR_DATA,
        inline=True,
        example=Example(
            {
                **STAMP,
                "latitude": 47.6,
                "longitude": -122.1,
                "altitude": 100.0,
                "fix_type": 3,
                "eph": 1.0,
                "epv": 2.0,
            }
        ),
    ),
    converter_info(
        "barometer",
        SIM_TO_ROS,
        ["sensor_msgs/FluidPressure"],
        PUBLISH,
        "instruments",
        "barometer",
        "sim Barometer -> FluidPressure (Pa)",
        qos=SENSOR_DATA,
        inline=True,
        example=Example({**STAMP, "pressure": 101325.0}),
    ),
    converter_info(
        "magnetometer",
        SIM_TO_ROS,
        ["sensor_msgs/MagneticField"],
        PUBLISH,
        "instruments",
        "magnetometer",
        "sim Magnetometer (gauss) -> MagneticField (tesla)",
        qos=SENSOR_DATA,
        inline=True,
        example=Example(
            {
                **STAMP,
                "magnetic_field_body": {"x": 0.2, "y": 0.0, "z": 0.4},
                "magnetic_field_covariance": [0.0] * 9,
            }
        ),
    ),
    converter_info(
        "distance",
        SIM_TO_ROS,
        ["sensor_msgs/Range"],
        PUBLISH,
        "instruments",
        "distance",
        "sim DistanceSensor -> Range",
        qos=SENSOR_DATA,
        inline=True,
        example=Example({**STAMP, "current_distance": 3.0}),
    ),
    converter_info(
        "battery",
        SIM_TO_ROS,
        ["sensor_msgs/BatteryState"],
        PUBLISH,
        "instruments",
        "battery",
        "sim Battery -> BatteryState",
        qos=SENSOR_DATA,
        inline=True,
        example=Example(
            {**STAMP, "battery_pct_remaining": 50.0, "battery_charge_state": "BATTERY_CHARGE_STATE_OK"}
        ),
    ),
    converter_info(
        "airspeed",
        SIM_TO_ROS,
        ["sensor_msgs/FluidPressure"],
        PUBLISH,
        "instruments",
        "airspeed",
        "sim Airspeed (differential pressure) -> FluidPressure (Pa)",
        qos=SENSOR_DATA,
        inline=True,
        example=Example({**STAMP, "diff_pressure": 3.0}),
    ),
)
