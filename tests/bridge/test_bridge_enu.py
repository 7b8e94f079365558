"""mappings/enu.yaml end to end on the sensors scene: REP-103 poses, optical camera frames, lidar points
and radar azimuths, checked through tf as a ROS user would see them."""

from __future__ import annotations

import math
import time

import numpy as np
import pytest
from bridgeharness import Stack
from harness import ROOT, wait_until

from airsim_mapper.common.geometry import quat_to_matrix

ROBOT = "/airsim_node/Drone1"
MAPPING = ROOT / "mappings" / "enu.yaml"


@pytest.fixture(scope="module")
def rig(module_rig_factory) -> Stack:
    rig = module_rig_factory()
    rig.start_node(
        "--scene",
        "scene_drone_sensors.jsonc",
        "--mapping",
        str(MAPPING),
        node_name="enu_bridge",
        wait_for=f"{ROBOT}/radar1/radar_detections",
    )
    return rig


@pytest.fixture(scope="module")
def tf_buffer(rig: Stack):
    import tf2_ros

    buffer = tf2_ros.Buffer()
    buffer.listener = tf2_ros.TransformListener(buffer)
    return buffer


def receive(topic: str, cls, timeout: float = 20.0):
    import rospy

    return rospy.wait_for_message(topic, cls, timeout=timeout)


def lookup(buffer, frame: str):
    """(translation, rotation matrix) of `frame` in map."""
    import rospy

    t = buffer.lookup_transform("map", frame, rospy.Time(0), rospy.Duration(10)).transform
    q = t.rotation
    return np.array([t.translation.x, t.translation.y, t.translation.z]), quat_to_matrix(
        np.array([q.w, q.x, q.y, q.z])
    )


def test_pose_is_enu_the_drone_4_m_up_is_at_z_plus_4(rig: Stack, tf_buffer):
    from geometry_msgs.msg import PoseStamped

    msg = receive(f"{ROBOT}/actual_pose", PoseStamped)
    p, q = msg.pose.position, msg.pose.orientation
    assert msg.header.frame_id == "map"
    assert (p.x, p.y, p.z) == pytest.approx((0.0, 0.0, 4.0), abs=0.05)
    # facing north: the FLU body's x axis is ENU +y, its z axis is up
    rotation = quat_to_matrix(np.array([q.w, q.x, q.y, q.z]))
    assert rotation[:, 0] == pytest.approx([0.0, 1.0, 0.0], abs=1e-3)
    assert rotation[:, 2] == pytest.approx([0.0, 0.0, 1.0], abs=1e-3)
    position, _ = lookup(tf_buffer, "Drone1/base_link")
    assert position == pytest.approx([0.0, 0.0, 4.0], abs=0.05)


def test_optical_frame_z_points_along_the_cameras_view_and_images_carry_it(rig: Stack, tf_buffer):
    from sensor_msgs.msg import CameraInfo, Image

    image = receive(f"{ROBOT}/DownCamera/scene_camera/image", Image)
    info = receive(f"{ROBOT}/DownCamera/scene_camera/camera_info", CameraInfo)
    assert image.header.frame_id == info.header.frame_id == "Drone1/DownCamera/scene_camera_optical"
    position, optical = lookup(tf_buffer, image.header.frame_id)
    # DownCamera: 0.2 m forward and 0.1 m below the body, pitched 45 degrees down; the drone faces north.
    h = math.sqrt(0.5)
    assert optical[:, 2] == pytest.approx([0.0, h, -h], abs=1e-3)  # z: the view direction
    assert optical[:, 0] == pytest.approx([1.0, 0.0, 0.0], abs=1e-3)  # x: image right = east
    assert position == pytest.approx([0.0, 0.2, 3.9], abs=0.05)
    body_position, body = lookup(tf_buffer, "Drone1/DownCamera/scene_camera")
    assert body[:, 0] == pytest.approx(optical[:, 2], abs=1e-6)  # FLU forward = optical z
    assert body_position == pytest.approx(position, abs=1e-6)


def test_depth_centre_pixel_seen_through_the_optical_frame_lands_on_the_ground(rig: Stack, tf_buffer):
    from sensor_msgs.msg import Image

    image = receive(f"{ROBOT}/DownCamera/depth_planar_camera/image", Image)
    depth = np.frombuffer(image.data, dtype="<f4").reshape(image.height, image.width)
    position, optical = lookup(tf_buffer, image.header.frame_id)
    ground = position + optical @ np.array([0.0, 0.0, float(depth[120, 160])])
    assert ground[2] == pytest.approx(0.0, abs=0.1)


