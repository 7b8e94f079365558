"""Commands through the bridge: cmd_vel with its watchdog, robot and camera desired_pose, load_scene."""

from __future__ import annotations

import math
import time
from collections.abc import Iterator

import numpy as np
import pytest
from bridgeharness import Stack, published_topics, wait_gone, wait_topic
from harness import wait_until

ROBOT = "/airsim_node/Drone1"
SCENE = "/Sim/SceneDroneSensors/robots/Drone1"


class PoseWatch:
    """Keeps the latest actual_pose position (NED) from the bridge."""

    def __init__(self, topic: str = f"{ROBOT}/actual_pose") -> None:
        import rospy
        from geometry_msgs.msg import PoseStamped

        self.position: np.ndarray | None = None
        self.orientation: np.ndarray | None = None
        self.sub = rospy.Subscriber(topic, PoseStamped, self._on_pose, queue_size=1)
        wait_until(lambda: self.position is not None, 20, what=f"a message on {topic}")

    def _on_pose(self, msg) -> None:
        p, q = msg.pose.position, msg.pose.orientation
        self.position = np.array([p.x, p.y, p.z])
        self.orientation = np.array([q.w, q.x, q.y, q.z])

    def settle(self, seconds: float = 0.3) -> np.ndarray:
        time.sleep(seconds)
        return self.position.copy()


@pytest.fixture(scope="module")
def rig(module_rig_factory) -> Stack:
    rig = module_rig_factory()
    rig.start_node(
        "--scene", "scene_drone_sensors.jsonc", node_name="cmd_bridge", wait_for=f"{ROBOT}/actual_pose"
    )
    client = rig.services_client()
    try:
        for method in ("EnableApiControl", "Arm"):
            assert client.request({"method": f"{SCENE}/{method}", "params": {}, "version": 1.0})
    finally:
        client.disconnect()
    return rig


@pytest.fixture(scope="module")
def pose(rig: Stack) -> Iterator[PoseWatch]:
    watch = PoseWatch()
    yield watch
    watch.sub.unregister()  # a lingering subscriber would keep later modules' dead publishers' latches


def publisher(topic: str, cls):
    import rospy

    pub = rospy.Publisher(topic, cls, queue_size=1)
    wait_until(lambda: pub.get_num_connections() > 0, 20, what=f"the bridge to subscribe to {topic}")
    return pub


def pose_msg(x: float, y: float, z: float, yaw: float = 0.0, frame: str = "map"):
    from geometry_msgs.msg import PoseStamped

    msg = PoseStamped()
    msg.header.frame_id = frame
    msg.pose.position.x, msg.pose.position.y, msg.pose.position.z = x, y, z
    msg.pose.orientation.w, msg.pose.orientation.z = math.cos(yaw / 2), math.sin(yaw / 2)
    return msg


def test_desired_pose_teleports_the_robot(rig: Stack, pose: PoseWatch):
    from geometry_msgs.msg import PoseStamped

    pub = publisher(f"{ROBOT}/desired_pose", PoseStamped)
    pub.publish(pose_msg(6.0, -3.0, -7.0))
    wait_until(lambda: np.allclose(pose.position, [6.0, -3.0, -7.0], atol=0.05), 10, what="the teleport")


def test_cmd_vel_moves_the_robot_forward_in_its_body_frame(rig: Stack, pose: PoseWatch):
    from geometry_msgs.msg import PoseStamped, Twist

    # Face east (yaw +90 deg in NED): body-frame forward is world east (+y).
    publisher(f"{ROBOT}/desired_pose", PoseStamped).publish(pose_msg(0.0, 0.0, -6.0, yaw=math.pi / 2))
    wait_until(lambda: np.allclose(pose.position, [0, 0, -6.0], atol=0.05), 10, what="the teleport")
    pub = publisher(f"{ROBOT}/cmd_vel", Twist)
    start = pose.settle()
    cmd = Twist()
    cmd.linear.x = 2.0
    for _ in range(15):  # 1.5 s at 10 Hz
        pub.publish(cmd)
        time.sleep(0.1)
    moved = pose.settle(0.2) - start
    assert moved[1] > 2.0  # east
    assert abs(moved[0]) < 0.3 and abs(moved[2]) < 0.3


def test_watchdog_stops_the_robot_three_seconds_after_the_last_cmd_vel(rig: Stack, pose: PoseWatch):
    from geometry_msgs.msg import Twist

    pub = publisher(f"{ROBOT}/cmd_vel", Twist)
    cmd = Twist()
    cmd.linear.x = 1.5
    for _ in range(5):
        pub.publish(cmd)
        time.sleep(0.1)
    last = time.monotonic()
    # Still moving 2 s after the last message (the watchdog is 3 s, not the old bridge's 1 s)...
    p1 = pose.settle(2.0 - (time.monotonic() - last))
    p2 = pose.settle(0.5)
    assert np.linalg.norm(p2 - p1) > 0.4
    # ...and stopped from 3 s on.
    p3 = pose.settle(3.6 - (time.monotonic() - last))
    p4 = pose.settle(1.0)
    assert np.linalg.norm(p4 - p3) < 0.05


