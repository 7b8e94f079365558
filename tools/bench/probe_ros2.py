"""The probe on ROS 2: an rclpy subscriber process that measures delivered rate and latency (receive time -
header stamp), the twin of probe.py, run by .venv-ros2's Python.

Messages are taken serialised (`raw=True`, no deserialisation: the probe costs as little as possible); the
stamp is read from the CDR bytes (a 4-byte encapsulation header, then the header's `sec` int32 and `nanosec`
uint32), so every stamped type works. Each topic is subscribed with the QoS the bridge offers it: poses
reliable, images `sensor_data` (best effort, depth 5). Poses keep a history deep enough that a probe that
fell behind counts every one. Its output, window and JSON result are probe.py's.

    python -m tools.bench.probe_ros2 --out result.json [--warmup S] [--duration S] [--malloc glibc] TOPIC...
"""

from __future__ import annotations

import struct
import threading
import time
from typing import Any

from tools.bench.probe import (
    TopicRecord,
    measure,
    parse_arguments,
)
from tools.bench.results import kind

STAMP = {0: struct.Struct(">iI"), 1: struct.Struct("<iI")}  # by the encapsulation's second byte: BE, LE
POSE_DEPTH = 100


def stamp_s(data: bytes) -> float:
    """The header stamp of a CDR-serialised stamped message, in seconds."""
    sec, nanosec = STAMP[data[1] & 1].unpack_from(data, 4)
    return sec + nanosec * 1e-9


def qos_for(topic: str) -> Any:
    """The QoS the bridge offers `topic`: reliable for a pose, sensor_data for the rest."""
    from rclpy.qos import QoSProfile, ReliabilityPolicy, qos_profile_sensor_data

    if kind(topic) == "pose":
        return QoSProfile(depth=POSE_DEPTH, reliability=ReliabilityPolicy.RELIABLE)
    return qos_profile_sensor_data


def message_class(topic: str) -> type:
    from geometry_msgs.msg import PoseStamped
    from sensor_msgs.msg import Image

    return PoseStamped if kind(topic) == "pose" else Image


def main(argv: list[str] | None = None) -> int:
    import rclpy
    from rclpy.executors import SingleThreadedExecutor
    from rclpy.signals import SignalHandlerOptions

    args, malloc = parse_arguments(argv)
    rclpy.init(signal_handler_options=SignalHandlerOptions.NO)
    node = rclpy.create_node("bench_probe")
    records = {topic: TopicRecord() for topic in args.topics}
    lock = threading.Lock()
    state = {"recording": False}

    def callback(data: bytes, topic: str) -> None:
        now = time.time()
        with lock:
            record = records[topic]
            record.seen += 1
            if state["recording"]:
                record.latencies_ms.append((now - stamp_s(data)) * 1e3)
                record.bytes += len(data)

    for topic in args.topics:
        node.create_subscription(
            message_class(topic), topic, lambda data, t=topic: callback(data, t), qos_for(topic), raw=True
        )
    executor = SingleThreadedExecutor()
    executor.add_node(node)
    threading.Thread(target=executor.spin, name="probe-executor", daemon=True).start()
    if not measure(args, records, state, lock, malloc):
        return 1
    executor.shutdown(timeout_sec=1.0)
    node.destroy_node()
    rclpy.try_shutdown()
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
