"""An rclpy recorder, run by .venv-ros2's Python: every message of some topics, for a while.

`record_ros2.py SECONDS TYPE=TOPIC ... [until:TEXT]` subscribes to each topic (best-effort; /rosout reliable
and transient-local, as rclpy publishes it), prints "ready" once subscribed, and records each message with
its arrival (wall clock, ns) until SECONDS passed or a /rosout record whose text contains TEXT arrived (a
second more is recorded after it). It prints one JSON line: per topic a list of records.
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


def record(msg: object) -> dict:
    """The fields a test checks, of whichever message it is, and its arrival."""
    out: dict = {"arrived_ns": time.time_ns()}
    header = getattr(msg, "header", None)
    if header is not None:
        out["stamp_ns"] = header.stamp.sec * 10**9 + header.stamp.nanosec
    if hasattr(msg, "clock"):
        out["clock_ns"] = msg.clock.sec * 10**9 + msg.clock.nanosec
    if hasattr(msg, "level") and hasattr(msg, "msg"):  # rcl_interfaces/Log
        out.update(level=int(msg.level), name=msg.name, text=msg.msg)
        out["stamp_ns"] = msg.stamp.sec * 10**9 + msg.stamp.nanosec
    return out


def main(argv: list[str]) -> int:
    seconds = float(argv[0])
    topics = [a.split("=", 1) for a in argv[1:] if not a.startswith("until:")]
    until = next((a[len("until:") :] for a in argv[1:] if a.startswith("until:")), None)
    rclpy.init()
    node = rclpy.create_node("record_ros2", enable_rosout=False)  # its own records are not the test's
    got: dict[str, list[dict]] = {topic: [] for _kind, topic in topics}
    for type_name, topic in topics:
        qos = QoSProfile(depth=100, reliability=ReliabilityPolicy.BEST_EFFORT)
        if topic == "/rosout":
            reliable, kept = ReliabilityPolicy.RELIABLE, DurabilityPolicy.TRANSIENT_LOCAL
            qos = QoSProfile(depth=1000, reliability=reliable, durability=kept)

        def on_message(msg: object, topic: str = topic) -> None:
            got[topic].append(record(msg))

        node.create_subscription(message_type(type_name), topic, on_message, qos)
    print("ready", flush=True)
    deadline = time.monotonic() + seconds
    while time.monotonic() < deadline:
        rclpy.spin_once(node, timeout_sec=0.1)
        if until is not None and any(until in r.get("text", "") for r in got.get("/rosout", ())):
            deadline = min(deadline, time.monotonic() + 1.0)
            until = None
    print(json.dumps(got), flush=True)
    node.destroy_node()
    rclpy.shutdown()
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
