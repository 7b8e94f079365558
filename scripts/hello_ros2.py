#!/usr/bin/env python3
"""hello_ros2: hello_ros.py on ROS 2, a mission script and the bridge sharing one Project AirSim client.

Run with `.venv-ros2/bin/python scripts/hello_ros2.py` (ROS 2 arguments after `--ros-args`, e.g. `-r
__ns:=/sim1`). Loads the sensors scene, runs the bridge in this script's rclpy node on the same client (the
wrapper spins the node on a thread of its own), and flies Drone1 from the launch pad to the orange ball and
back, over and over, until Ctrl-C, SIGTERM (or --seconds). The mission runs as an asyncio task; the signals
only set a flag that the main loop watches between awaits, then everything stops in order: the drone hovers,
the bridge stops, the client disconnects, the node is destroyed and rclpy shut down.
"""

from __future__ import annotations

import argparse
import asyncio
import signal
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))  # run from a checkout without install

from hello_ros import log, mission, parse_args, quiet_closed_contexts, stop_mission  # noqa: E402

NODE_NAME = "projectairsim"


async def main(client, bridge, drone, hover_method: str, args: argparse.Namespace) -> None:
    """Run the mission until SIGINT/SIGTERM or --seconds pass; then stop everything."""
    target = tuple(float(v) for v in args.target.split())
    stop = asyncio.Event()
    loop = asyncio.get_running_loop()
    for sig in (signal.SIGINT, signal.SIGTERM):  # Ctrl-C ends the mission and the bridge together
        loop.add_signal_handler(sig, stop.set)
    task = asyncio.create_task(mission(drone, target, args.speed, stop.is_set))
    deadline = time.monotonic() + args.seconds if args.seconds > 0 else None
    while not stop.is_set() and not task.done():
        if deadline is not None and time.monotonic() > deadline:
            stop.set()
            break
        await asyncio.sleep(0.2)  # yield to the mission between checks
    log.info("stopping the mission")
    stop.set()
    await stop_mission(client, bridge, task, hover_method)


def run(argv: list[str]) -> int:
    import rclpy
    from projectairsim import Drone, ProjectAirSimClient, World
    from rclpy.signals import SignalHandlerOptions
    from rclpy.utilities import remove_ros_args

    from airsim_mapper.common.dds_profile import use_shipped_profile
    from airsim_mapper.wrapper import ProjectAirSimWrapper, redirect_client_log

    args = parse_args(remove_ros_args(argv)[1:])
    profile = use_shipped_profile()  # Fast DDS's shared memory fits 1080p frames, unless the user chose
    rclpy.init(args=argv, signal_handler_options=SignalHandlerOptions.NO)  # the script stops itself
    node = rclpy.create_node(args.nodename or NODE_NAME)
    try:
        redirect_client_log(node)  # the client's log, the bridge's and this script's on the node's logger
        log.info(profile)
        quiet_closed_contexts()
        client = ProjectAirSimClient(args.address, args.topicsport, args.servicesport)
        client.connect()
        try:
            world = World(client, args.scene, sim_config_path=args.simconfigpath.rstrip("/") + "/")
            bridge = ProjectAirSimWrapper(
                client, node=node, sim_config_path=args.simconfigpath, mapping=args.mapping, tune_process=True
            )
            bridge.update_topics(world)
            drone = Drone(client, world, args.robot)
        except BaseException:
            client.disconnect()
            raise
        asyncio.run(main(client, bridge, drone, f"{world.parent_topic}/robots/{args.robot}/Hover", args))
    finally:
        node.destroy_node()
        rclpy.try_shutdown()
    return 0


if __name__ == "__main__":
    sys.exit(run(sys.argv))
