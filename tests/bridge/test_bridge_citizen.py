"""A good ROS citizen: the node started without a scene, then a scene loaded over ROS, once per
request whatever the publisher latches."""

from __future__ import annotations

import time

import pytest
from bridgeharness import wait_topic
from harness import Child, RigError, wait_until

SENSORS, TWO = "scene_drone_sensors.jsonc", "scene_two_drones.jsonc"


def subscribed(topic: str) -> bool:
    import rosgraph

    _pubs, subs, _srvs = rosgraph.Master("/probe").getSystemState()
    return any(name == topic for name, _nodes in subs)


def loads(node: Child, scene_file: str) -> int:
    """How many times the node loaded `scene_file` (its log line per load)."""
    return node.output().count(f"({scene_file}) loaded")


def rostopic_pub(rig, topic: str, scene_file: str, *flags: str) -> Child:
    return rig.launcher.start(
        "rostopic_pub", ["rostopic", "pub", *flags, topic, "std_msgs/String", f"data: '{scene_file}'"]
    )


def at(poses: list, x: float, y: float, z: float) -> bool:
    """Whether the last of `poses` (geometry_msgs Pose) is within 5 cm of (x, y, z)."""
    p = poses[-1].position if poses else None
    return p is not None and max(abs(p.x - x), abs(p.y - y), abs(p.z - z)) <= 0.05


def test_start_without_a_scene_then_load_one_once_per_request(rig_factory):
    rig = rig_factory()
    node = rig.start_node(node_name="waiting_bridge")
    topic = "/ProjectAirSim/node/waiting_bridge/load_scene"
    waiting = f"no --scene: waiting for a scene file name on {topic}"
    wait_until(lambda: node.check_alive() is None and waiting in node.output(), 60, what="the node to wait")
    assert subscribed(topic)

    # The documented flow with `rostopic pub -1` (latched, stays 3 s, leaves): one load.
    rostopic_pub(rig, topic, SENSORS, "-1")
    wait_topic("/airsim_node/Drone1/DownCamera/scene_camera/image", node)
    time.sleep(5)
    assert loads(node, SENSORS) == 1
    assert subscribed(topic)

    # A plain `rostopic pub` latches its message and stays: 10 s of it, still one load.
    publisher = rostopic_pub(rig, topic, TWO)
    wait_topic("/airsim_node/Drone2/actual_pose", node)
    time.sleep(10)
    assert loads(node, TWO) == 1
    publisher.stop()

    # The same scene name published again on purpose is a new request: it reloads.
    rostopic_pub(rig, topic, TWO, "-1")
    wait_until(lambda: loads(node, TWO) == 2, 30, what="the deliberate second load")
    time.sleep(4)
    assert loads(node, TWO) == 2
    assert node.alive()
    node.stop()


def lookup(parent: str, child: str, timeout: float = 20.0):
    import rospy
    import tf2_ros

    buffer = tf2_ros.Buffer()
    listener = tf2_ros.TransformListener(buffer)
    try:
        return buffer.lookup_transform(parent, child, rospy.Time(0), rospy.Duration(timeout))
    finally:
        listener.unregister()


def test_rosrun_from_home_in_ros_namespace_with_private_params(rig_factory, tmp_path):
    """rosrun from a directory without sim_config/, under ROS_NAMESPACE, configured by `_param:=` only."""
    rig = rig_factory()
    ports = rig.sim.ports
    node = rig.launcher.start(
        "rosrun_ns",
        [
            "rosrun",
            "projectairsim_ros",
            "projectairsim_node.py",
            "__name:=ns_bridge",
            f"_topicsport:={ports.topics}",
            f"_servicesport:={ports.services}",
            "_scene:=scene_drone_sensors.jsonc",
            "_mapping:=enu",
            "_max_frame_mb:=8",  # a switch only: said, not passed over
        ],
        env={"ROS_NAMESPACE": "sim1"},
        cwd=tmp_path,
    )
    wait_topic("/sim1/airsim_node/Drone1/actual_pose", node)
    out = node.output()
    assert "setting scene = 'scene_drone_sensors.jsonc' (parameter ~scene)" in out
    assert "setting mapping = 'enu' (parameter ~mapping)" in out
    assert "parameter ~max_frame_mb is not one the node reads; --max-frame-mb is a command-line switch" in out
    assert "setting simconfigpath = " in out and "does not exist here, so the package's own" in out
    assert subscribed("/sim1/ProjectAirSim/node/ns_bridge/load_scene")
    lookup("sim1/map", "sim1/Drone1/base_link")  # the ENU mapping's frames, prefixed
    node.stop()


