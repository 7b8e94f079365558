"""Control services of the default mapping, end to end: takeoff, land, hover, arm, disarm, api control,
reset to the scene origin, pause/step/resume of the sim clock, and collisions reported on the way."""

from __future__ import annotations

import time
from collections.abc import Iterator

import numpy as np
import pytest
from bridgeharness import Stack
from harness import wait_until

ROBOT = "/airsim_node/Drone1"
STEP_NS = 3_000_000  # the scene's clock step-ns
ROBOT_SERVICES = (
    "takeoff",
    "land",
    "hover",
    "arm",
    "disarm",
    "enable_api_control",
    "disable_api_control",
    "reset",
)


@pytest.fixture(scope="module")
def rig(module_rig_factory) -> Stack:
    rig = module_rig_factory()
    rig.start_node(
        "--scene", "scene_drone_sensors.jsonc", node_name="srv_bridge", wait_for=f"{ROBOT}/actual_pose"
    )
    return rig


class PoseWatch:
    """The latest actual_pose position (NED)."""

    def __init__(self) -> None:
        import rospy
        from geometry_msgs.msg import PoseStamped

        self.position: np.ndarray | None = None
        self.sub = rospy.Subscriber(f"{ROBOT}/actual_pose", PoseStamped, self._on_pose, queue_size=1)
        wait_until(lambda: self.position is not None, 20, what="a pose")

    def _on_pose(self, msg) -> None:
        p = msg.pose.position
        self.position = np.array([p.x, p.y, p.z])


@pytest.fixture(scope="module")
def pose(rig: Stack) -> Iterator[PoseWatch]:
    watch = PoseWatch()
    yield watch
    watch.sub.unregister()


def call(name: str, *args):
    import rospy
    from std_srvs.srv import SetBool, Trigger

    rospy.wait_for_service(name, timeout=20)
    return rospy.ServiceProxy(name, SetBool if name.endswith("/pause") else Trigger)(*args)


class ClockWatch:
    """Every /clock stamp published since the watch began (ns)."""

    def __init__(self) -> None:
        import rospy
        from rosgraph_msgs.msg import Clock

        self.stamps: list[int] = []
        self.sub = rospy.Subscriber("/clock", Clock, lambda m: self.stamps.append(m.clock.to_nsec()))
        wait_until(lambda: self.stamps, 10, what="/clock")

    def shows(self, stamp_ns: int, what: str) -> None:
        wait_until(lambda: self.stamps[-1] == stamp_ns, 5, what=what)


def test_every_control_service_is_advertised_with_its_type(rig: Stack):
    import rosgraph
    import rosservice

    names = [f"{ROBOT}/{name}" for name in ROBOT_SERVICES] + ["/airsim_node/pause", "/airsim_node/step"]
    for name in names:
        call_type = "std_srvs/SetBool" if name.endswith("/pause") else "std_srvs/Trigger"
        wait_until(lambda n=name: rosservice.get_service_type(n) is not None, 20, what=name)
        assert rosservice.get_service_type(name) == call_type
    _pubs, _subs, services = rosgraph.Master("/probe").getSystemState()
    ours = {name for name, nodes in services if "/srv_bridge" in nodes}
    assert set(names) <= ours


def test_api_control_and_arming_services_succeed(rig: Stack):
    for name in ("enable_api_control", "arm", "disarm", "disable_api_control", "enable_api_control", "arm"):
        reply = call(f"{ROBOT}/{name}")
        assert (reply.success, reply.message) == (True, ""), name


def test_land_brings_the_drone_to_the_ground_and_takeoff_lifts_it(rig: Stack, pose: PoseWatch):
    reply = call(f"{ROBOT}/land")
    assert reply.success
    # the reply comes at touchdown; the pose reaches this probe a little later
    wait_until(lambda: abs(pose.position[2]) < 0.2, 10, what="a landed pose (NED z near 0)")
    reply = call(f"{ROBOT}/takeoff")
    assert reply.success
    wait_until(lambda: pose.position[2] < -2.5, 5, what="the drone to rise")
    assert call(f"{ROBOT}/hover").success
    time.sleep(0.3)
    held = pose.position.copy()
    time.sleep(0.3)
    assert pose.position == pytest.approx(held, abs=0.05)


def test_land_from_take_off_height_waits_for_the_whole_descent(rig: Stack, pose: PoseWatch):
    assert call(f"{ROBOT}/reset").success  # back at the scene's origin, 4 m up
    wait_until(lambda: np.allclose(pose.position, [0.0, 0.0, -4.0], atol=0.05), 10, what="the origin")
    time.sleep(0.5)
    assert call(f"{ROBOT}/takeoff").success
    wait_until(lambda: pose.position[2] < -6.9, 10, what="take-off height (7 m up)")
    started = time.monotonic()
    reply = call(f"{ROBOT}/land")  # 7 m at 0.2 m/s: longer than the bridge's plain 30 s wait
    assert (reply.success, reply.message) == (True, "")
    assert time.monotonic() - started > 30
    wait_until(lambda: abs(pose.position[2]) < 0.2, 10, what="a landed pose (NED z near 0)")


