"""A good ROS citizen (issue #19): the node started without a scene, then a scene loaded over ROS, once per
request whatever the publisher latches."""

from __future__ import annotations

import time

from bridgeharness import wait_topic
from harness import Child, wait_until

SENSORS, TWO = "scene_drone_sensors.jsonc", "scene_two_drones.jsonc"


def subscribed(topic: str) -> bool:
    import rosgraph

    _pubs, subs, _srvs = rosgraph.Master("/probe").getSystemState()
    return any(name == topic for name, _nodes in subs)


def loads(node: Child, scene_file: str) -> int:
    """How many times the node loaded `scene_file` (its log line per load)."""
    return node.output().count(f"({scene_file}) loaded")


def rostopic_pub(rig, topic: str, scene_file: str, *flags: str) -> Child:
    return rig.launcher.start(
        "rostopic_pub", ["rostopic", "pub", *flags, topic, "std_msgs/String", f"data: '{scene_file}'"]
    )


def test_start_without_a_scene_then_load_one_once_per_request(rig_factory):
    rig = rig_factory()
    node = rig.start_node(node_name="waiting_bridge")
    topic = "/ProjectAirSim/node/waiting_bridge/load_scene"
    waiting = f"no --scene: waiting for a scene file name on {topic}"
    wait_until(lambda: node.check_alive() is None and waiting in node.output(), 60, what="the node to wait")
    assert subscribed(topic)

    # The documented flow with `rostopic pub -1` (latched, stays 3 s, leaves): one load.
    rostopic_pub(rig, topic, SENSORS, "-1")
    wait_topic("/airsim_node/Drone1/DownCamera/scene_camera/image", node)
    time.sleep(5)
    assert loads(node, SENSORS) == 1
    assert subscribed(topic)

    # A plain `rostopic pub` latches its message and stays: 10 s of it, still one load.
    publisher = rostopic_pub(rig, topic, TWO)
    wait_topic("/airsim_node/Drone2/actual_pose", node)
    time.sleep(10)
    assert loads(node, TWO) == 1
    publisher.stop()

    # The same scene name published again on purpose is a new request: it reloads.
    rostopic_pub(rig, topic, TWO, "-1")
    wait_until(lambda: loads(node, TWO) == 2, 30, what="the deliberate second load")
    time.sleep(4)
    assert loads(node, TWO) == 2
    assert node.alive()
    node.stop()
