"""How rclpy takes a large `data` field, and the 1080p latency between two processes (docs/ros2.md).

Run in .venv-ros2 from the repository root: `.venv-ros2/bin/python -m tools.ros2_measure`. It prints, for a
6 MB buffer given as bytes, memoryview, array.array('B') and a numpy uint8 array, what assigning it to
`Image.data` and `PointCloud2.data` costs and whether the message keeps the caller's object; rclpy's
serialisation of a 1080p Image both ways; what `publish()` costs with a subscriber in another process; and
the publish-to-receive latency of 1080p rgb8 images at 30 Hz from this process to that one over Fast DDS
(localhost discovery, domain from ROS_DOMAIN_ID, default 77). Nothing here is part of the package.
"""

from __future__ import annotations

import argparse
import array
import json
import os
import statistics
import subprocess
import sys
import time
from collections.abc import Callable

import numpy as np
import rclpy
from rclpy.qos import QoSProfile, ReliabilityPolicy
from rclpy.serialization import deserialize_message, serialize_message
from sensor_msgs.msg import Image, PointCloud2

SIZE = 1920 * 1080 * 3  # a 1080p rgb8 frame, 6 220 800 bytes
TOPIC = "ros2_measure/image"
QOS = QoSProfile(depth=5, reliability=ReliabilityPolicy.RELIABLE)


def sources() -> dict[str, Callable[[], object]]:
    """Fresh 6 MB buffers, one maker per kind."""
    raw = os.urandom(SIZE)
    return {
        "bytes": lambda: bytes(raw),
        "memoryview": lambda: memoryview(raw),
        "array.array": lambda: array.array("B", raw),
        "numpy": lambda: np.frombuffer(raw, np.uint8).copy(),
    }


def median_ms(action: Callable[[], object], runs: int) -> float:
    times = []
    for _ in range(runs):
        start = time.perf_counter()
        action()
        times.append((time.perf_counter() - start) * 1e3)
    return statistics.median(times)


def assignment(runs: int) -> list[dict]:
    """The cost of `msg.data = buffer` and whether the message holds the caller's object."""
    rows = []
    for cls in (Image, PointCloud2):
        for kind, make in sources().items():
            buffer = make()
            msg = cls()
            runs_here = 3 if kind in ("memoryview", "numpy") else runs  # the slow paths: fewer runs
            cost = median_ms(lambda msg=msg, buffer=buffer: setattr(msg, "data", buffer), runs_here)
            rows.append(
                {
                    "message": cls.__name__,
                    "given": kind,
                    "assign_ms": round(cost, 3),
                    "stored_as": type(msg.data).__name__,
                    "kept_callers_object": msg.data is buffer,
                }
            )
    return rows


def serialisation(runs: int) -> dict:
    """rclpy's own CDR round trip of a 1080p Image: what publish() and a subscriber's take pay in Python."""
    msg = Image(
        height=1080, width=1920, encoding="rgb8", step=1920 * 3, data=array.array("B", os.urandom(SIZE))
    )
    wire = serialize_message(msg)
    return {
        "serialize_ms": round(median_ms(lambda: serialize_message(msg), runs), 3),
        "deserialize_ms": round(median_ms(lambda: deserialize_message(wire, Image), runs), 3),
        "cdr_bytes": len(wire),
    }


def wait_for_subscriber(node, pub, timeout: float = 20.0) -> None:
    end = time.monotonic() + timeout
    while pub.get_subscription_count() == 0:
        if time.monotonic() > end:
            raise SystemExit("no subscriber matched")
        rclpy.spin_once(node, timeout_sec=0.05)


