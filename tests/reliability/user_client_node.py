"""Test node: a mission script that owns its client and embeds the bridge (ProjectAirSimWrapper)."""

from __future__ import annotations

import sys

import rospy
from projectairsim import ProjectAirSimClient, World

from airsim_mapper.wrapper import ProjectAirSimWrapper


def main(topics_port: int, services_port: int, sim_config: str, scene: str) -> None:
    rospy.init_node("owner")
    client = ProjectAirSimClient("127.0.0.1", topics_port, services_port)
    client.connect()
    world = World(client, scene, sim_config_path=sim_config.rstrip("/") + "/")
    bridge = ProjectAirSimWrapper(client, sim_config_path=sim_config)
    bridge.update_topics(world)
    rospy.on_shutdown(client.disconnect)  # the owner closes its client (after the bridge's own hook)
    print("BRIDGED", flush=True)
    rospy.spin()


if __name__ == "__main__":
    args = rospy.myargv(sys.argv)[1:]
    main(int(args[0]), int(args[1]), args[2], args[3])
