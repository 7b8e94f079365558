"""The runners against fake links: what each catalogue runner sends, its after-hooks, lazy attach and
detach as ROS subscribers come and go, and the command watchdog. No simulator, no ROS master."""

from __future__ import annotations

import logging
import time

import pytest
from fakes import IMU_MESSAGE, FakeRos, FakeSimLink
from geometry_msgs.msg import PoseStamped, Twist
from harness import SIM_CONFIG, wait_until
from std_msgs.msg import String
from std_srvs.srv import TriggerRequest

from airsim_mapper.convert.pose import camera_pose_key
from airsim_mapper.engine.bridges import BridgeParts, SimToRos, StreamingImage
from airsim_mapper.engine.hub import StreamHub
from airsim_mapper.engine.mounts import CameraMounts
from airsim_mapper.engine.ros_to_sim import RosService, RosToSim
from airsim_mapper.engine.runners import build
from airsim_mapper.mapping.expand import expand
from airsim_mapper.mapping.loader import load_mapping
from airsim_mapper.mapping.scene import read_scene


@pytest.fixture(scope="module")
def specs():
    scene = read_scene(str(SIM_CONFIG), "scene_drone_sensors.jsonc")
    return {spec.name: spec for spec in expand(load_mapping("default"), scene, "node", "")}


def spec_of(specs, prefix: str):
    return next(spec for name, spec in specs.items() if name.startswith(prefix))


@pytest.fixture
def sim() -> FakeSimLink:
    return FakeSimLink()


@pytest.fixture
def ros() -> FakeRos:
    return FakeRos()


@pytest.fixture
def services(sim: FakeSimLink, ros: FakeRos) -> BridgeParts:
    actions: list[tuple[str, dict]] = []
    found = BridgeParts(
        sim, StreamHub(sim, ros.send_tf), ros, CameraMounts(), lambda a, p: actions.append((a, p))
    )
    found.actions = actions  # type: ignore[attr-defined]
    return found


def test_the_catalogue_picks_each_runner(specs, services):
    kinds = {name.split("[")[0]: type(build(spec, services)) for name, spec in specs.items()}
    assert kinds["actual_pose"] is SimToRos
    assert kinds["streaming_image"] is StreamingImage
    assert kinds["cmd_vel"] is RosToSim and kinds["load_scene"] is RosToSim
    assert kinds["switch_view"] is RosService and kinds["takeoff_all"] is RosService


def test_a_lazy_bridge_subscribes_to_the_simulator_only_while_ros_listens(specs, services, sim, ros):
    spec = spec_of(specs, "imu[Drone1/IMU1]")
    bridge = build(spec, services)
    bridge.start()
    publisher = ros.publishers[spec.ros]
    assert spec.options.lazy and spec.sim not in sim.subscriptions
    publisher.subscribers(1)
    assert spec.sim in sim.subscriptions
    assert sim.deliver(spec.sim, IMU_MESSAGE) == 1
    wait_until(lambda: len(publisher.messages) == 1, 5, what="the converted IMU message")
    imu = publisher.messages[0]
    assert imu.header.frame_id == spec.frame_id and imu.linear_acceleration.z == pytest.approx(-9.8)
    publisher.subscribers(0)
    assert spec.sim not in sim.subscriptions
    assert sim.deliver(spec.sim, IMU_MESSAGE) == 0
    publisher.subscribers(2)  # back again: subscribed anew
    assert spec.sim in sim.subscriptions
    bridge.stop()
    assert spec.sim not in sim.subscriptions and publisher.unregistered
    publisher.subscribers(1)  # a late peer callback after the stop attaches nothing
    assert spec.sim not in sim.subscriptions


def test_cmd_vel_drives_the_robot_and_the_watchdog_stops_it_when_commands_stop(specs, services, sim, ros):
    spec = spec_of(specs, "cmd_vel[Drone1]")
    bridge = build(spec, services)
    bridge.start()
    twist = Twist()
    twist.linear.x = 1.0
    ros.subscribers[spec.ros].handler(twist)
    assert [method for method, _ in sim.calls] == [spec.sim]
    timeout = spec.options.watchdog_s
    assert timeout is not None
    bridge.check_watchdog(time.monotonic())  # commands are still fresh
    assert len(sim.calls) == 1
    bridge.check_watchdog(time.monotonic() + timeout + 0.1)
    stop_method = spec.params.get("stop_method", "Hover")
    assert sim.calls[-1] == (f"{spec.sim.rsplit('/', 1)[0]}/{stop_method}", {})
    bridge.check_watchdog(time.monotonic() + 2 * timeout + 0.2)  # stopped once, not again
    assert len(sim.calls) == 2


