"""Run in .venv-ros2 against a running ROS 2 bridge node: the endpoints of every expanded rule, seen from
another process.

Reads JSON from stdin: `seconds`, `node` (the bridge's full node name), `publishers` (each `topic`,
`type`, `qos` as [reliability, durability, depth, history], and `events`: true for a topic that carries
only events and may stay silent), `subscribers` and `services` (each `name`, `type`). Subscribes to each
published topic with its own QoS and waits until every one but the event topics delivered or `seconds`
passed; then reads the graph (the bridge's publishers and subscribers of each topic with their type,
reliability and durability; its services with their types) and calls each service in `services`, one after
the other, with a default request. Prints one JSON line.
"""

from __future__ import annotations

import importlib
import json
import sys
import time

import rclpy
from listen_ros2 import summary
from rclpy.qos import DurabilityPolicy, HistoryPolicy, QoSProfile, ReliabilityPolicy

CALL_S = 60.0


def ros_class(ros_type: str, kind: str) -> type:
    package, _, name = ros_type.partition("/")
    return getattr(importlib.import_module(f"{package}.{kind}"), name)


def profile(qos: list) -> QoSProfile:
    reliability, durability, depth, history = qos
    return QoSProfile(
        depth=depth,
        history=HistoryPolicy[history.upper()],
        reliability=ReliabilityPolicy[reliability.upper()],
        durability=DurabilityPolicy[durability.upper()],
    )


def endpoints(infos: list, node: str) -> list[dict]:
    """The bridge's endpoints among a topic's: type and the QoS settings discovery carries."""
    return [
        {
            "type": info.topic_type.replace("/msg/", "/"),
            "qos": [info.qos_profile.reliability.name.lower(), info.qos_profile.durability.name.lower()],
        }
        for info in infos
        if f"{info.node_namespace.rstrip('/')}/{info.node_name}" == node
    ]


def response_fields(response: object) -> dict:
    return {name: getattr(response, name) for name in response.get_fields_and_field_types()}


def main() -> int:
    spec = json.load(sys.stdin)
    rclpy.init()
    node = rclpy.create_node("rules_ros2")
    got: dict[str, dict] = {}
    for pub in spec["publishers"]:

        def on_message(msg: object, topic: str = pub["topic"]) -> None:
            got.setdefault(topic, summary(msg))

        node.create_subscription(ros_class(pub["type"], "msg"), pub["topic"], on_message, profile(pub["qos"]))
    wanted = {pub["topic"] for pub in spec["publishers"] if not pub["events"]}
    deadline = time.monotonic() + spec["seconds"]
    while time.monotonic() < deadline and not wanted <= got.keys():
        rclpy.spin_once(node, timeout_sec=0.1)
    bridge = spec["node"]
    namespace, _, name = bridge.rpartition("/")
    graph = {
        "publishers": {
            pub["topic"]: endpoints(node.get_publishers_info_by_topic(pub["topic"]), bridge)
            for pub in spec["publishers"]
        },
        "subscribers": {
            sub["name"]: endpoints(node.get_subscriptions_info_by_topic(sub["name"]), bridge)
            for sub in spec["subscribers"]
        },
        "services": {
            name: [t.replace("/srv/", "/") for t in types]
            for name, types in node.get_service_names_and_types_by_node(name, namespace or "/")
        },
    }
    answers, took = {}, {}
    for service in spec["services"]:
        srv = ros_class(service["type"], "srv")
        client = node.create_client(srv, service["name"])
        answers[service["name"]] = None
        started = time.monotonic()
        if client.wait_for_service(timeout_sec=10.0):
            future = client.call_async(srv.Request())
            rclpy.spin_until_future_complete(node, future, timeout_sec=CALL_S)
            if future.done() and future.result() is not None:
                answers[service["name"]] = response_fields(future.result())
        took[service["name"]] = round(time.monotonic() - started, 2)
    print(json.dumps({"topics": got, "graph": graph, "answers": answers, "took": took}), flush=True)
    node.destroy_node()
    rclpy.shutdown()
    return 0


if __name__ == "__main__":
    sys.exit(main())
