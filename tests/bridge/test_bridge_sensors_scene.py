"""The documented interface, end to end on the sensors scene: real roscore, real client, headless
server, bridge node as a subprocess; this test process is a ROS node that subscribes and looks up tf."""

from __future__ import annotations

import math

import numpy as np
import pytest
from bridgeharness import Stack, published_topics
from harness import wait_until

ROBOT = "/airsim_node/Drone1"
IMAGE_TYPES = (
    "scene_camera",
    "depth_planar_camera",
    "depth_camera",
    "segmentation_camera",
    "depth_vis_camera",
    "disparity_normalized_camera",
    "surface_normals",
)
DEPTH = ("depth_planar_camera", "depth_camera")
# Written by hand from the documented topic list, for sim_config/scene_drone_sensors.jsonc.
EXPECTED_PUBLISHED = {
    f"{ROBOT}/actual_pose": "geometry_msgs/PoseStamped",
    f"{ROBOT}/Chase/camera_pose": "geometry_msgs/PoseStamped",
    f"{ROBOT}/DownCamera/camera_pose": "geometry_msgs/PoseStamped",
    f"{ROBOT}/Chase/scene_camera/image": "sensor_msgs/Image",
    f"{ROBOT}/Chase/scene_camera/camera_info": "sensor_msgs/CameraInfo",
    **{f"{ROBOT}/DownCamera/{kind}/image": "sensor_msgs/Image" for kind in IMAGE_TYPES},
    **{f"{ROBOT}/DownCamera/{kind}/camera_info": "sensor_msgs/CameraInfo" for kind in IMAGE_TYPES},
    # image_transport's sibling topics: compressedDepth for the depth types, compressed for the others
    f"{ROBOT}/Chase/scene_camera/image/compressed": "sensor_msgs/CompressedImage",
    **{
        f"{ROBOT}/DownCamera/{kind}/image/{'compressedDepth' if kind in DEPTH else 'compressed'}": (
            "sensor_msgs/CompressedImage"
        )
        for kind in IMAGE_TYPES
    },
    f"{ROBOT}/lidar1/lidar": "sensor_msgs/PointCloud2",
    f"{ROBOT}/radar1/radar_detections": "radar_msgs/RadarScan",
    f"{ROBOT}/radar1/radar_tracks": "radar_msgs/RadarTracks",
    "/airsim_streaming_camera/image_raw": "sensor_msgs/Image",
    "/tf": "tf2_msgs/TFMessage",
    "/tf_static": "tf2_msgs/TFMessage",
    "/clock": "rosgraph_msgs/Clock",
    f"{ROBOT}/odom": "nav_msgs/Odometry",
    f"{ROBOT}/collision": "geometry_msgs/PointStamped",
    f"{ROBOT}/IMU1/imu": "sensor_msgs/Imu",
    f"{ROBOT}/GPS/gps": "sensor_msgs/NavSatFix",
    f"{ROBOT}/Barometer/barometer": "sensor_msgs/FluidPressure",
    f"{ROBOT}/Magnetometer/magnetometer": "sensor_msgs/MagneticField",
    f"{ROBOT}/DistanceSensor/distance": "sensor_msgs/Range",
    f"{ROBOT}/Battery/battery": "sensor_msgs/BatteryState",
    f"{ROBOT}/Airspeed/airspeed": "sensor_msgs/FluidPressure",
    "/diagnostics": "diagnostic_msgs/DiagnosticArray",
    "/airsim_mapper/sensors_bridge/status": "std_msgs/String",
}
EXPECTED_SUBSCRIBED = {
    "/ProjectAirSim/node/sensors_bridge/load_scene": "std_msgs/String",
    f"{ROBOT}/cmd_vel": "geometry_msgs/Twist",
    f"{ROBOT}/desired_pose": "geometry_msgs/PoseStamped",
    f"{ROBOT}/Chase/desired_pose": "geometry_msgs/PoseStamped",
    f"{ROBOT}/DownCamera/desired_pose": "geometry_msgs/PoseStamped",
}


@pytest.fixture(scope="module")
def rig(module_rig_factory) -> Stack:
    rig = module_rig_factory()
    rig.start_node(
        "--scene",
        "scene_drone_sensors.jsonc",
        node_name="sensors_bridge",
        wait_for=f"{ROBOT}/Airspeed/airspeed",  # the last topic the mapping makes
    )
    return rig


