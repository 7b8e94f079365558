"""An rclpy watcher that keeps running, run by .venv-ros2's Python beside a ROS 2 bridge node; it prints what
it sees as it sees it, one line each, until it is stopped.

`watch_ros2.py ITEM...`, each ITEM one of:
  TYPE=TOPIC       subscribe (best-effort; reliable and transient-local for /tf_static); print
                   "MSG <topic> <wall time>" at most every THROTTLE_S per topic, and for /tf and
                   /tf_static "TF <topic> <json list of parent>child>" for each message with new frames
  status:TOPIC     print "STATUS <json>" for every message of the node's status topic (std_msgs/String)
  graph:NODE       print "GRAPH <json {topic: [types]}>" of what the node (a full name, /ns/name) publishes,
                   whenever that changes
It prints "READY" once its subscriptions are made.
"""

from __future__ import annotations

import importlib
import json
import signal
import sys
import time

import rclpy
from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy

THROTTLE_S = 0.02
GRAPH_PERIOD_S = 0.2


def message_type(name: str) -> type:
    package, _, kind = name.partition("/")
    return getattr(importlib.import_module(f"{package}.msg"), kind)


def say(line: str) -> None:
    print(line, flush=True)


def watch_topic(node: object, type_name: str, topic: str) -> None:
    static = topic == "/tf_static"
    qos = QoSProfile(
        depth=10,
        reliability=ReliabilityPolicy.RELIABLE if static else ReliabilityPolicy.BEST_EFFORT,
        durability=DurabilityPolicy.TRANSIENT_LOCAL if static else DurabilityPolicy.VOLATILE,
    )
    last = [0.0]
    frames_seen: list[list[str]] = [[]]

    def on_message(msg: object) -> None:
        now = time.time()
        if hasattr(msg, "transforms"):
            frames = sorted(f"{t.header.frame_id}>{t.child_frame_id}" for t in msg.transforms)
            if frames != frames_seen[0]:
                frames_seen[0] = frames
                say(f"TF {topic} {json.dumps(frames)}")
        if now - last[0] >= THROTTLE_S:
            last[0] = now
            say(f"MSG {topic} {now:.4f}")

    node.create_subscription(message_type(type_name), topic, on_message, qos)


def main(items: list[str]) -> int:
    signal.signal(signal.SIGTERM, lambda *_: sys.exit(0))
    rclpy.init()
    node = rclpy.create_node("watch_ros2")
    graphs: list[str] = []
    for item in items:
        if item.startswith("status:"):
            from std_msgs.msg import String

            qos = QoSProfile(depth=5, durability=DurabilityPolicy.TRANSIENT_LOCAL)
            node.create_subscription(String, item[len("status:") :], lambda m: say(f"STATUS {m.data}"), qos)
        elif item.startswith("graph:"):
            graphs.append(item[len("graph:") :])
        else:
            type_name, topic = item.split("=", 1)
            watch_topic(node, type_name, topic)
    say("READY")
    shown: dict[str, str] = {}
    next_graph = 0.0
    try:
        while rclpy.ok():
            rclpy.spin_once(node, timeout_sec=0.05)
            if graphs and time.monotonic() >= next_graph:
                next_graph = time.monotonic() + GRAPH_PERIOD_S
                for full_name in graphs:
                    namespace, _, name = full_name.rpartition("/")
                    try:
                        published = node.get_publisher_names_and_types_by_node(name, namespace or "/")
                    except Exception:  # the node is not (or no longer) in the graph
                        published = []
                    text = json.dumps({topic: sorted(types) for topic, types in sorted(published)})
                    if shown.get(full_name) != text:
                        shown[full_name] = text
                        say(f"GRAPH {text}")
    except (KeyboardInterrupt, SystemExit):
        pass
    finally:
        node.destroy_node()
        rclpy.try_shutdown()
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