def test_flying_into_a_block_reports_the_collision_and_reset_returns_to_the_origin(
    rig: Stack, pose: PoseWatch
):
    import rospy
    from geometry_msgs.msg import PointStamped, PoseStamped, Twist

    hits: list[PointStamped] = []
    sub = rospy.Subscriber(f"{ROBOT}/collision", PointStamped, hits.append, queue_size=10)
    teleport = rospy.Publisher(f"{ROBOT}/desired_pose", PoseStamped, queue_size=1)
    velocity = rospy.Publisher(f"{ROBOT}/cmd_vel", Twist, queue_size=1)
    wait_until(lambda: teleport.get_num_connections() and velocity.get_num_connections(), 20, what="links")
    wait_until(lambda: sub.get_num_connections() > 0, 20, what="the collision topic")
    target = PoseStamped()
    target.header.frame_id = "map"
    target.pose.position.x, target.pose.position.z, target.pose.orientation.w = 25.0, -4.0, 1.0
    teleport.publish(target)  # 3 m short of BlockNorth's south face (x = 28), facing it
    wait_until(lambda: np.allclose(pose.position, [25.0, 0.0, -4.0], atol=0.05), 10, what="the teleport")
    forward = Twist()
    forward.linear.x = 3.0
    deadline = time.monotonic() + 10
    while not hits and time.monotonic() < deadline:
        velocity.publish(forward)
        time.sleep(0.1)
    sub.unregister()
    assert hits, "no collision reported"
    hit = hits[0]
    assert hit.header.frame_id == "map"
    assert (hit.point.x, hit.point.y, hit.point.z) == pytest.approx((28.0, 0.0, -4.0), abs=0.3)
    assert pose.position[0] < 28.0  # the block stopped the drone
    reply = call(f"{ROBOT}/reset")
    assert reply.success
    wait_until(lambda: np.allclose(pose.position, [0.0, 0.0, -4.0], atol=0.05), 10, what="the reset")
    teleport.unregister()
    velocity.unregister()


def test_pause_stops_sim_time_step_advances_one_step_and_resume_runs_it_again(rig: Stack):
    clock = ClockWatch()
    reply = call("/airsim_node/pause", True)
    try:
        assert reply.success and reply.message.startswith("Sim time paused at t = ")
        paused_at = int(reply.message.rsplit(" ", 1)[1])
        clock.shows(paused_at, "/clock to show the pause")
        seen = len(clock.stamps)
        time.sleep(0.3)
        assert len(clock.stamps) == seen  # paused: no physics tick, so no pose and no /clock
        stepped = call("/airsim_node/step")
        assert stepped.success and int(stepped.message) == paused_at + STEP_NS
        clock.shows(paused_at + STEP_NS, "/clock to show the step")
        time.sleep(0.2)
        assert clock.stamps[seen:] == [paused_at + STEP_NS]  # one step, one stamp; paused again after it
    finally:
        resumed = call("/airsim_node/pause", False)
    assert resumed.success and resumed.message.startswith("Sim time resumed from t = ")
    before = clock.stamps[-1]
    time.sleep(0.2)
    assert clock.stamps[-1] - before > 100_000_000
    clock.sub.unregister()


def test_a_reset_while_paused_moves_the_pose_topic_and_sends_tf_no_transform_twice(
    rig: Stack, pose: PoseWatch
):
    """The reset pose comes at the paused time: the topic carries it, and tf, which would refuse a second
    transform at that time (TF_REPEATED_DATA in every listener), gets it once the time moves on."""
    import rospy
    from geometry_msgs.msg import PoseStamped
    from tf2_msgs.msg import TFMessage

    child = ROBOT.lstrip("/")
    sent: list[tuple[int, float]] = []  # (stamp ns, x) of each of the robot's transforms on /tf

    def on_tf(message: TFMessage) -> None:
        mine = [t for t in message.transforms if t.child_frame_id == child]
        sent.extend((t.header.stamp.to_nsec(), t.transform.translation.x) for t in mine)

    tf_sub = rospy.Subscriber("/tf", TFMessage, on_tf, queue_size=1000)
    teleport = rospy.Publisher(f"{ROBOT}/desired_pose", PoseStamped, queue_size=1)
    try:
        wait_until(lambda: sent and teleport.get_num_connections(), 20, what="/tf and the desired_pose link")
        target = PoseStamped()
        target.header.frame_id = "map"
        target.pose.position.x, target.pose.position.z, target.pose.orientation.w = 5.0, -4.0, 1.0
        teleport.publish(target)
        wait_until(lambda: np.allclose(pose.position, [5.0, 0.0, -4.0], atol=0.05), 10, what="the teleport")
        assert call("/airsim_node/pause", True).success
        try:
            time.sleep(0.3)
            assert call(f"{ROBOT}/reset").success
            wait_until(lambda: np.allclose(pose.position, [0.0, 0.0, -4.0], atol=0.05), 10, what="the reset")
            time.sleep(0.3)
        finally:
            resumed = call("/airsim_node/pause", False)
        assert resumed.success
        wait_until(lambda: abs(sent[-1][1]) < 0.05, 10, what="the reset pose on /tf after the pause")
        stamps = [stamp for stamp, _ in sent]
        assert len(stamps) == len(set(stamps)), "a transform sent twice at one time"
    finally:
        tf_sub.unregister()
        teleport.unregister()
