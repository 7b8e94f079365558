"""RViz: the radar-to-marker conversion, the config and launch file against the mapping's interface, and the
screenshot pipeline end to end on the real stack (Xvfb, roscore, headless server, bridge + mission, radar
marker node, RViz)."""

from __future__ import annotations

import math
import os
import subprocess
import sys
import xml.etree.ElementTree as ET
from io import BytesIO

import commentjson
import numpy as np
import pytest
from harness import ROOT, SIM_CONFIG

from airsim_mapper.common.geometry import quat_from_rpy
from airsim_mapper.convert.context import ConvertContext
from airsim_mapper.convert.radar import radar_scan
from airsim_mapper.convert.rviz_radar import (
    STRONG_RGBA,
    WEAK_RGBA,
    MarkerStyle,
    RadarMarkerError,
    amplitude_colors,
    return_points,
    scan_markers,
)
from airsim_mapper.mapping.pipeline import load_and_expand
from airsim_mapper.simserver.sensors.radar_model import RadarModel
from airsim_mapper.simserver.world.world_file import load_world
from tools.screenshot import rviz_config, watch

LAUNCH = ROOT / "launch" / "rviz.launch"
RADAR_FRAME = "airsim_node/Drone1/radar1"
RVIZ_TYPES = {
    "rviz/Image": "sensor_msgs/Image",
    "rviz/PointCloud2": "sensor_msgs/PointCloud2",
    "rviz/Odometry": "nav_msgs/Odometry",
}


def make_scan(*returns: tuple[float, float, float, float, float], frame: str = RADAR_FRAME):
    import rospy
    from radar_msgs.msg import RadarReturn, RadarScan
    from std_msgs.msg import Header

    header = Header(frame_id=frame, stamp=rospy.Time(12, 500))
    return RadarScan(header=header, returns=[RadarReturn(*r) for r in returns])


# -- the conversion, by hand ------------------------------------------------------------------------------


@pytest.mark.parametrize(
    ("rng", "azimuth", "elevation", "convention", "expected"),
    [
        (10.0, 0.0, 0.0, "frd", (10.0, 0.0, 0.0)),  # dead ahead
        (10.0, math.pi / 2, 0.0, "frd", (0.0, 10.0, 0.0)),  # FRD: positive azimuth is right = +y
        (10.0, -math.pi / 2, 0.0, "frd", (0.0, -10.0, 0.0)),
        (10.0, 0.0, math.pi / 6, "frd", (10 * math.sqrt(3) / 2, 0.0, -5.0)),  # up is -z in FRD
        (10.0, math.pi / 2, 0.0, "flu", (0.0, 10.0, 0.0)),  # FLU: positive azimuth is left = +y
        (10.0, 0.0, math.pi / 6, "flu", (10 * math.sqrt(3) / 2, 0.0, 5.0)),  # up is +z in FLU
        (2.0, math.pi / 4, math.pi / 4, "frd", (1.0, 1.0, -math.sqrt(2))),
    ],
)
def test_returns_become_points_in_the_radar_frame(rng, azimuth, elevation, convention, expected):
    points = return_points([rng], [azimuth], [elevation], convention)
    assert points.shape == (1, 3)
    assert points[0] == pytest.approx(expected, abs=1e-9)


def test_points_invert_the_servers_angle_definitions():
    # The server: azimuth = atan2(y, x), elevation = asin(-z / range), in the FRD sensor frame.
    xyz = np.random.default_rng(7).uniform(-50, 50, size=(200, 3))
    rng = np.linalg.norm(xyz, axis=1)
    points = return_points(rng, np.arctan2(xyz[:, 1], xyz[:, 0]), np.arcsin(-xyz[:, 2] / rng), "frd")
    assert np.allclose(points, xyz)


