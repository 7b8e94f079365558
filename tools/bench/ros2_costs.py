"""What a ROS 2 message costs to build and serialise in Python, the bridge's way beside the plain ones.

Run in .venv-ros2 from the repository root: `.venv-ros2/bin/python -m tools.bench.ros2_costs [--calls N]`.
Per pose: the pose converter (sim message -> PoseStamped), the bare forwarder's attribute setting, rosidl's
keyword constructors, rclpy's serialisation against the bridge's CDR writer (engine/ros2_cdr.py), and
`publish()` of the message against its CDR bytes, to a subscriber in another process (the CPU of this
process: rclpy and Fast DDS's sending side; `ROS_DOMAIN_ID` as set). Per 1080p frame: the converters' Image
(`buffer_data.ros2_buffer_message`, one copy from the frame) against `bytes` through the constructor. Best
of five runs, CPU time of this process (`time.process_time`), its malloc thresholds fixed as the node's
(`tuning.keep_frame_buffers`).
"""

from __future__ import annotations

import argparse
import subprocess
import sys
import time
from collections.abc import Callable

FRAME = 1920 * 1080 * 3
POSE = {
    "time_stamp": 1_765_000_000_123_456_789,
    "position": {"x": 1.0, "y": 2.0, "z": -3.0},
    "orientation": {"w": 1.0, "x": 0.0, "y": 0.0, "z": 0.0},
}


def best_us(action: Callable[[], object], calls: int) -> float:
    """The fastest of five runs of `calls` calls, per call in microseconds."""
    runs = []
    for _ in range(5):
        start = time.process_time()
        for _ in range(calls):
            action()
        runs.append((time.process_time() - start) / calls * 1e6)
    return min(runs)


def cases() -> dict[str, tuple[Callable[[], object], int]]:
    """Each case's action and how many calls make one run."""
    from builtin_interfaces.msg import Time
    from geometry_msgs.msg import Point, Pose, PoseStamped, Quaternion
    from rclpy.serialization import serialize_message
    from sensor_msgs.msg import Image
    from std_msgs.msg import Header

    from airsim_mapper.convert.buffer_data import ros2_buffer_message
    from airsim_mapper.convert.context import ConvertContext
    from airsim_mapper.convert.pose import robot_pose
    from airsim_mapper.engine.ros2_cdr import pose_stamped
    from tools.bench.forwarder_ros2 import NANOSECONDS

    ctx = ConvertContext(frame_id="map")

    def by_attributes() -> PoseStamped:
        out = PoseStamped()
        out.header.stamp.sec, out.header.stamp.nanosec = divmod(POSE["time_stamp"], NANOSECONDS)
        out.header.frame_id = "map"
        p, q, o = POSE["position"], POSE["orientation"], out.pose.orientation
        out.pose.position.x, out.pose.position.y, out.pose.position.z = p["x"], p["y"], p["z"]
        o.w, o.x, o.y, o.z = q["w"], q["x"], q["y"], q["z"]
        return out

    def by_keywords() -> PoseStamped:
        sec, nanosec = divmod(POSE["time_stamp"], NANOSECONDS)
        return PoseStamped(
            header=Header(stamp=Time(sec=sec, nanosec=nanosec), frame_id="map"),
            pose=Pose(position=Point(x=1.0, y=2.0, z=-3.0), orientation=Quaternion(w=1.0)),
        )

    frame = memoryview(bytearray(FRAME))
    image = {"height": 1080, "width": 1920, "encoding": "bgr8", "step": 1920 * 3}
    buffer_image = ros2_buffer_message(Image)
    built = robot_pose(POSE, ctx)
    publisher, cdr = matched_publisher(PoseStamped), pose_stamped(built)
    return {
        "pose: the converter": (lambda: robot_pose(POSE, ctx), 20_000),
        "pose: the forwarder's attribute setting": (by_attributes, 20_000),
        "pose: rosidl's keyword constructors": (by_keywords, 20_000),
        "pose: rclpy serialize_message": (lambda: serialize_message(built), 20_000),
        "pose: the CDR writer": (lambda: pose_stamped(built), 20_000),
        "pose: publish() of the message": (lambda: publisher.publish(built), 20_000),
        "pose: publish() of its CDR bytes, given": (lambda: publisher.publish(cdr), 20_000),
        "pose: publish() of its CDR bytes, written": (lambda: publisher.publish(pose_stamped(built)), 20_000),
        "1080p Image: the converters' (one copy)": (lambda: buffer_image(**image, data=frame), 20),
        "1080p Image: bytes through the constructor": (lambda: Image(**image, data=bytes(frame)), 20),
    }


TOPIC = "/ros2_costs"
# A subscriber that takes the poses serialised (nothing deserialised), in a process of its own.
SUBSCRIBER = f"""
import rclpy
from geometry_msgs.msg import PoseStamped
rclpy.init()
node = rclpy.create_node("ros2_costs_subscriber")
node.create_subscription(PoseStamped, "{TOPIC}", lambda _raw: None, 10, raw=True)
rclpy.spin(node)
"""
MATCH_TIMEOUT_S = 20.0


def matched_publisher(message_class: type) -> object:
    """An rclpy publisher of `message_class` (rclpy initialised here) once SUBSCRIBER, started for the rest
    of this process's life, has matched it."""
    import atexit

    import rclpy

    rclpy.init()
    publisher = rclpy.create_node("ros2_costs").create_publisher(message_class, TOPIC, 10)
    subscriber = subprocess.Popen([sys.executable, "-c", SUBSCRIBER])
    atexit.register(subscriber.kill)
    deadline = time.monotonic() + MATCH_TIMEOUT_S
    while publisher.get_subscription_count() == 0:
        if time.monotonic() > deadline or subscriber.poll() is not None:
            raise SystemExit("the subscriber process did not match the publisher")
        time.sleep(0.1)
    return publisher


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--calls", type=float, default=1.0, help="scale the calls per run")
    args = parser.parse_args(argv)
    from airsim_mapper.common.tuning import keep_frame_buffers

    keep_frame_buffers()
    for name, (action, calls) in cases().items():
        print(f"{name:45s} {best_us(action, max(1, int(calls * args.calls))):10.1f} us", flush=True)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