def test_ns_remap_and_command_line_over_parameter(rig_factory):
    """`__ns:=` plus a relative --namespace nests; --scene on the command line wins over `_scene:=`."""
    rig = rig_factory()
    node = rig.start_node(
        "__ns:=fleet",
        "--namespace",
        "sim2",
        "--scene",
        TWO,
        "_scene:=scene_drone_sensors.jsonc",
        node_name="nested_bridge",
    )
    wait_topic("/fleet/sim2/airsim_node/Drone2/actual_pose", node)
    assert "setting scene = 'scene_two_drones.jsonc' (command line)" in node.output()
    assert "setting namespace = 'sim2' (command line)" in node.output()
    line = "namespace '/fleet/sim2': topics under it, frames prefixed 'fleet/sim2/'"  # after the bridge table
    wait_until(lambda: line in node.output(), 20, what="the namespace line")
    lookup("fleet/sim2/map", "fleet/sim2/airsim_node/Drone2")
    # The streaming image's frame follows switch_view to the other drone's camera.
    import rospy
    from sensor_msgs.msg import Image
    from std_srvs.srv import Trigger

    stream = "/fleet/sim2/airsim_streaming_camera"

    def frame() -> str:
        return rospy.wait_for_message(f"{stream}/image_raw", Image, timeout=20).header.frame_id

    assert frame() == "fleet/sim2/airsim_node/Drone1/FrontCamera/scene_camera_optical"
    rospy.wait_for_service(f"{stream}/switch_view", timeout=10)
    assert rospy.ServiceProxy(f"{stream}/switch_view", Trigger)().success
    wait_until(
        lambda: frame() == "fleet/sim2/airsim_node/Drone2/FrontCamera/scene_camera_optical",
        20,
        what="the new frame",
    )
    node.stop()


LAUNCH = """<launch>
  <group ns="fleet">
    <include file="$(find projectairsim_ros)/launch/projectairsim.launch">
      <arg name="nodename" value="group_bridge"/>
      <arg name="topicsport" value="{topics}"/>
      <arg name="servicesport" value="{services}"/>
    </include>
  </group>
</launch>
"""


def test_roslaunch_group_ns_with_defaults_then_load_a_scene(rig_factory, tmp_path):
    """The shipped launch file in <group ns>, its defaults (no scene): load_scene under the group, then a
    scene loaded on it brings the robots' topics up under the group; status and diagnostics name the node
    in full."""
    rig = rig_factory()
    launch = tmp_path / "fleet.launch"
    launch.write_text(LAUNCH.format(topics=rig.sim.ports.topics, services=rig.sim.ports.services))
    roslaunch = rig.launcher.start("roslaunch_group", ["roslaunch", str(launch)])
    topic = "/fleet/ProjectAirSim/node/group_bridge/load_scene"
    wait_until(lambda: roslaunch.check_alive() is None and subscribed(topic), 90, what=topic)
    rostopic_pub(rig, topic, SENSORS, "-1")
    wait_topic("/fleet/airsim_node/Drone1/DownCamera/scene_camera/image", roslaunch)
    assert "setting scene = '' (parameter ~scene)" in roslaunch.output()
    lookup("fleet/map", "fleet/airsim_node/Drone1")
    # The status topic and the diagnostics go by the node's full name: another group's node differs.
    import json

    import rospy
    from diagnostic_msgs.msg import DiagnosticArray
    from std_msgs.msg import String

    status = rospy.wait_for_message("/airsim_mapper/fleet/group_bridge/status", String, timeout=20)
    assert json.loads(status.data)["state"] == "connected"
    names = {s.name for s in rospy.wait_for_message("/diagnostics", DiagnosticArray, timeout=20).status}
    assert "fleet/group_bridge: mapping" in names
    assert all(name.startswith("fleet/group_bridge: ") for name in names), names
    rig.launcher.stop_all()


