"""A user's rclpy subscriber with nothing configured, run by .venv-ros2's Python: how many images arrive.

`rate_ros2.py TOPIC SECONDS TIMEOUT` subscribes to TOPIC as sensor_msgs/Image with rclpy's
`qos_profile_sensor_data` (best-effort, depth 5) and no Fast DDS profile of its own, waits up to TIMEOUT
seconds for the first image, counts the images of the next SECONDS, and prints one JSON line: the count,
the rate, and the first image's size.
"""

from __future__ import annotations

import json
import sys
import time

import rclpy
from rclpy.qos import qos_profile_sensor_data
from sensor_msgs.msg import Image


def main(topic: str, seconds: float, timeout: float) -> int:
    rclpy.init()
    node = rclpy.create_node("rate_ros2")
    arrivals: list[float] = []
    size: list[int] = []

    def on_image(msg: Image) -> None:
        arrivals.append(time.monotonic())
        if not size:
            size.extend((msg.width, msg.height, len(msg.data)))

    node.create_subscription(Image, topic, on_image, qos_profile_sensor_data)
    deadline = time.monotonic() + timeout
    while not arrivals and time.monotonic() < deadline:
        rclpy.spin_once(node, timeout_sec=0.1)
    start = time.monotonic()
    while arrivals and time.monotonic() < start + seconds:
        rclpy.spin_once(node, timeout_sec=0.1)
    counted = sum(1 for t in arrivals if start <= t < start + seconds)
    print(json.dumps({"first": bool(arrivals), "count": counted, "hz": counted / seconds, "size": size}))
    node.destroy_node()
    rclpy.try_shutdown()
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1], float(sys.argv[2]), float(sys.argv[3])))