def test_cloud_ground_points_are_at_z_0_in_map_after_tf(rig: Stack, tf_buffer):
    from sensor_msgs.msg import PointCloud2

    cloud = receive(f"{ROBOT}/lidar1/lidar", PointCloud2)
    assert cloud.header.frame_id == "Drone1/lidar1"
    dtype = np.dtype(
        {
            "names": [f.name for f in cloud.fields],
            "formats": ["<f4", "<f4", "<f4", "<f4", "<i4"],
            "offsets": [f.offset for f in cloud.fields],
            "itemsize": cloud.point_step,
        }
    )
    points = np.frombuffer(cloud.data, dtype=dtype)
    xyz = np.stack([points["x"], points["y"], points["z"]], axis=1).astype(float)
    position, rotation = lookup(tf_buffer, cloud.header.frame_id)
    world = xyz @ rotation.T + position
    ground = points["segmentation"] == np.bincount(points["segmentation"]).argmax()
    assert ground.sum() > 100
    assert world[ground, 2] == pytest.approx(np.zeros(ground.sum()), abs=0.05)
    assert np.all(world[:, 2] > -0.05)  # nothing below the ground: z is up


def radar_block_azimuths(yaw_enu: float) -> np.ndarray:
    """Turn the drone to `yaw_enu` (ENU desired_pose) and return the azimuths of BlockNorth's returns.

    The radar reports each object once, at its nearest point (1 m range resolution).
    """
    import rospy
    from geometry_msgs.msg import PoseStamped
    from radar_msgs.msg import RadarScan

    pub = rospy.Publisher(f"{ROBOT}/desired_pose", PoseStamped, queue_size=1)
    wait_until(lambda: pub.get_num_connections() > 0, 20, what="the desired_pose link")
    msg = PoseStamped()
    msg.header.frame_id = "map"
    msg.pose.position.z = 4.0
    msg.pose.orientation.w, msg.pose.orientation.z = math.cos(yaw_enu / 2), math.sin(yaw_enu / 2)

    turned_at = []

    def turned() -> bool:
        pub.publish(msg)
        actual = receive(f"{ROBOT}/actual_pose", PoseStamped)
        pose = actual.pose.orientation
        turned_at[:] = [actual.header.stamp]
        return abs(pose.z * msg.pose.orientation.z + pose.w * msg.pose.orientation.w) > 0.9999

    try:
        wait_until(turned, 10, interval=0.2, what="the turn")
    finally:
        pub.unregister()
    # A new subscriber first gets the simulator's cached last scan, which may predate the turn (the radar
    # bridge is lazy and left the simulator with the previous call's subscriber): wait for a newer one.
    scans: list = []
    radar = rospy.Subscriber(f"{ROBOT}/radar1/radar_detections", RadarScan, scans.append)
    try:
        wait_until(
            lambda: any(s.header.stamp > turned_at[0] for s in scans), 20, what="a scan after the turn"
        )
    finally:
        radar.unregister()
    scan = next(s for s in scans if s.header.stamp > turned_at[0])
    assert scan.header.frame_id == "Drone1/radar1"
    table = np.array([(r.range, r.azimuth, r.elevation) for r in scan.returns])
    block = np.abs(table[:, 0] - 28.0) < 0.6  # the block's nearest point: (28, 0) NED, 28 m away
    return table[block, 1]


def test_radar_azimuth_is_positive_to_the_left_as_rep103_says(rig: Stack):
    north = math.pi / 2
    try:
        # turned 30 degrees right of north, BlockNorth (due north) is on the left; turned left, on the right
        left = radar_block_azimuths(north - math.radians(30))
        right = radar_block_azimuths(north + math.radians(30))
    finally:
        radar_block_azimuths(north)
    assert len(left) and len(right)
    assert np.median(left) == pytest.approx(math.radians(30), abs=0.15)
    assert np.median(right) == pytest.approx(-math.radians(30), abs=0.15)


def test_a_world_frame_cmd_vel_flies_east_when_told_east(rig_factory, tmp_path):
    """cmd_vel pointed at MoveByVelocity with params.frame world, as the default mapping's comment offers:
    an ENU Twist of +x is east, whatever the drone faces (it faces north here)."""
    import rospy
    from geometry_msgs.msg import PoseStamped, Twist

    mapping = tmp_path / "world_cmd_vel.yaml"
    mapping.write_text(
        f"version: 1\nextends: {MAPPING}\nrules:\n  - name: cmd_vel\n"
        "    sim: /Sim/<scene_name>/robots/<robot_name>/MoveByVelocity\n    params: {frame: world}\n"
    )
    rig = rig_factory()
    robot = f"/world{ROBOT}"  # the module's node serves ROBOT's names on this master
    rig.start_node(
        "--scene",
        "scene_drone_sensors.jsonc",
        "--mapping",
        str(mapping),
        "--namespace",
        "world",
        node_name="world_cmd_vel",
        wait_for=f"{robot}/actual_pose",
    )

    def position() -> np.ndarray:
        p = receive(f"{robot}/actual_pose", PoseStamped).pose.position
        return np.array([p.x, p.y, p.z])

    pub = rospy.Publisher(f"{robot}/cmd_vel", Twist, queue_size=1)
    try:
        wait_until(lambda: pub.get_num_connections() > 0, 20, what="the cmd_vel link")
        start = position()
        cmd = Twist()
        cmd.linear.x = 2.0
        for _ in range(15):  # 1.5 s at 10 Hz
            pub.publish(cmd)
            time.sleep(0.1)
        moved = position() - start
    finally:
        pub.unregister()
    assert moved[0] > 2.0, moved  # east
    assert abs(moved[1]) < 0.3 and abs(moved[2]) < 0.3, moved
