"""Run in .venv-ros2: rclpy's own verdict on names (read as JSON from stdin) and its QoS profiles, as JSON.

For each name: whether rclpy takes it as a topic name as written, whether its expansion for the node
`node` in `/ns` is a full name rclpy takes, and whether it is a valid node name and namespace.
"""

from __future__ import annotations

import json
import sys

import rclpy.qos
from rclpy.exceptions import InvalidNamespaceException, InvalidNodeNameException, InvalidTopicNameException
from rclpy.expand_topic_name import expand_topic_name
from rclpy.validate_full_topic_name import validate_full_topic_name
from rclpy.validate_namespace import validate_namespace
from rclpy.validate_node_name import validate_node_name
from rclpy.validate_topic_name import validate_topic_name

INVALID = (InvalidNamespaceException, InvalidNodeNameException, InvalidTopicNameException)


def takes(check, *args) -> bool:
    try:
        check(*args)
    except INVALID:
        return False
    return True


def expands(name: str) -> bool:
    """rcl expands `name` (it refuses an unknown substitution) to a full name it takes."""
    try:
        full = expand_topic_name(name, "node", "/ns")
    except ValueError:
        return False
    return takes(validate_full_topic_name, full)


def verdict(name: str) -> dict[str, bool]:
    topic = takes(validate_topic_name, name)
    full = topic and expands(name)
    return {
        "topic": topic,
        "full": full,
        "node": takes(validate_node_name, name),
        "namespace": takes(validate_namespace, name),
    }


def profile(qos) -> list:
    return [qos.reliability.name.lower(), qos.durability.name.lower(), qos.depth, qos.history.name.lower()]


def main() -> int:
    names = json.load(sys.stdin)
    profiles = {
        "sensor_data": profile(rclpy.qos.qos_profile_sensor_data),
        "default": profile(rclpy.qos.qos_profile_default),
        "services": profile(rclpy.qos.qos_profile_services_default),
    }
    json.dump({"names": {name: verdict(name) for name in names}, "profiles": profiles}, sys.stdout)
    return 0


if __name__ == "__main__":
    sys.exit(main())