def test_bad_conventions_and_shapes_are_errors():
    with pytest.raises(RadarMarkerError, match="convention"):
        return_points([1.0], [0.0], [0.0], "ned")
    with pytest.raises(RadarMarkerError, match="1-D"):
        return_points([1.0, 2.0], [0.0], [0.0])


def test_colours_ramp_from_weak_to_strong_amplitude():
    colours = amplitude_colors([-100.0, -50.0, 0.0])
    assert colours[0] == pytest.approx(WEAK_RGBA)
    assert colours[2] == pytest.approx(STRONG_RGBA)
    assert colours[1] == pytest.approx((np.add(WEAK_RGBA, STRONG_RGBA) / 2).tolist())
    assert amplitude_colors([3.0])[0] == pytest.approx(STRONG_RGBA)  # one return: strongest
    assert amplitude_colors([]).shape == (0, 4)


def test_a_scan_becomes_one_sphere_list_in_the_scans_frame_and_stamp():
    from visualization_msgs.msg import Marker

    scan = make_scan((10.0, 0.0, 0.0, -1.0, 5.0), (10.0, math.pi / 2, 0.0, 0.0, -20.0))
    array = scan_markers(scan, "frd", MarkerStyle(diameter_m=0.8, lifetime_s=2.0))
    (marker,) = array.markers
    assert marker.type == Marker.SPHERE_LIST and marker.action == Marker.ADD
    assert marker.header.frame_id == RADAR_FRAME and marker.header.stamp.to_nsec() == 12_000_000_500
    assert np.allclose([(p.x, p.y, p.z) for p in marker.points], [(10, 0, 0), (0, 10, 0)], atol=1e-9)
    assert (marker.scale.x, marker.scale.y, marker.scale.z) == pytest.approx((0.8, 0.8, 0.8))
    assert marker.lifetime.to_sec() == pytest.approx(2.0)
    assert marker.pose.orientation.w == 1.0
    assert np.allclose([(c.r, c.g, c.b, c.a) for c in marker.colors], [STRONG_RGBA, WEAK_RGBA])
    array.serialize(BytesIO())  # a valid message


def test_an_empty_scan_deletes_the_marker_and_non_finite_returns_are_dropped():
    from visualization_msgs.msg import Marker

    (empty,) = scan_markers(make_scan()).markers
    assert empty.action == Marker.DELETE and empty.header.frame_id == RADAR_FRAME
    (marker,) = scan_markers(make_scan((math.nan, 0, 0, 0, 0), (5.0, 0.0, 0.0, 0.0, 1.0))).markers
    assert np.allclose([(p.x, p.y, p.z) for p in marker.points], [(5.0, 0.0, 0.0)])
    (gone,) = scan_markers(make_scan((math.inf, 0, 0, 0, 0))).markers
    assert gone.action == Marker.DELETE


@pytest.mark.parametrize(("convention", "sign"), [("ned", 1.0), ("enu", -1.0)])
def test_server_detection_through_the_bridge_converter_lands_on_the_ball(convention, sign):
    """Headless server radar -> bridge radar_scan converter -> marker: the sphere sits on the ball's surface,
    on the line to its centre (the ball: centre (20, 20, -3) NED, radius 1 m)."""
    robot = commentjson.loads((SIM_CONFIG / "robot_radar_tower.jsonc").read_text())
    radar = RadarModel.from_config(next(s for s in robot["sensors"] if s["type"] == "radar"))
    facing_east = quat_from_rpy(0.0, 0.0, math.pi / 2)
    detections = radar.detect(load_world(), np.array([25.0, 8.0, -1.0]), facing_east, np.zeros(3), 0)
    ball_rcs = math.pi * radar.rcs_adjust_factor
    sim = {
        "time_stamp": 1,
        "radar_detections": [d for d in detections if d["rcs_sqm"] == pytest.approx(ball_rcs)],
        "pose": {"position": {"x": 0, "y": 0, "z": 0}, "orientation": {"w": 1, "x": 0, "y": 0, "z": 0}},
    }
    scan = radar_scan(sim, ConvertContext(frame_id=RADAR_FRAME, convention=convention))
    (marker,) = scan_markers(scan, "frd" if convention == "ned" else "flu").markers
    (point,) = [(p.x, p.y, p.z) for p in marker.points]
    centre = np.array([12.0, 5.0, -2.0])  # FRD: 12 m ahead, 5 m right, 2 m up
    expected = centre / np.linalg.norm(centre) * round(np.linalg.norm(centre) - 1.0)
    assert point == pytest.approx((expected * [1.0, sign, sign]).tolist(), abs=1e-6)


