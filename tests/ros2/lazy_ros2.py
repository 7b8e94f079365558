"""Lazy streams on ROS 2, seen from outside: `lazy_ros2.py STATUS_TOPIC IMAGE_TOPIC SIM_SUFFIX [CYCLES]` (run
by .venv-ros2's Python) reads the node's status (std_msgs/String of JSON) while an image subscriber comes and
goes CYCLES times (1 unless told), then while two subscribers come and one of them leaves, and prints one
JSON line saying whether the simulator stream whose name ends with SIM_SUFFIX was subscribed at each step
and how many images arrived."""

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


def main(status_topic: str, image_topic: str, suffix: str, cycles: int = 1) -> int:
    rclpy.init()
    node = rclpy.create_node("lazy_ros2")
    latest: dict = {}

    def on_status(msg: String) -> None:
        latest["streams"] = list(json.loads(msg.data).get("streams", {}))

    status_qos = QoSProfile(depth=1, durability=DurabilityPolicy.TRANSIENT_LOCAL)
    node.create_subscription(String, status_topic, on_status, status_qos)
    image_qos = QoSProfile(depth=5, reliability=ReliabilityPolicy.BEST_EFFORT)

    def streaming() -> bool:
        return any(name.endswith(suffix) for name in latest.get("streams", []))

    def spin_for(seconds: float, until=lambda: False) -> None:
        deadline = time.monotonic() + seconds
        while time.monotonic() < deadline and not until():
            rclpy.spin_once(node, timeout_sec=0.1)

    def subscribe(images: list[int]) -> object:
        return node.create_subscription(Image, image_topic, lambda _m: images.append(1), image_qos)

    def stopped() -> bool:
        """The stream went and stays gone for a while."""
        spin_for(SETTLE_S * 2, lambda: not streaming())
        spin_for(SETTLE_S / 2)  # two more statuses
        return not streaming()

    spin_for(WAIT_S, lambda: "streams" in latest)
    spin_for(SETTLE_S)
    seen: dict = {"before": streaming(), "cycles": []}
    for _ in range(cycles):
        images: list[int] = []
        subscription = subscribe(images)
        spin_for(WAIT_S, lambda images=images: bool(images))
        spin_for(SETTLE_S, streaming)
        during = streaming()
        node.destroy_subscription(subscription)
        seen["cycles"].append({"images": len(images), "during": during, "after": not stopped()})
    first, second = [], []
    one, other = subscribe(first), subscribe(second)
    spin_for(WAIT_S, lambda: bool(first) and bool(second))
    spin_for(SETTLE_S, streaming)
    both = streaming()
    node.destroy_subscription(one)
    left = len(second)
    spin_for(SETTLE_S)  # the first one's leaving has been seen by now
    spin_for(WAIT_S, lambda: len(second) > left + 3)
    seen["two"] = {
        "images": [len(first), left],
        "both": both,
        "one_left": streaming(),
        "images_after_one_left": len(second) - left,
    }
    node.destroy_subscription(other)
    seen["two"]["after"] = not stopped()
    print(json.dumps(seen), flush=True)
    node.destroy_node()
    rclpy.shutdown()
    return 0


if __name__ == "__main__":
    sys.exit(main(*sys.argv[1:4], *(int(a) for a in sys.argv[4:5])))
