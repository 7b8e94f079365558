"""Lazy streams on ROS 2, seen from outside: `lazy_ros2.py STATUS_TOPIC IMAGE_TOPIC SIM_SUFFIX` (run by
.venv-ros2's Python) reads the node's status (std_msgs/String of JSON) before, while and after it subscribes
to an image topic, and prints one JSON line saying whether the simulator stream whose name ends with
SIM_SUFFIX was subscribed at each step."""

from __future__ import annotations

import json
import sys
import time

import rclpy
from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy
from sensor_msgs.msg import Image
from std_msgs.msg import String

WAIT_S = 30.0
SETTLE_S = 4.0  # the node's status comes once a second


def main(status_topic: str, image_topic: str, suffix: str) -> int:
    rclpy.init()
    node = rclpy.create_node("lazy_ros2")
    latest: dict = {}
    images: list[int] = []

    def on_status(msg: String) -> None:
        latest["streams"] = list(json.loads(msg.data).get("streams", {}))

    status_qos = QoSProfile(depth=1, durability=DurabilityPolicy.TRANSIENT_LOCAL)
    node.create_subscription(String, status_topic, on_status, status_qos)

    def streaming() -> bool:
        return any(name.endswith(suffix) for name in latest.get("streams", []))

    def spin_for(seconds: float, until=lambda: False) -> None:
        deadline = time.monotonic() + seconds
        while time.monotonic() < deadline and not until():
            rclpy.spin_once(node, timeout_sec=0.1)

    spin_for(WAIT_S, lambda: "streams" in latest)
    spin_for(SETTLE_S)
    before = streaming()
    image_qos = QoSProfile(depth=5, reliability=ReliabilityPolicy.BEST_EFFORT)
    subscription = node.create_subscription(Image, image_topic, lambda _m: images.append(1), image_qos)
    spin_for(WAIT_S, lambda: bool(images))
    spin_for(SETTLE_S, streaming)
    during = streaming()
    node.destroy_subscription(subscription)
    spin_for(SETTLE_S * 2, lambda: not streaming())
    spin_for(SETTLE_S)
    after = streaming()
    print(json.dumps({"before": before, "images": len(images), "during": during, "after": after}), flush=True)
    node.destroy_node()
    rclpy.shutdown()
    return 0


if __name__ == "__main__":
    sys.exit(main(*sys.argv[1:4]))