# -- the config and the launch file match the mapping -----------------------------------------------------


def default_interface() -> dict[str, str]:
    _, _, bridges = load_and_expand(
        ROOT / "mappings" / "default.yaml", "scene_drone_sensors.jsonc", ROOT / "sim_config", "projectairsim"
    )
    return {b.ros: b.ros_type for b in bridges if b.ros is not None and b.ros_kind == "topic"}


def launch_node_args(node_type: str) -> dict[str, str]:
    node = next(n for n in ET.parse(LAUNCH).getroot().iter("node") if n.get("type") == node_type)
    words = node.get("args").split()
    return {words[i]: words[i + 1] for i in range(0, len(words) - 1) if words[i].startswith("--")}


def test_every_topic_of_the_rviz_config_is_in_the_default_interface_or_made_by_the_launch_file():
    interface = default_interface()
    markers = launch_node_args("radar_markers.py")
    assert interface[markers["--scan"]] == "radar_msgs/RadarScan"
    assert markers["--convention"] == "frd"  # the default mapping's radar frame is FRD
    topics = rviz_config.config_topics()
    assert topics.pop(markers["--markers"]) == "rviz/MarkerArray"
    assert markers["--markers"] == watch.MARKER_TOPIC
    assert set(topics.values()) == set(RVIZ_TYPES)  # images, the cloud and the odometry
    for topic, display in topics.items():
        assert topic in interface, f"{topic} ({display}) is not in the default mapping's interface"
        assert interface[topic] == RVIZ_TYPES[display], topic
    assert {watch.IMAGE_TOPIC, watch.LIDAR_TOPIC, watch.ODOM_TOPIC} <= set(topics)


def test_every_frame_the_config_names_is_published_by_the_default_mapping():
    _, _, bridges = load_and_expand(
        ROOT / "mappings" / "default.yaml", "scene_drone_sensors.jsonc", ROOT / "sim_config", "projectairsim"
    )
    frames = {f for b in bridges if b.tf is not None for f in (b.tf.parent, b.tf.child)}
    shown = rviz_config.config_frames()
    assert {"map", "airsim_node/Drone1", "airsim_node/Drone1/Chase/scene_camera"} <= shown
    assert shown <= frames


@pytest.mark.live
def test_the_launch_file_starts_the_sim_the_mission_the_marker_node_and_rviz(tmp_path):
    env = {
        **os.environ,
        "ROS_PACKAGE_PATH": f"{ROOT}:/usr/share",
        "ROS_HOME": str(tmp_path),
        "PATH": f"{os.path.dirname(sys.executable)}{os.pathsep}{os.environ.get('PATH', '')}",
    }

    def nodes(*args: str) -> set[str]:
        run = subprocess.run(
            ["roslaunch", "--nodes", str(LAUNCH), *args], env=env, capture_output=True, text=True, timeout=120
        )
        assert run.returncode == 0, run.stdout + run.stderr
        return set(run.stdout.split())

    assert nodes() == {"/headless_sim", "/projectairsim", "/radar_markers", "/rviz"}
    assert nodes("bridge:=node", "with_sim:=false", "rviz:=false") == {"/projectairsim", "/radar_markers"}
    assert nodes("bridge:=none") == {"/headless_sim", "/radar_markers", "/rviz"}