def receive(topic: str, cls, timeout: float = 20.0):
    import rospy

    return rospy.wait_for_message(topic, cls, timeout=timeout)


def test_every_documented_topic_is_advertised_with_its_type(rig: Stack):
    import rosgraph

    pubs, _subs, _srvs = rosgraph.Master("/probe").getSystemState()
    ours = {topic for topic, nodes in pubs if "/sensors_bridge" in nodes}
    published = published_topics()
    for topic, ros_type in EXPECTED_PUBLISHED.items():
        assert published.get(topic) == ros_type, topic
    assert ours - {"/rosout"} == set(EXPECTED_PUBLISHED)


def test_every_documented_command_topic_is_subscribed_with_its_type(rig: Stack):
    import rosgraph
    import rospy

    master = rosgraph.Master("/probe")
    _pubs, subs, services = master.getSystemState()
    subscribed = {topic for topic, nodes in subs if "/sensors_bridge" in nodes}
    types = dict(master.getTopicTypes())
    for topic, ros_type in EXPECTED_SUBSCRIBED.items():
        assert topic in subscribed, topic
        assert types[topic] == ros_type
    assert "/airsim_streaming_camera/switch_view" in {name for name, _ in services}
    assert rospy.get_param is not None


def test_actual_pose_equals_the_simulators_pose_in_ned(rig: Stack):
    from geometry_msgs.msg import PoseStamped

    msg = receive(f"{ROBOT}/actual_pose", PoseStamped)
    client = rig.services_client()
    try:
        truth = client.request(
            {
                "method": "/Sim/SceneDroneSensors/robots/Drone1/GetGroundTruthPose",
                "params": {},
                "version": 1.0,
            }
        )
    finally:
        client.disconnect()
    assert msg.header.frame_id == "map"
    p = msg.pose.position
    t = truth["translation"]
    assert (p.x, p.y, p.z) == pytest.approx((t["x"], t["y"], t["z"]), abs=0.05)
    assert p.z == pytest.approx(-4.0, abs=0.05)  # NED: 4 m up is z = -4
    assert msg.header.stamp.to_nsec() > 0  # stamped with sim time


@pytest.mark.parametrize("kind", IMAGE_TYPES)
def test_each_image_type_has_its_size_encoding_and_frame(rig: Stack, kind: str):
    from sensor_msgs.msg import CameraInfo, Image

    image = receive(f"{ROBOT}/DownCamera/{kind}/image", Image)
    info = receive(f"{ROBOT}/DownCamera/{kind}/camera_info", CameraInfo)
    assert (image.height, image.width) == (240, 320)
    depth = kind in ("depth_planar_camera", "depth_camera")
    assert image.encoding == ("32FC1" if depth else "bgr8")
    assert image.step == image.width * 4 if depth else image.width * 3
    assert len(image.data) == image.step * image.height
    assert image.header.frame_id == f"airsim_node/Drone1/DownCamera/{kind}_optical"  # REP 103
    assert info.header.frame_id == image.header.frame_id
    assert (info.width, info.height) == (320, 240)
    f = 160.0  # (320 / 2) / tan(90 deg / 2)
    assert pytest.approx([f, 0, 160, 0, f, 120, 0, 0, 1]) == info.K
    assert pytest.approx([f, 0, 160, 0, 0, f, 120, 0, 0, 0, 1, 0]) == info.P
    assert info.distortion_model == "plumb_bob"


def test_depth_is_in_metres_to_the_ground_along_the_camera_axis(rig: Stack):
    from sensor_msgs.msg import Image

    image = receive(f"{ROBOT}/DownCamera/depth_camera/image", Image)
    depth = np.frombuffer(image.data, dtype="<f4").reshape(image.height, image.width)
    # DownCamera: 0.1 m below the drone at 4 m, pitched 45 deg down: the optical axis meets the ground
    # at 3.9 / sin(45 deg) metres.
    centre = depth[119:121, 159:161].mean()
    assert centre == pytest.approx(3.9 / math.sin(math.radians(45)), abs=0.1)
    # The top row looks 45 - 36.9 = 8.1 degrees below the horizon: ground about 27 m away.
    assert depth[0, 150:170].mean() == pytest.approx(3.9 / math.sin(math.radians(45 - 36.87)), rel=0.05)