def goal(x: float, y: float, z: float, frame: str, yaw: float = 0.0):
    import math

    from geometry_msgs.msg import PoseStamped

    msg = PoseStamped()
    msg.header.frame_id = frame
    msg.pose.position.x, msg.pose.position.y, msg.pose.position.z = x, y, z
    msg.pose.orientation.w, msg.pose.orientation.z = math.cos(yaw / 2), math.sin(yaw / 2)
    return msg


def test_goals_in_the_namespaced_world_frame_the_body_frame_and_an_unknown_frame(rig_factory):
    import math

    import rospy
    from geometry_msgs.msg import PoseStamped

    rig = rig_factory()
    ns = "/sim1/airsim_node/Drone1"
    node = rig.start_node(
        "--namespace", "sim1", "--scene", SENSORS, node_name="goal_bridge", wait_for=f"{ns}/actual_pose"
    )
    latest: list = []
    sub = rospy.Subscriber(f"{ns}/actual_pose", PoseStamped, lambda m: latest.append(m.pose))
    pub = rospy.Publisher(f"{ns}/desired_pose", PoseStamped, queue_size=1)
    try:
        wait_until(lambda: pub.get_num_connections() > 0, 20, what="the desired_pose link")

        # In the bridge's own namespaced world frame (was refused before).
        pub.publish(goal(0.0, 0.0, -5.0, "sim1/map", yaw=math.pi / 2))
        wait_until(lambda: at(latest, 0.0, 0.0, -5.0), 15, what="the goal in sim1/map")
        time.sleep(0.5)  # let tf catch up with the teleport
        # "1 m ahead" in the robot's own frame: facing east (yaw 90 deg in NED), so 1 m east.
        pub.publish(goal(1.0, 0.0, 0.0, "sim1/airsim_node/Drone1"))
        wait_until(lambda: at(latest, 0.0, 1.0, -5.0), 15, what="the body-frame goal")
        q = latest[-1].orientation
        assert math.isclose(2 * math.atan2(q.z, q.w), math.pi / 2, abs_tol=0.02)  # still facing east
        # The same frame written tf1-style with a leading slash, which tf2 itself refuses: 1 m further east.
        pub.publish(goal(1.0, 0.0, 0.0, "/sim1/airsim_node/Drone1"))
        wait_until(lambda: at(latest, 0.0, 2.0, -5.0), 15, what="the slashed body-frame goal")
        # A frame tf does not know: refused with a warning naming it, nothing sent.
        pub.publish(goal(9.0, 9.0, -9.0, "nowhere_frame"))
        wait_until(lambda: "'nowhere_frame'" in node.output(), 15, what="the refusal")
        time.sleep(1.0)
        assert at(latest, 0.0, 2.0, -5.0)
    finally:
        sub.unregister()
        pub.unregister()
    node.stop()


