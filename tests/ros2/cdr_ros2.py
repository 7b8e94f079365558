"""The CDR bytes ros2_cdr writes for the per-pose messages, run by pytest in .venv-ros2
(test_ros2_cdr.py): for many simulator frames, the bytes of the converters' messages are rclpy's
serialisation of them, and a subscriber takes them, published through the ROS link, as those messages."""

from __future__ import annotations

import threading
import time
from typing import Any

import rclpy
from geometry_msgs.msg import PoseStamped
from hypothesis import given, settings
from hypothesis import strategies as st
from rclpy.executors import SingleThreadedExecutor
from rclpy.serialization import deserialize_message, serialize_message
from tf2_msgs.msg import TFMessage

from airsim_mapper.convert.clock import clock
from airsim_mapper.convert.context import ConvertContext
from airsim_mapper.convert.pose import robot_pose
from airsim_mapper.engine import ros2_cdr
from airsim_mapper.engine.ros2_link import Ros2Link
from airsim_mapper.engine.tf_poses import transform_from_pose
from airsim_mapper.mapping.model import Qos

floats = st.floats(-1e12, 1e12)  # finite, also once turned to ENU
# a frame name: text (no NUL, which ends a C string)
frames = st.text(st.characters(exclude_categories=("Cs",), exclude_characters="\x00"), max_size=40)
sim_poses = st.fixed_dictionaries(
    {
        "time_stamp": st.integers(0, 2**31 * 10**9 - 1),
        "position": st.fixed_dictionaries({"x": floats, "y": floats, "z": floats}),
        "orientation": st.fixed_dictionaries({"w": floats, "x": floats, "y": floats, "z": floats}).filter(
            lambda q: any(q.values())  # the converters refuse a zero quaternion
        ),
    }
)
conventions = st.sampled_from(["ned", "enu"])


def converted(sim: dict[str, Any], frame: str, convention: str) -> PoseStamped:
    return robot_pose(sim, ConvertContext(frame_id=frame, convention=convention))


def assert_rclpy_bytes(ours: bytes, message: Any) -> None:
    """`ours` is rclpy's serialisation of `message`: the same length, the same bytes but where rclpy leaves
    alignment padding unset (ours holds zeros there), and read back as `message`."""
    theirs = serialize_message(message)
    assert len(ours) == len(theirs)
    assert all(a == 0 for a, b in zip(ours, theirs) if a != b), (ours.hex(), theirs.hex())
    assert deserialize_message(ours, type(message)) == message


@settings(max_examples=300, deadline=None)
@given(sim_poses, frames, conventions)
def test_a_converted_pose_is_written_as_rclpy_serialises_it(sim: dict, frame: str, convention: str) -> None:
    message = converted(sim, frame, convention)
    assert_rclpy_bytes(ros2_cdr.pose_stamped(message), message)


@settings(max_examples=200, deadline=None)
@given(st.lists(st.tuples(sim_poses, frames, frames, conventions), max_size=5))
def test_transforms_are_written_as_rclpy_serialises_their_tf_message(cases: list) -> None:
    transforms = [
        transform_from_pose(converted(sim, "", convention), parent, child)
        for sim, parent, child, convention in cases
    ]
    message = TFMessage(transforms=transforms)
    ours = ros2_cdr.tf_transforms(transforms)
    assert ours == ros2_cdr.tf_message(message)
    assert_rclpy_bytes(ours, message)


@settings(max_examples=100, deadline=None)
@given(sim_poses)
def test_a_clock_is_written_as_rclpy_serialises_it(sim: dict) -> None:
    message = clock(sim, ConvertContext())
    assert_rclpy_bytes(ros2_cdr.clock(message), message)


def test_only_the_per_pose_types_have_a_writer() -> None:
    from geometry_msgs.msg import TransformStamped
    from nav_msgs.msg import Odometry
    from rosgraph_msgs.msg import Clock

    assert ros2_cdr.writer(PoseStamped) is ros2_cdr.pose_stamped
    assert ros2_cdr.writer(TFMessage) is ros2_cdr.tf_message
    assert ros2_cdr.writer(Clock) is ros2_cdr.clock
    assert ros2_cdr.writer(TransformStamped) is None and ros2_cdr.writer(Odometry) is None


def test_a_subscriber_takes_what_the_link_publishes_as_bytes() -> None:
    """Poses through the link's publisher and transforms through its /tf, to subscribers in another node."""
    sims = [
        {
            "time_stamp": 1_700_000_000_000_000_000 + i * 10_000_000,
            "position": {"x": i * 0.5, "y": -1.25 * i, "z": -3.0},
            "orientation": {"w": 1.0, "x": 0.01 * i, "y": 0.0, "z": -0.02 * i},
        }
        for i in range(20)
    ]
    poses = [converted(sim, "map" + "é" * (i % 5), "enu") for i, sim in enumerate(sims)]
    tf_batches = [
        [transform_from_pose(p, "map", f"drone{i % 3}" * (1 + i % 4))] * (1 + i % 2)
        for i, p in enumerate(poses)
    ]
    rclpy.init()
    try:
        node, listener = rclpy.create_node("cdr_talker"), rclpy.create_node("cdr_listener")
        executor = SingleThreadedExecutor()
        executor.add_node(listener)
        got_poses: list = []
        got_tf: list = []
        reliable = rclpy.qos.QoSProfile(depth=100, reliability=rclpy.qos.ReliabilityPolicy.RELIABLE)
        listener.create_subscription(PoseStamped, "/cdr/pose", got_poses.append, reliable)
        listener.create_subscription(TFMessage, "/tf", got_tf.append, reliable)
        link = Ros2Link(node)
        qos = Qos("reliable", "volatile", 100)
        publisher = link.publisher("/cdr/pose", "geometry_msgs/PoseStamped", queue_size=100, qos=qos)
        spinning = threading.Thread(target=executor.spin, daemon=True)
        spinning.start()
        deadline = time.monotonic() + 10
        while publisher.get_num_connections() == 0 or not link.tf_wanted():
            assert time.monotonic() < deadline, "the listener never matched"
            time.sleep(0.05)
        for pose, batch in zip(poses, tf_batches):
            publisher.publish(pose)
            link.send_tf(batch)
            time.sleep(0.005)
        while len(got_poses) < len(poses) or len(got_tf) < len(tf_batches):
            assert time.monotonic() < deadline, (len(got_poses), len(got_tf))
            time.sleep(0.05)
        assert got_poses == poses
        assert got_tf == [TFMessage(transforms=batch) for batch in tf_batches]
        executor.shutdown()
    finally:
        rclpy.try_shutdown()