def test_point_cloud_points_lie_on_the_ground_in_the_map_frame(rig: Stack):
    from sensor_msgs.msg import PointCloud2

    check_cloud_on_ground(receive(f"{ROBOT}/lidar1/lidar", PointCloud2))


def check_cloud_on_ground(cloud) -> None:
    import rospy
    import tf2_ros

    names = [f.name for f in cloud.fields]
    assert names == ["x", "y", "z", "intensity", "segmentation"]
    assert cloud.header.frame_id == "airsim_node/Drone1/lidar1"
    points = np.frombuffer(
        cloud.data,
        dtype=np.dtype(
            {
                "names": names,
                "formats": ["<f4", "<f4", "<f4", "<f4", "<i4"],
                "offsets": [f.offset for f in cloud.fields],
                "itemsize": cloud.point_step,
            }
        ),
    )
    assert cloud.width == len(points) > 1000
    buffer = tf2_ros.Buffer()
    tf2_ros.TransformListener(buffer)
    tf = buffer.lookup_transform("map", cloud.header.frame_id, rospy.Time(0), rospy.Duration(10)).transform
    sensor_z = tf.translation.z  # the lidar is level: world z = sensor z + point z
    xyz = np.stack([points["x"], points["y"], points["z"]], axis=1)
    ground = points["segmentation"] == np.bincount(points["segmentation"]).argmax()
    assert ground.sum() > 100
    assert sensor_z + xyz[ground, 2] == pytest.approx(np.zeros(ground.sum()), abs=0.05)
    assert np.all(points["intensity"] >= 0)


def test_radar_detects_the_block_ahead(rig: Stack):
    from radar_msgs.msg import RadarScan

    scan = receive(f"{ROBOT}/radar1/radar_detections", RadarScan)
    assert scan.header.frame_id == "airsim_node/Drone1/radar1"
    ranges = np.array([r.range for r in scan.returns])
    azimuths = np.array([r.azimuth for r in scan.returns])
    # BlockNorth: near face at x = 28 m, centred on the radar's axis (radar at x = 0.3).
    ahead = (np.abs(azimuths) < 0.2) & (np.abs(ranges - 27.7) < 2.0)
    assert ahead.any(), list(zip(ranges, azimuths))
    assert all(math.isfinite(r.amplitude) for r in scan.returns)


def test_tf_resolves_every_documented_frame_from_map(rig: Stack):
    import rospy
    import tf2_ros

    buffer = tf2_ros.Buffer()
    tf2_ros.TransformListener(buffer)
    # Every frame comes from actual_pose and the scene's mounts, so none waits for a data subscriber.
    frames = [
        "airsim_node/Drone1",
        "airsim_node/Drone1/Chase/scene_camera",
        *(f"airsim_node/Drone1/DownCamera/{kind}" for kind in IMAGE_TYPES),
        *(f"airsim_node/Drone1/DownCamera/{kind}_optical" for kind in IMAGE_TYPES),  # what images carry
        "airsim_node/Drone1/lidar1",
        "airsim_node/Drone1/radar1",
        "airsim_node/Drone1/DistanceSensor",
    ]
    for frame in frames:
        tf = buffer.lookup_transform("map", frame, rospy.Time(0), rospy.Duration(10))
        assert tf.child_frame_id == frame
    body = buffer.lookup_transform("map", "airsim_node/Drone1", rospy.Time(0)).transform.translation
    down = buffer.lookup_transform("map", "airsim_node/Drone1/DownCamera/depth_camera", rospy.Time(0))
    # The camera frame is the body frame moved by the camera's mount (0.2, 0, 0.1) in FRD.
    t = down.transform.translation
    assert (t.x - body.x, t.y - body.y, t.z - body.z) == pytest.approx((0.2, 0.0, 0.1), abs=0.02)


def test_camera_and_sensor_frames_are_static_mounts_on_the_robot_and_not_sent_per_pose(rig: Stack):
    import rospy
    from tf2_msgs.msg import TFMessage

    latched = rospy.wait_for_message("/tf_static", TFMessage, timeout=20)
    mounts = {t.child_frame_id: t.header.frame_id for t in latched.transforms}
    cameras = {
        f"airsim_node/Drone1/DownCamera/{kind}{end}" for kind in IMAGE_TYPES for end in ("", "_optical")
    }
    sensors = {"airsim_node/Drone1/lidar1", "airsim_node/Drone1/radar1", "airsim_node/Drone1/DistanceSensor"}
    assert cameras | sensors <= set(mounts)
    assert set(mounts.values()) == {"airsim_node/Drone1"}  # each one relative to the robot's frame
    moving = {
        t.child_frame_id for _ in range(20) for t in rospy.wait_for_message("/tf", TFMessage, 10).transforms
    }
    assert "airsim_node/Drone1" in moving and not moving & set(mounts)