def publishing(node, pub, runs: int) -> list[dict]:
    """publish() of a 1080p Image whose data was given as each kind (assigned once, outside the timing)."""
    rows = []
    for kind, make in sources().items():
        msg = Image(height=1080, width=1920, encoding="rgb8", step=1920 * 3)
        buffer = make()
        msg.data = buffer if kind in ("bytes", "array.array") else array.array("B", memoryview(buffer))
        times = []
        for _ in range(runs):
            start = time.perf_counter()
            pub.publish(msg)
            times.append((time.perf_counter() - start) * 1e3)
            time.sleep(0.03)  # the subscriber keeps up: each publish() meets an idle reader
        cost = statistics.median(times)
        rows.append({"given": kind, "publish_ms": round(cost, 3)})
    return rows


def latency(node, pub, frames: int, rate: float) -> None:
    """1080p frames at `rate`, each stamped with the wall clock just before publish()."""
    raw = array.array("B", os.urandom(SIZE))
    msg = Image(height=1080, width=1920, encoding="rgb8", step=1920 * 3, data=raw)
    for i in range(frames):
        now = time.time_ns()
        msg.header.stamp.sec, msg.header.stamp.nanosec = divmod(now, 1_000_000_000)
        msg.header.frame_id = str(i)
        pub.publish(msg)
        time.sleep(1.0 / rate)
    msg.header.frame_id = "end"
    for _ in range(20):
        pub.publish(msg)
        time.sleep(0.05)


def receive() -> int:
    """The subscriber process: latencies of every frame until 'end', then one JSON line."""
    rclpy.init()
    node = rclpy.create_node("ros2_measure_sub")
    lat: list[float] = []
    done = []

    def on_image(msg: Image) -> None:
        if msg.header.frame_id == "end":
            done.append(True)
            return
        sent = msg.header.stamp.sec * 1_000_000_000 + msg.header.stamp.nanosec
        if sent:
            lat.append((time.time_ns() - sent) / 1e6)

    node.create_subscription(Image, TOPIC, on_image, QOS)
    end = time.monotonic() + 300
    while not done and time.monotonic() < end:
        rclpy.spin_once(node, timeout_sec=0.1)
    print(json.dumps(lat))
    rclpy.shutdown()
    return 0


def percentile(values: list[float], q: float) -> float:
    ordered = sorted(values)
    return ordered[min(len(ordered) - 1, int(q * len(ordered)))]


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--receive", action="store_true", help=argparse.SUPPRESS)
    parser.add_argument("--runs", type=int, default=20)
    parser.add_argument("--frames", type=int, default=300)
    parser.add_argument("--rate", type=float, default=30.0)
    args = parser.parse_args(argv)
    if args.receive:
        return receive()
    env = {**os.environ, "ROS_AUTOMATIC_DISCOVERY_RANGE": "LOCALHOST"}
    env.setdefault("ROS_DOMAIN_ID", "77")
    os.environ.update(env)
    print(json.dumps({"assignment": assignment(args.runs)}, indent=1))
    print(json.dumps({"serialisation_1080p": serialisation(args.runs)}, indent=1))
    receiver = [sys.executable, "-m", "tools.ros2_measure", "--receive"]
    sub = subprocess.Popen(receiver, env=env, stdout=subprocess.PIPE)
    rclpy.init()
    node = rclpy.create_node("ros2_measure_pub")
    pub = node.create_publisher(Image, TOPIC, QOS)
    try:
        wait_for_subscriber(node, pub)
        print(json.dumps({"publish": publishing(node, pub, args.runs)}, indent=1))
        latency(node, pub, args.frames, args.rate)
        out, _ = sub.communicate(timeout=120)
    finally:
        if sub.poll() is None:
            sub.kill()
        rclpy.shutdown()
    lat = json.loads(out)
    summary = {
        "frames_sent": args.frames,
        "frames_received": len(lat),
        "rate_hz": args.rate,
        "median_ms": round(statistics.median(lat), 2),
        "p99_ms": round(percentile(lat, 0.99), 2),
        "max_ms": round(max(lat), 2),
    }
    print(json.dumps({"latency_1080p": summary}, indent=1))
    return 0


if __name__ == "__main__":
    sys.exit(main())
