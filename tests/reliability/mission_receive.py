"""Test node: a mission script that embeds the bridge, in either order, and listens to a topic itself.

Arguments: ORDER (world-first or bridge-first), the simulator's topics and services ports, the sim_config
directory, the scene, the simulator topic the mission subscribes to, the bridge's ROS topic and a run
time. It prints one JSON line: what the mission's own callback received, what the bridge published, and
which function the client's receive thread runs.
"""

from __future__ import annotations

import json
import sys
import threading
import time

import rospy
from projectairsim import ProjectAirSimClient, World

from airsim_mapper.wrapper import ProjectAirSimWrapper


def thread_functions(thread: threading.Thread) -> list[str]:
    """The qualified names of the functions on a running thread's stack, innermost last."""
    frame = sys._current_frames().get(thread.ident)
    names: list[str] = []
    while frame is not None:
        names.append(f"{frame.f_globals.get('__name__')}.{frame.f_code.co_name}")
        frame = frame.f_back
    return names[::-1]


def main(
    order: str,
    topics: int,
    services: int,
    sim_config: str,
    scene: str,
    sim_topic: str,
    ros_topic: str,
    seconds: float,
) -> None:
    rospy.init_node("mission")
    client = ProjectAirSimClient("127.0.0.1", topics, services)
    client.connect()
    config_path = sim_config.rstrip("/") + "/"
    if order == "world-first":
        world = World(client, scene, sim_config_path=config_path, delay_after_load_sec=0)
        bridge = ProjectAirSimWrapper(client, sim_config_path=sim_config)
    else:
        bridge = ProjectAirSimWrapper(client, sim_config_path=sim_config)
        world = World(client, scene, sim_config_path=config_path, delay_after_load_sec=0)
    bridge.update_topics(world)
    mission: list[tuple[float, object]] = []
    client.subscribe(sim_topic, lambda _topic, message: mission.append((time.monotonic(), message)))
    published: list[float] = []
    rospy.Subscriber(ros_topic, rospy.AnyMsg, lambda _msg: published.append(time.monotonic()))
    time.sleep(seconds)
    recent = time.monotonic() - 1.0
    result = {
        "mission_messages": len(mission),
        "mission_last_second": sum(1 for t, _ in mission if t > recent),
        "mission_messages_seen": [message for _, message in mission[:40]],
        "published": len(published),
        "published_last_second": sum(1 for t in published if t > recent),
        "bad_frames": bridge.engine.sim.bad_frames,
        "receive_stack": thread_functions(client.recv_topic_thread),
        "receive_thread": client.recv_topic_thread.name,
    }
    print("RESULT " + json.dumps(result, default=repr), flush=True)
    rospy.signal_shutdown("done")
    client.disconnect()


if __name__ == "__main__":
    argv = rospy.myargv(sys.argv)[1:]
    main(argv[0], int(argv[1]), int(argv[2]), argv[3], argv[4], argv[5], argv[6], float(argv[7]))
