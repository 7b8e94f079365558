"""Instruments, odometry and /clock of the default mapping, end to end on the sensors scene: units and
frames of every sensor the scene config declares, and sim time that a /use_sim_time node follows."""

from __future__ import annotations

import json
import math
import sys
import textwrap

import numpy as np
import pytest
from bridgeharness import Stack
from harness import wait_until

ROBOT = "/airsim_node/Drone1"
HOME_LAT, HOME_LON, HOME_ALT = 47.641468, -122.140165, 122.0
GRAVITY = 9.80665


@pytest.fixture(scope="module")
def rig(module_rig_factory) -> Stack:
    rig = module_rig_factory()
    rig.start_node(
        "--scene", "scene_drone_sensors.jsonc", node_name="extra_bridge", wait_for=f"{ROBOT}/IMU1/imu"
    )
    return rig


def receive(topic: str, cls, timeout: float = 20.0):
    import rospy

    return rospy.wait_for_message(topic, cls, timeout=timeout)


def test_imu_reads_minus_g_on_body_z_while_hovering_level(rig: Stack):
    from sensor_msgs.msg import Imu

    msg = receive(f"{ROBOT}/IMU1/imu", Imu)
    assert msg.header.frame_id == "airsim_node/Drone1"
    a, w, q = msg.linear_acceleration, msg.angular_velocity, msg.orientation
    assert (a.x, a.y, a.z) == pytest.approx((0.0, 0.0, -GRAVITY), abs=0.05)  # FRD specific force
    assert (w.x, w.y, w.z) == pytest.approx((0.0, 0.0, 0.0), abs=1e-3)
    assert (q.w, q.x, q.y, q.z) == pytest.approx((1.0, 0.0, 0.0, 0.0), abs=1e-3)


def test_gps_fixes_the_home_point_four_metres_up(rig: Stack):
    from sensor_msgs.msg import NavSatFix, NavSatStatus

    def fixed() -> NavSatFix | None:
        msg = receive(f"{ROBOT}/GPS/gps", NavSatFix)
        return msg if msg.status.status == NavSatStatus.STATUS_FIX else None

    wait_until(lambda: fixed() is not None, 20, what="a GPS fix")
    msg = fixed() or receive(f"{ROBOT}/GPS/gps", NavSatFix)
    assert msg.header.frame_id == "airsim_node/Drone1"
    assert (msg.latitude, msg.longitude) == pytest.approx((HOME_LAT, HOME_LON), abs=1e-6)
    assert msg.altitude == pytest.approx(HOME_ALT + 4.0, abs=0.1)
    assert msg.position_covariance_type == NavSatFix.COVARIANCE_TYPE_APPROXIMATED
    assert msg.position_covariance[0] > 0.0


def test_barometer_gives_standard_atmosphere_pascals_at_the_drones_altitude(rig: Stack):
    from sensor_msgs.msg import FluidPressure

    msg = receive(f"{ROBOT}/Barometer/barometer", FluidPressure)
    expected = 101325.0 * (1.0 - 2.25577e-5 * (HOME_ALT + 4.0)) ** 5.25588
    assert msg.fluid_pressure == pytest.approx(expected, rel=0.002)
    assert msg.header.frame_id == "airsim_node/Drone1"


def test_magnetometer_gives_earths_field_in_tesla(rig: Stack):
    from sensor_msgs.msg import MagneticField

    msg = receive(f"{ROBOT}/Magnetometer/magnetometer", MagneticField)
    field = np.array([msg.magnetic_field.x, msg.magnetic_field.y, msg.magnetic_field.z])
    assert 2e-5 < np.linalg.norm(field) < 7e-5  # tens of microtesla, not gauss
    assert field[2] > 0.0  # the northern hemisphere field points down (FRD z)
    assert msg.magnetic_field_covariance[0] == pytest.approx(0.005**2 * 1e-8)


def test_distance_sensor_ranges_to_the_ground_along_its_downward_x_axis(rig: Stack):
    import rospy
    import tf2_ros
    from sensor_msgs.msg import Range

    msg = receive(f"{ROBOT}/DistanceSensor/distance", Range)
    assert msg.header.frame_id == "airsim_node/Drone1/DistanceSensor"
    assert (msg.min_range, msg.max_range) == pytest.approx((0.2, 40.0))  # float32
    assert msg.range == pytest.approx(3.9, abs=0.05)  # mounted 0.1 m below the drone at 4 m
    buffer = tf2_ros.Buffer()
    tf2_ros.TransformListener(buffer)
    tf = buffer.lookup_transform("map", msg.header.frame_id, rospy.Time(0), rospy.Duration(10)).transform
    r = tf.rotation
    from airsim_mapper.common.geometry import quat_to_matrix

    beam = quat_to_matrix(np.array([r.w, r.x, r.y, r.z]))[:, 0]
    assert beam == pytest.approx([0.0, 0.0, 1.0], abs=1e-6)  # NED down