def test_cmd_vel_with_nan_is_rejected_and_the_node_keeps_working(rig: Stack, pose: PoseWatch):
    from geometry_msgs.msg import PoseStamped, Twist

    pub = publisher(f"{ROBOT}/cmd_vel", Twist)
    before = pose.settle()
    bad = Twist()
    bad.linear.x = float("nan")
    pub.publish(bad)
    after = pose.settle(1.0)
    assert np.linalg.norm(after - before) < 0.05
    assert rig.node.alive()
    publisher(f"{ROBOT}/desired_pose", PoseStamped).publish(pose_msg(1.0, 1.0, -5.0))
    wait_until(lambda: np.allclose(pose.position, [1.0, 1.0, -5.0], atol=0.05), 10, what="a later teleport")


def test_camera_desired_pose_moves_the_camera_frame_and_its_images(rig: Stack, pose: PoseWatch):
    import rospy
    import tf2_ros
    from geometry_msgs.msg import PoseStamped
    from sensor_msgs.msg import Image

    publisher(f"{ROBOT}/desired_pose", PoseStamped).publish(pose_msg(0.0, 0.0, -5.0))
    wait_until(lambda: np.allclose(pose.position, [0, 0, -5.0], atol=0.05), 10, what="the teleport")
    # Point the down camera straight down (pitch -90 deg), 0.5 m under the body.
    cam = pose_msg(0.0, 0.0, 0.5)
    cam.pose.orientation.w = math.cos(-math.pi / 4)
    cam.pose.orientation.y = math.sin(-math.pi / 4)
    cam.pose.orientation.z = 0.0
    cam.header.frame_id = ""
    publisher(f"{ROBOT}/DownCamera/desired_pose", PoseStamped).publish(cam)
    buffer = tf2_ros.Buffer()
    tf2_ros.TransformListener(buffer)
    frame = "airsim_node/Drone1/DownCamera/depth_planar_camera"

    def camera_moved() -> bool:
        try:
            t = buffer.lookup_transform("map", frame, rospy.Time(0)).transform.translation
        except tf2_ros.TransformException:
            return False
        return abs(t.z - (-4.5)) < 0.05 and abs(t.x) < 0.05

    wait_until(camera_moved, 10, what="the camera frame to move")

    def centre_depth() -> float:
        img = rospy.wait_for_message(f"{ROBOT}/DownCamera/depth_planar_camera/image", Image, timeout=10)
        depth = np.frombuffer(img.data, dtype="<f4").reshape(img.height, img.width)
        return float(depth[img.height // 2, img.width // 2])

    # Looking straight down from 4.5 m over the landing pad (its top 2 cm above the ground).
    wait_until(lambda: abs(centre_depth() - 4.48) < 0.1, 10, what="the images to follow the camera")


def test_load_scene_switches_scenes_and_the_topics_follow(rig: Stack):
    from std_msgs.msg import String

    pub = publisher("/ProjectAirSim/node/cmd_bridge/load_scene", String)
    pub.publish(String(data="scene_two_drones.jsonc"))
    wait_topic("/airsim_node/Drone2/actual_pose", rig.node)
    wait_gone(f"{ROBOT}/DownCamera/scene_camera/image")
    # the new scene's bridges register one after another: a loaded CI machine saw actual_pose first
    wait_topic("/airsim_node/Drone2/FrontCamera/scene_camera/image", rig.node)
    wait_topic("/airsim_node/Drone1/FrontCamera/depth_planar_camera/image", rig.node)
    topics = published_topics()
    assert "/airsim_node/Drone2/FrontCamera/scene_camera/image" in topics
    assert "/airsim_node/Drone1/FrontCamera/depth_planar_camera/image" in topics
    assert f"{ROBOT}/lidar1/lidar" not in topics


def test_load_scene_refuses_a_path_outside_the_config_directory(rig: Stack):
    from std_msgs.msg import String

    pub = publisher("/ProjectAirSim/node/cmd_bridge/load_scene", String)
    pub.publish(String(data="../../x.jsonc"))
    wait_until(
        lambda: "x.jsonc" in rig.node.output() and "refused" in rig.node.output(),
        10,
        what="the refusal in the node's log",
    )
    time.sleep(0.5)
    assert "/airsim_node/Drone2/actual_pose" in published_topics()
    assert rig.node.alive()
