"""An rclpy listener, run by .venv-ros2's Python against a running ROS 2 bridge node.

`listen_ros2.py SECONDS TYPE=TOPIC ... [call:SERVICE] [say:TOPIC=TEXT]` subscribes to each topic
(best-effort, which also matches a reliable publisher; transient-local for /tf_static), publishes each TEXT
once as a std_msgs/String on its TOPIC (once a subscriber is there), waits until every topic delivered or
SECONDS passed, calls the std_srvs/Trigger services named, and prints one JSON line: per topic a summary of
its first message, per service its response. `TOPIC@reliable` subscribes reliably instead (reported under
that name; it does not match a best-effort publisher).
"""

from __future__ import annotations

import importlib
import json
import sys
import time

import rclpy
from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy


def message_type(name: str) -> type:
    package, _, kind = name.partition("/")
    return getattr(importlib.import_module(f"{package}.msg"), kind)


def summary(msg: object) -> dict:
    """The fields a test checks, of whichever message it is."""
    out: dict = {"type": type(msg).__name__}
    header = getattr(msg, "header", None)
    if header is not None:
        out["frame_id"] = header.frame_id
        out["stamp"] = [header.stamp.sec, header.stamp.nanosec]
    for name in (
        "height",
        "width",
        "encoding",
        "format",
        "step",
        "point_step",
        "row_step",
        "distortion_model",
    ):
        if hasattr(msg, name):
            out[name] = getattr(msg, name)
    if hasattr(msg, "data"):
        out["data_len"] = len(msg.data)
        if isinstance(msg.data, str):
            out["text"] = msg.data
    if hasattr(msg, "fields") and not isinstance(msg.fields, str):
        out["fields"] = [f.name for f in msg.fields]
    for name in ("k", "p", "d"):
        if hasattr(msg, name):
            out[name] = [float(v) for v in getattr(msg, name)]
    if hasattr(msg, "pose") and hasattr(msg.pose, "position"):
        p, q = msg.pose.position, msg.pose.orientation
        out["position"], out["orientation"] = [p.x, p.y, p.z], [q.w, q.x, q.y, q.z]
    if hasattr(msg, "transforms"):
        out["frames"] = sorted(f"{t.header.frame_id}>{t.child_frame_id}" for t in msg.transforms)
    if hasattr(msg, "returns"):
        out["returns"] = len(msg.returns)
    if isinstance(getattr(msg, "status", None), list):  # DiagnosticArray (NavSatFix has one status)
        out["statuses"] = [s.name for s in msg.status]
    if hasattr(msg, "clock"):
        out["clock"] = [msg.clock.sec, msg.clock.nanosec]
    return out


def main(argv: list[str]) -> int:
    seconds = float(argv[0])
    topics = [a.split("=", 1) for a in argv[1:] if not a.startswith(("call:", "say:"))]
    services = [a[len("call:") :] for a in argv[1:] if a.startswith("call:")]
    sayings = [a[len("say:") :].split("=", 1) for a in argv[1:] if a.startswith("say:")]
    rclpy.init()
    node = rclpy.create_node("listen_ros2")
    got: dict[str, dict] = {}
    tf_frames: dict[str, set[str]] = {}
    for type_name, topic in topics:
        durability = DurabilityPolicy.TRANSIENT_LOCAL if topic == "/tf_static" else DurabilityPolicy.VOLATILE
        qos = QoSProfile(depth=10, reliability=ReliabilityPolicy.BEST_EFFORT, durability=durability)
        if topic == "/tf_static" or topic.endswith("@reliable"):
            qos.reliability = ReliabilityPolicy.RELIABLE

        def on_message(msg: object, topic: str = topic) -> None:
            if topic in ("/tf", "/tf_static"):
                frames = tf_frames.setdefault(topic, set())
                frames.update(summary(msg)["frames"])
                got[topic] = {"type": "TFMessage", "frames": sorted(frames)}
            elif topic not in got:
                got[topic] = summary(msg)

        node.create_subscription(message_type(type_name), topic.removesuffix("@reliable"), on_message, qos)
    deadline = time.monotonic() + seconds
    if sayings:
        from std_msgs.msg import String

        for topic, text in sayings:
            publisher = node.create_publisher(String, topic, 10)
            while publisher.get_subscription_count() == 0 and time.monotonic() < deadline:
                rclpy.spin_once(node, timeout_sec=0.1)
            time.sleep(0.5)  # matched on this side; give the other side a moment to match too
            publisher.publish(String(data=text))
    while time.monotonic() < deadline and len(got) < len(topics):
        rclpy.spin_once(node, timeout_sec=0.1)
    for _ in range(20):  # a little more /tf, for the frames of every robot
        rclpy.spin_once(node, timeout_sec=0.05)
    answers = {}
    if services:
        from std_srvs.srv import Trigger

        for name in services:
            client = node.create_client(Trigger, name)
            if not client.wait_for_service(timeout_sec=max(1.0, deadline - time.monotonic())):
                answers[name] = None
                continue
            future = client.call_async(Trigger.Request())
            rclpy.spin_until_future_complete(node, future, timeout_sec=30.0)
            result = future.result()
            answers[name] = None if result is None else {"success": result.success, "message": result.message}
    print(json.dumps({"topics": got, "services": answers}), flush=True)
    node.destroy_node()
    rclpy.shutdown()
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