def test_a_lazy_stream_s_first_message_is_taken_after_the_subscription(rig_factory):
    """rostopic echo -n1 / wait_for_message get a current frame, not the simulator's cached one."""
    import rospy
    from diagnostic_msgs.msg import DiagnosticArray
    from geometry_msgs.msg import PoseStamped
    from sensor_msgs.msg import Image, PointCloud2

    rig = rig_factory()
    robot = "/airsim_node/Drone1"
    rig.start_node("--scene", SENSORS, node_name="fresh_bridge", wait_for=f"{robot}/actual_pose")
    # The camera renders only while someone listens: its cached frame stays from the first read. The lidar
    # scans on, unheard; its cached sample is the last scan, which may be as new as the subscription (then
    # it is current and published, so only the first-message check applies to it).
    camera = "camera_image[Drone1/DownCamera/scene_camera]"
    streams = (
        (f"{robot}/DownCamera/scene_camera/image", Image, camera),
        (f"{robot}/lidar1/lidar", PointCloud2, "lidar[Drone1/lidar1]"),
    )
    for topic, cls, _ in streams:
        rospy.wait_for_message(topic, cls, timeout=20)  # the simulator now holds a frame of this time
    time.sleep(3.0)  # simulated time goes on; the camera's cached frame stays behind
    for topic, cls, _ in streams:
        before = rospy.wait_for_message(f"{robot}/actual_pose", PoseStamped, timeout=10).header.stamp
        first = rospy.wait_for_message(topic, cls, timeout=20).header.stamp
        assert first >= before, (
            f"{topic}: first message {(before - first).to_sec():.2f} s older than the subscription"
        )
    names = {f"fresh_bridge: {name}" for _, _, name in streams}
    dropped: dict[str, int] = {}
    seen: set[str] = set()

    def counted() -> bool:
        for status in rospy.wait_for_message("/diagnostics", DiagnosticArray, timeout=10).status:
            seen.add(status.name)
            if status.name in names:
                dropped[status.name] = int({kv.key: kv.value for kv in status.values}["stale_dropped"])
        return len(dropped) == len(names) and dropped[f"fresh_bridge: {camera}"] >= 1

    try:
        wait_until(counted, 10, what="the camera's stale frame counted in /diagnostics")
    except RigError as exc:  # with what was seen at the end (`what` is written before the wait)
        raise AssertionError(f"{exc}: {dropped}; statuses: {sorted(seen)}") from None
    rig.node.stop()


BALL_NED = (20.0, 20.0, -3.0)  # the default world's orange ball (centre), BGR (0, 140, 255), radius 1 m


@pytest.mark.parametrize("mapping", ["default", "enu"])
def test_the_ball_projects_onto_its_pixels_through_the_image_s_optical_frame(rig_factory, mapping):
    """As image_geometry would: the ball's centre looked up in the image's frame with tf2, projected with
    camera_info's P, lands on the ball's orange pixels (the Chase camera from the drone's start pose sees
    the ball up and to the right)."""
    import math

    import numpy as np
    import rospy
    import tf2_geometry_msgs
    import tf2_ros
    from geometry_msgs.msg import PointStamped
    from sensor_msgs.msg import CameraInfo, Image

    rig = rig_factory()
    camera = "/airsim_node/Drone1/Chase/scene_camera"
    node = rig.start_node(
        "--mapping", mapping, "--scene", SENSORS, node_name=f"optical_{mapping}", wait_for=f"{camera}/image"
    )
    buffer = tf2_ros.Buffer()
    listener = tf2_ros.TransformListener(buffer)
    try:
        rospy.wait_for_message(f"{camera}/image", Image, timeout=20)
        time.sleep(1.0)  # the drone settles on its start pose
        image = rospy.wait_for_message(f"{camera}/image", Image, timeout=20)
        info = rospy.wait_for_message(f"{camera}/camera_info", CameraInfo, timeout=20)
        tf = buffer.lookup_transform(image.header.frame_id, "map", image.header.stamp, rospy.Duration(10))
    finally:
        listener.unregister()
    assert image.header.frame_id == info.header.frame_id
    assert image.header.frame_id.endswith("Chase/scene_camera_optical")
    ball = PointStamped()
    ball.header.frame_id = "map"
    x, y, z = BALL_NED
    ball.point.x, ball.point.y, ball.point.z = (y, x, -z) if mapping == "enu" else (x, y, z)
    point = tf2_geometry_msgs.do_transform_point(ball, tf).point
    assert point.z > 0  # in front of the camera
    u, v, w = np.array(info.P).reshape(3, 4) @ np.array([point.x, point.y, point.z, 1.0])
    u, v = u / w, v / w
    pixels = np.frombuffer(image.data, np.uint8).reshape(image.height, image.width, 3)  # bgr8
    b, g, r = (pixels[..., i].astype(float) for i in range(3))
    orange = (r > 60) & (b < 0.25 * r) & (g > 0.35 * r) & (g < 0.75 * r)  # lit side or shaded side
    rows, cols = np.nonzero(orange)
    assert len(rows) > 20, "the ball is not in the image"
    assert math.dist((u, v), (cols.mean(), rows.mean())) < 3.0, ((u, v), (cols.mean(), rows.mean()))
    assert orange[round(v), round(u)]
    node.stop()