def test_a_refused_command_is_counted_and_nothing_is_sent(specs, services, sim, ros):
    spec = spec_of(specs, "cmd_vel[Drone1]")
    bridge = build(spec, services)
    bridge.start()
    twist = Twist()
    twist.linear.x = float("nan")
    ros.subscribers[spec.ros].handler(twist)
    assert sim.calls == [] and bridge.stats.errors == 1


def test_switch_view_calls_the_simulator_then_every_streaming_image_follows(specs, services, sim, ros):
    stream_spec = spec_of(specs, "streaming_image[")
    streams = [build(stream_spec, services), build(stream_spec, services)]
    for stream in streams:
        stream.cameras = [{"sim": "/Sim/a"}, {"sim": "/Sim/b"}]  # two streaming cameras
        stream.topic = "/Sim/a"
        stream.start()
    spec = spec_of(specs, "switch_view[")
    service = build(spec, services)
    service.start()
    handler = ros.services[spec.ros].handler
    assert handler(TriggerRequest()).success and sim.calls == [(spec.sim, {})]
    assert [s.topic for s in streams] == ["/Sim/b", "/Sim/b"]
    sim.result = False  # the simulator refused: the streaming images stay on their cameras
    refusal = handler(TriggerRequest())
    assert not refusal.success and refusal.message == f"{spec.sim.rsplit('/', 1)[-1]} returned false"
    assert [s.topic for s in streams] == ["/Sim/b", "/Sim/b"]
    streams[0].stop()
    sim.result = True
    handler(TriggerRequest())
    assert [s.topic for s in streams] == ["/Sim/b", "/Sim/a"]  # a stopped stream no longer follows


def test_a_camera_pose_command_is_remembered_once_the_simulator_took_it(specs, services, sim, ros):
    spec = spec_of(specs, "camera_desired_pose[Drone1/DownCamera")
    build(spec, services).start()
    goal = PoseStamped()
    goal.pose.orientation.w = 1.0
    goal.pose.position.x = 2.0
    ros.subscribers[spec.ros].handler(goal)
    assert [method for method, _ in sim.calls] == [spec.sim]
    assert camera_pose_key("Drone1", "DownCamera") in services.mounts


def test_load_scene_asks_the_engine_for_its_action(specs, services, sim, ros):
    spec = spec_of(specs, "load_scene[")
    build(spec, services).start()
    ros.subscribers[spec.ros].handler(String(data=" scene_basic_drone.jsonc "))
    assert services.actions == [("load_scene", {"scene": "scene_basic_drone.jsonc"})]
    assert sim.calls == [] and sim.published == []


def test_a_clamped_command_is_counted_and_warned_at_most_once_per_period(specs, services, sim, ros, caplog):
    spec = spec_of(specs, "cmd_vel[Drone1]")
    assert spec.options.limits.on_violation == "clamp"
    bridge = build(spec, services)
    bridge.start()
    twist = Twist()
    twist.linear.x = 1e308
    with caplog.at_level(logging.WARNING, logger="rosout.airsim_mapper.bridge"):
        for _ in range(3):
            ros.subscribers[spec.ros].handler(twist)
    top = spec.options.limits.max_linear_speed
    assert len(sim.calls) == 3 and sim.calls[0][1]["vx"] == pytest.approx(top)
    assert bridge.stats.clamped == 3 and bridge.stats.errors == 0
    warnings = [r.getMessage() for r in caplog.records]
    assert len(warnings) == 1 and "clamped linear speed 1e+308 m/s to max_linear_speed 20" in warnings[0]


def test_a_goal_in_a_huge_frame_is_refused_with_the_frame_cut_short(specs, services, sim, ros, caplog):
    spec = spec_of(specs, "desired_pose[Drone1]")
    bridge = build(spec, services)
    bridge.start()
    goal = PoseStamped()
    goal.header.frame_id = "x" * 10_000_000
    goal.pose.orientation.w = 1.0
    with caplog.at_level(logging.WARNING, logger="rosout.airsim_mapper.bridge"):
        for _ in range(5):
            ros.subscribers[spec.ros].handler(goal)
    assert sim.calls == [] and bridge.stats.errors == 5
    warnings = [r.getMessage() for r in caplog.records]
    assert len(warnings) == 1 and len(warnings[0]) < 1000 and "more)" in warnings[0]
    assert len(bridge.stats.last_error) < 1000  # the status topic and /diagnostics show it too


