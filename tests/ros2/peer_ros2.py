"""One rclpy peer, run by .venv-ros2's Python: `pub KIND` publishes a known message of a kind until its
subscriber has come and gone, `sub KIND` waits for one message, compares it with the same known message and
prints one JSON line. `fields` prints the generated types' field lists.

The kinds: `tf` (tf2_msgs/TFMessage), `radar` (radar_msgs/RadarScan), `image` (a 1080p rgb8
sensor_msgs/Image). Both sides build the message with `sample` (its float32 fields hold values that
float32 represents exactly), so equality means every field arrived.
"""

from __future__ import annotations

import json
import sys
import time

import rclpy
from geometry_msgs.msg import TransformStamped
from radar_msgs.msg import RadarReturn, RadarScan
from rclpy.qos import QoSProfile, ReliabilityPolicy
from sensor_msgs.msg import Image
from tf2_msgs.msg import TFMessage

TIMEOUT = 30.0


def sample(kind: str):
    """The known message of a kind."""
    if kind == "tf":
        msg = TFMessage()
        for i, child in enumerate(("drone_1", "drone_1/front_center")):
            t = TransformStamped()
            t.header.stamp.sec, t.header.stamp.nanosec = 12, 345_000_000 + i
            t.header.frame_id, t.child_frame_id = "map", child
            t.transform.translation.x, t.transform.translation.z = 1.5 + i, -2.0
            t.transform.rotation.w = 1.0
            msg.transforms.append(t)
        return msg
    if kind == "radar":
        msg = RadarScan()
        msg.header.frame_id = "drone_1/radar"
        msg.header.stamp.sec = 7
        msg.returns = [RadarReturn(range=10.0 + i, azimuth=0.25 * i, elevation=-0.0625, doppler_velocity=2.5,
                                   amplitude=30.0) for i in range(5)]  # fmt: skip
        return msg
    if kind == "image":
        height, width = 1080, 1920
        row = bytes(range(256)) * (width * 3 // 256) + bytes(width * 3 % 256)
        msg = Image(height=height, width=width, encoding="rgb8", is_bigendian=0, step=width * 3)
        msg.header.frame_id = "drone_1/front_center/scene_camera"
        msg.data = row * height
        return msg
    raise SystemExit(f"unknown kind {kind}")


TYPES = {"tf": TFMessage, "radar": RadarScan, "image": Image}
QOS = QoSProfile(depth=1, reliability=ReliabilityPolicy.RELIABLE)


def publish(kind: str) -> int:
    node = rclpy.create_node(f"peer_pub_{kind}")
    pub = node.create_publisher(TYPES[kind], f"peer/{kind}", QOS)
    msg = sample(kind)
    matched, end = False, time.monotonic() + TIMEOUT
    while time.monotonic() < end:
        count = pub.get_subscription_count()
        if count:
            matched = True
            pub.publish(msg)
        elif matched:
            return 0
        rclpy.spin_once(node, timeout_sec=0.1)
    print(f"publisher: {'subscriber never left' if matched else 'no subscriber'}", file=sys.stderr)
    return 1


def subscribe(kind: str) -> int:
    node = rclpy.create_node(f"peer_sub_{kind}")
    got: list = []
    node.create_subscription(TYPES[kind], f"peer/{kind}", got.append, QOS)
    end = time.monotonic() + TIMEOUT
    while not got and time.monotonic() < end:
        rclpy.spin_once(node, timeout_sec=0.1)
    if not got:
        print("subscriber: nothing received", file=sys.stderr)
        return 1
    msg = got[0]
    size = len(msg.data) if kind == "image" else len(msg.transforms if kind == "tf" else msg.returns)
    print(json.dumps({"kind": kind, "type": type(msg).__name__, "equal": msg == sample(kind), "size": size}))
    return 0


def fields() -> int:
    from radar_msgs.msg import RadarTrack, RadarTracks

    classes = (TFMessage, RadarReturn, RadarScan, RadarTrack, RadarTracks)
    out = {f"{c.__module__.split('.')[0]}/{c.__name__}": c.get_fields_and_field_types() for c in classes}
    print(json.dumps(out))
    return 0


def main(argv: list[str]) -> int:
    if argv[0] == "fields":
        return fields()
    rclpy.init()
    try:
        return (publish if argv[0] == "pub" else subscribe)(argv[1])
    finally:
        rclpy.try_shutdown()


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