def test_a_re_created_load_scene_subscriber_ignores_the_latched_replay(ros_session):
    """In this process: a load_scene runner re-created on the same engine services gets the latched message
    again on its new connection and does not act on it; the same name published again is acted on."""
    import rospy
    from std_msgs.msg import String

    from airsim_mapper.engine.bridges import BridgeParts
    from airsim_mapper.engine.mounts import CameraMounts
    from airsim_mapper.engine.ros_link import RosLink
    from airsim_mapper.engine.ros_to_sim import RosToSim
    from airsim_mapper.mapping.expand import expand
    from airsim_mapper.mapping.loader import load_mapping

    (spec,) = expand(load_mapping("default"), None, "replay_probe")
    actions: list[str] = []
    services = BridgeParts(
        None, None, RosLink(), CameraMounts(), lambda _action, params: actions.append(params["scene"])
    )
    publisher = rospy.Publisher(spec.ros, String, queue_size=1, latch=True)
    publisher.publish(String(SENSORS))
    bridge = RosToSim(spec, services)
    bridge.start()
    try:
        wait_until(lambda: actions == [SENSORS], 10, what="the first load")
        bridge.stop()
        bridge = RosToSim(spec, services)  # a new subscriber: the latched message arrives again
        bridge.start()
        wait_until(lambda: publisher.get_num_connections() == 1, 10, what="the new connection")
        time.sleep(2.0)
        assert actions == [SENSORS]
        publisher.publish(String(SENSORS))  # on purpose, again
        wait_until(lambda: actions == [SENSORS, SENSORS], 10, what="the deliberate reload")
    finally:
        bridge.stop()
        publisher.unregister()


def test_a_goal_in_the_robots_frame_after_loading_another_scene_is_placed_from_the_new_pose(rig_factory):
    """Another scene's clock starts from zero under a running node: the node's tf forgets the old scene's
    transforms, so "1 m ahead" is 1 m ahead of where the robot is now, not of where it was."""
    import rospy
    from geometry_msgs.msg import PoseStamped

    rig = rig_factory()
    robot = "/airsim_node/Drone1"
    node = rig.start_node("--scene", SENSORS, node_name="switch_bridge", wait_for=f"{robot}/actual_pose")
    latest: list = []
    sub = rospy.Subscriber(f"{robot}/actual_pose", PoseStamped, lambda m: latest.append(m.pose))
    pub = rospy.Publisher(f"{robot}/desired_pose", PoseStamped, queue_size=1)

    try:
        wait_until(lambda: pub.get_num_connections() > 0, 20, what="the desired_pose link")
        pub.publish(goal(10.0, 10.0, -5.0, "map"))
        wait_until(lambda: at(latest, 10.0, 10.0, -5.0), 15, what="the goal in map")
        pub.publish(goal(1.0, 0.0, 0.0, "airsim_node/Drone1"))  # the node's tf now holds this scene's time
        wait_until(lambda: at(latest, 11.0, 10.0, -5.0), 15, what="the first body-frame goal")
        time.sleep(3.0)  # the old scene's time runs well ahead of where the new one starts
        rostopic_pub(rig, "/ProjectAirSim/node/switch_bridge/load_scene", TWO, "-1")
        wait_topic("/airsim_node/Drone2/actual_pose", node)
        wait_until(lambda: not at(latest, 11.0, 10.0, -5.0), 15, what="Drone1 at its new scene's start")
        time.sleep(1.0)
        start = latest[-1].position
        pub.publish(goal(1.0, 0.0, 0.0, "airsim_node/Drone1"))
        wait_until(lambda: at(latest, start.x + 1.0, start.y, start.z), 15, what="1 m ahead of the new pose")
    finally:
        sub.unregister()
        pub.unregister()
    assert "TF_OLD_DATA" not in node.output()
    node.stop()