def test_camera_pose_topic_is_the_body_pose_moved_by_the_mount(rig: Stack):
    from geometry_msgs.msg import PoseStamped

    cam = receive(f"{ROBOT}/Chase/camera_pose", PoseStamped)
    body = receive(f"{ROBOT}/actual_pose", PoseStamped)
    assert cam.header.frame_id == "map"
    dz = cam.pose.position.z - body.pose.position.z
    dx = cam.pose.position.x - body.pose.position.x
    assert (dx, dz) == pytest.approx((-8.0, -2.0), abs=0.05)


def test_streaming_camera_carries_the_chase_scene_image_and_switch_view_answers(rig: Stack):
    import rospy
    from sensor_msgs.msg import Image
    from std_srvs.srv import Trigger

    image = receive("/airsim_streaming_camera/image_raw", Image)
    assert (image.width, image.height, image.encoding) == (640, 360, "bgr8")
    rospy.wait_for_service("/airsim_streaming_camera/switch_view", timeout=10)
    reply = rospy.ServiceProxy("/airsim_streaming_camera/switch_view", Trigger)()
    assert reply.success


def test_diagnostics_report_every_bridge_by_its_validate_mapping_name(rig: Stack):
    import rospy
    from diagnostic_msgs.msg import DiagnosticArray
    from sensor_msgs.msg import Image

    # An image subscriber makes the lazy image bridge active, so its rate shows.
    sub = rospy.Subscriber(f"{ROBOT}/DownCamera/scene_camera/image", Image, lambda m: None, queue_size=1)
    try:
        statuses = {}
        for _ in range(4):
            array = receive("/diagnostics", DiagnosticArray)
            statuses = {s.name: s for s in array.status}
        pose = statuses["sensors_bridge: actual_pose[Drone1]"]
        values = {kv.key: kv.value for kv in pose.values}
        assert pose.level == 0
        assert float(values["rate_hz"]) > 20
        assert values["ros"] == f"{ROBOT}/actual_pose"
        image = statuses["sensors_bridge: camera_image[Drone1/DownCamera/scene_camera]"]
        assert float({kv.key: kv.value for kv in image.values}["rate_hz"]) > 1
        sim = statuses["sensors_bridge: simulator"]
        assert sim.level == 0 and sim.message == "connected"
        idle = statuses["sensors_bridge: camera_image[Drone1/Chase/scene_camera]"]
        assert (
            idle.message.startswith("idle") or float({kv.key: kv.value for kv in idle.values}["rate_hz"]) > 0
        )
    finally:
        sub.unregister()


def test_a_lazy_stream_leaves_the_simulator_with_its_last_subscriber(rig: Stack):
    import json

    import rospy
    from sensor_msgs.msg import Image, Imu
    from std_msgs.msg import String

    prefix = "/Sim/SceneDroneSensors/robots/Drone1"
    image_topic = f"{prefix}/sensors/DownCamera/depth_planar_camera"
    imu_topic = f"{prefix}/sensors/IMU1/imu_kinematics"
    latest: dict = {}

    def on_status(msg) -> None:
        latest.update(json.loads(msg.data))

    def handled(topic: str) -> int:
        return latest.get("streams", {}).get(topic, {}).get("handled", 0)

    status = rospy.Subscriber("/airsim_mapper/sensors_bridge/status", String, on_status)
    image = rospy.Subscriber(f"{ROBOT}/DownCamera/depth_planar_camera/image", Image, lambda m: None)
    imu = rospy.Subscriber(f"{ROBOT}/IMU1/imu", Imu, lambda m: None)
    try:
        wait_until(lambda: handled(image_topic) > 0 and handled(imu_topic) > 0, 30, what="images and imu")
        image.unregister()
        imu.unregister()
        wait_until(lambda: not {image_topic, imu_topic} & set(latest["streams"]), 30, what="streams to leave")
        assert f"{prefix}/actual_pose" in latest["streams"]  # not lazy: it stays
    finally:
        for sub in (image, imu, status):
            sub.unregister()