def test_a_converter_that_raises_something_else_is_a_bridge_error_logged_with_its_traceback(
    specs, services, sim, ros, caplog
):
    def broken(_msg, _ctx):
        raise RuntimeError("a converter bug")

    spec = spec_of(specs, "imu[Drone1/IMU1]")
    bridge = build(spec, services)
    bridge.convert = broken
    bridge.start()
    ros.publishers[spec.ros].subscribers(1)
    sim.deliver(spec.sim, IMU_MESSAGE)
    wait_until(lambda: bridge.stats.errors == 1, 5, what="the bridge error")
    assert "RuntimeError: a converter bug" in bridge.stats.last_error
    stream = services.hub.streams()[spec.sim]
    wait_until(lambda: stream.stats.handled == 1, 5, what="the handled message")
    assert stream.stats.errors == 0 and services.counts.bad == 0  # the bridge's error, not the stream's
    logged = [r for r in caplog.records if "a converter bug" in r.getMessage()]
    assert logged and logged[0].exc_info is not None and logged[0].exc_info[0] is RuntimeError
    bridge.stop()

    command = build(spec_of(specs, "cmd_vel[Drone1]"), services)
    command.convert = broken
    command.start()
    ros.subscribers[command.spec.ros].handler(Twist())
    assert command.stats.errors == 1 and sim.calls == []
    service = build(spec_of(specs, "takeoff[Drone1]"), services)
    service.convert = broken
    service.start()
    response = ros.services[service.spec.ros].handler(TriggerRequest())
    assert not response.success and "a converter bug" in response.message and service.stats.errors == 1


def test_the_watchdog_says_when_it_can_next_be_due(specs, services, sim, ros):
    """The supervisor sleeps until then instead of polling: the full timeout while no command moves the
    robot, the rest of it while commands flow."""
    spec = spec_of(specs, "cmd_vel[Drone1]")
    bridge = build(spec, services)
    bridge.start()
    timeout = spec.options.watchdog_s
    assert bridge.check_watchdog(time.monotonic()) == timeout  # nothing sent yet
    twist = Twist()
    twist.linear.x = 1.0
    ros.subscribers[spec.ros].handler(twist)
    assert bridge.check_watchdog(bridge.last_message + 1.0) == pytest.approx(timeout - 1.0)
    assert bridge.check_watchdog(bridge.last_message + timeout + 0.1) == timeout  # stopped the robot
    assert not bridge.moving and len(sim.calls) == 2
    assert bridge.check_watchdog(bridge.last_message + 1.0) == timeout


def test_a_pose_builds_its_transform_only_while_tf_has_a_subscriber(specs, services, ros):
    """rospy would drop a tf message nobody subscribes to: its transform is not even built then."""
    bridge = build(spec_of(specs, "actual_pose[Drone1]"), services)
    bridge.start()
    pose = {
        "time_stamp": 2_000_000_000,
        "position": {"x": 1.0, "y": 2.0, "z": -3.0},
        "orientation": {"w": 1.0, "x": 0.0, "y": 0.0, "z": 0.0},
    }
    ros.tf_subscribed = False
    assert bridge.handle(pose) is None
    ros.tf_subscribed = True
    [transform] = bridge.handle(pose)
    tf = bridge.spec.tf
    assert (transform.header.frame_id, transform.child_frame_id) == (tf.parent, tf.child)
    assert transform.transform.translation.x == 1.0 and bridge.stats.messages == 2
    bridge.stop()


def test_a_pose_at_the_stamp_of_the_last_transform_is_published_without_a_transform(specs, services, ros):
    """A robot reset while the simulation is paused: its new pose comes at the paused time, which tf
    listeners refuse for a second transform (TF_REPEATED_DATA), so only the topic carries it."""
    bridge = build(spec_of(specs, "actual_pose[Drone1]"), services)
    bridge.start()
    ros.tf_subscribed = True

    def pose(x: float, stamp: int) -> dict:
        return {
            "time_stamp": stamp,
            "position": {"x": x, "y": 0.0, "z": 0.0},
            "orientation": {"w": 1.0, "x": 0.0, "y": 0.0, "z": 0.0},
        }

    [first] = bridge.handle(pose(1.0, 5_000_000_000))
    assert bridge.handle(pose(0.0, 5_000_000_000)) is None  # reset while paused: same time
    published = ros.publishers[bridge.spec.ros].messages
    assert [m.pose.position.x for m in published[-2:]] == [1.0, 0.0]
    [later] = bridge.handle(pose(0.0, 5_010_000_000))  # resumed: the time moves on
    assert later.transform.translation.x == 0.0 and later.header.stamp > first.header.stamp
    bridge.new_session()  # the simulator's time started over: any stamp is new again
    assert bridge.handle(pose(0.0, 5_010_000_000)) is not None
    bridge.stop()


def test_a_false_reply_to_a_timed_call_names_the_method_and_its_time_limit():
    from airsim_mapper.engine.ros_to_sim import refused

    land = "/Sim/S/robots/Drone1/Land"
    assert refused(land, {"timeout_sec": 60}, False, 61.0) == (
        "Land returned false after its timeout_sec, 60 s (the robot stays where it got to)"
    )
    assert refused(land, {"timeout_sec": 60}, False, 0.2) == "Land returned false"  # refused at once
    assert refused("/Sim/S/robots/Drone1/Hover", {}, None) == "Hover returned nothing"