def test_battery_reports_a_fraction_and_airspeed_zero_pascals_at_hover(rig: Stack):
    from sensor_msgs.msg import BatteryState, FluidPressure

    battery = receive(f"{ROBOT}/Battery/battery", BatteryState)
    later = receive(f"{ROBOT}/Battery/battery", BatteryState)
    assert 0.0 < later.percentage < battery.percentage <= 1.0  # a fraction, draining
    assert battery.power_supply_health == BatteryState.POWER_SUPPLY_HEALTH_GOOD
    assert battery.location == "Battery"
    airspeed = receive(f"{ROBOT}/Airspeed/airspeed", FluidPressure)
    assert airspeed.fluid_pressure == pytest.approx(0.0, abs=1e-6)
    assert airspeed.header.frame_id == "airsim_node/Drone1"


def test_odometry_carries_the_pose_and_a_still_twist_while_hovering(rig: Stack):
    from nav_msgs.msg import Odometry

    msg = receive(f"{ROBOT}/odom", Odometry)
    assert (msg.header.frame_id, msg.child_frame_id) == ("map", "airsim_node/Drone1")
    p = msg.pose.pose.position
    assert (p.x, p.y, p.z) == pytest.approx((0.0, 0.0, -4.0), abs=0.05)
    lin, ang = msg.twist.twist.linear, msg.twist.twist.angular
    assert (lin.x, lin.y, lin.z, ang.x, ang.y, ang.z) == pytest.approx((0.0,) * 6, abs=1e-3)


PROBE = textwrap.dedent(
    """
    import json, sys, time
    import rospy
    from geometry_msgs.msg import PoseStamped
    rospy.init_node("sim_time_probe", anonymous=True)
    print("ready", flush=True)
    sys.stdin.readline()
    samples = []
    def on_pose(msg):
        samples.append((rospy.Time.now().to_nsec(), msg.header.stamp.to_nsec()))
    rospy.Subscriber(sys.argv[1], PoseStamped, on_pose, queue_size=1)
    first = rospy.Time.now().to_nsec()
    deadline = time.monotonic() + 20
    while len(samples) < 50 and time.monotonic() < deadline:
        time.sleep(0.01)
    print(json.dumps({"first": first, "samples": samples, "now": rospy.Time.now().to_nsec()}), flush=True)
    """
)


def test_a_use_sim_time_node_follows_clock_and_it_agrees_with_the_pose_stamps(rig: Stack, tmp_path):
    import subprocess

    import rospy
    from rosgraph_msgs.msg import Clock

    tick = receive("/clock", Clock)
    assert tick.clock.to_nsec() > 0
    script = tmp_path / "probe.py"
    script.write_text(PROBE)
    env = dict(rig.launcher.env)
    rospy.set_param("/use_sim_time", True)  # read once, when the probe initialises
    try:
        probe = subprocess.Popen(
            [sys.executable, str(script), f"{ROBOT}/actual_pose"],
            stdin=subprocess.PIPE,
            stdout=subprocess.PIPE,
            env=env,
            text=True,
        )
        assert probe.stdout.readline().strip() == "ready"
    finally:
        rospy.delete_param("/use_sim_time")
    out, _ = probe.communicate("go\n", timeout=40)
    result = json.loads(out.strip().splitlines()[-1])
    samples = np.array(result["samples"], dtype=np.int64)
    samples = samples[samples[:, 0] > 0]  # from the first /clock on
    assert len(samples) >= 30
    now, stamps = samples[:, 0], samples[:, 1]
    assert np.all(np.diff(now) >= 0) and now[-1] > now[0]  # sim time advances
    # rospy.Time.now() is the latest /clock, made from the same pose stream: typically within one 10 ms
    # pose period of the pose being handled; under load the two links jitter by a few pose periods.
    offsets = np.abs(now - stamps)
    assert np.median(offsets) <= 25_000_000, offsets.tolist()
    # A single sample can lag by a few hundred ms when CI starves the probe of CPU (seen: 316 ms at load
    # 8 on 2 cores); nine in ten must still agree within 100 ms.
    assert np.percentile(offsets, 90) <= 100_000_000, offsets.tolist()
    assert math.isclose(result["now"] / 1e9, now[-1] / 1e9, abs_tol=1.0)
