#!/usr/bin/env python3
"""hello_ros: a mission script and the bridge sharing one Project AirSim client.

Loads the sensors scene, runs the bridge in this ROS node on the same client, and flies Drone1 from the
launch pad to the orange ball and back, over and over, until Ctrl-C (or --seconds). The mission runs as
an asyncio task; rospy delivers the bridge's callbacks on its own threads, so the main loop only has to
watch for ROS shutdown between awaits.
"""

from __future__ import annotations

import argparse
import asyncio
import contextlib
import logging
import signal
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))  # run from a checkout without install

log = logging.getLogger("rosout.hello_ros")


def parse_args(argv: list[str]) -> argparse.Namespace:
    parser = argparse.ArgumentParser(
        description="Fly Drone1 to the orange ball and back while bridging to ROS."
    )
    parser.add_argument("--address", default="127.0.0.1")
    parser.add_argument("--nodename", default=None)
    parser.add_argument("--simconfigpath", default=str(ROOT / "sim_config"))
    parser.add_argument("--servicesport", type=int, default=8990)
    parser.add_argument("--topicsport", type=int, default=8989)
    parser.add_argument("--mapping", default="default", help="mapping YAML file or shipped mapping name")
    parser.add_argument("--scene", default="scene_drone_sensors.jsonc")
    parser.add_argument("--robot", default="Drone1")
    parser.add_argument("--target", default="17 17 -4", help="NED point near the orange ball, 'x y z' metres")
    parser.add_argument("--speed", type=float, default=4.0, help="m/s")
    parser.add_argument("--seconds", type=float, default=0.0, help="stop after this long (0: until Ctrl-C)")
    return parser.parse_args(argv)


async def mission(drone, target: tuple[float, float, float], speed: float) -> None:
    """Take off, then shuttle between the launch pad and the ball forever."""
    drone.enable_api_control()
    drone.arm()
    await (await drone.takeoff_async())
    home = (0.0, 0.0, target[2])
    legs = 0
    while True:
        for x, y, z in (target, home):
            log.info("flying to (%.1f, %.1f, %.1f)", x, y, z)
            await (await drone.move_to_position_async(north=x, east=y, down=z, velocity=speed))
            legs += 1
            log.info("reached (%.1f, %.1f, %.1f) [leg %d]", x, y, z, legs)


async def main(client, bridge, drone, hover_method: str, args: argparse.Namespace) -> None:
    """Run the mission until ROS shuts down (Ctrl-C) or --seconds pass; then stop everything."""
    import rospy

    target = tuple(float(v) for v in args.target.split())
    loop = asyncio.get_running_loop()
    for sig in (signal.SIGINT, signal.SIGTERM):  # Ctrl-C ends the mission and ROS together
        loop.add_signal_handler(sig, rospy.signal_shutdown, f"signal {sig.name}")
    task = asyncio.create_task(mission(drone, target, args.speed))
    deadline = time.monotonic() + args.seconds if args.seconds > 0 else None
    while not rospy.is_shutdown() and not task.done():
        if deadline is not None and time.monotonic() > deadline:
            rospy.signal_shutdown("mission time is up")
            break
        await asyncio.sleep(0.2)  # yield to the mission between checks
    task.cancel()
    # Hover pre-empts the running move: the simulator answers its pending request (false), so the
    # cancelled mission finishes cleanly, and the drone holds its position.
    with contextlib.suppress(Exception):
        client.request({"method": f"{hover_method}", "params": {}, "version": 1.0})
    await asyncio.wait({task}, timeout=2.0)
    bridge.shutdown()
    # Closing the client's sockets ends the mission's pending request, so the cancelled task can finish.
    client.disconnect()
    await asyncio.wait({task}, timeout=5)


def run(argv: list[str]) -> int:
    import rospy
    from projectairsim import Drone, ProjectAirSimClient, World

    from airsim_mapper.wrapper import ProjectAirSimWrapper, redirect_client_log

    args = parse_args(rospy.myargv(argv)[1:])
    rospy.init_node(args.nodename or "projectairsim", anonymous=args.nodename is None)
    redirect_client_log()
    client = ProjectAirSimClient(args.address, args.topicsport, args.servicesport)
    client.connect()
    try:
        world = World(client, args.scene, sim_config_path=args.simconfigpath.rstrip("/") + "/")
        bridge = ProjectAirSimWrapper(
            client, sim_config_path=args.simconfigpath, mapping=args.mapping, tune_process=True
        )
        bridge.update_topics(world)
        drone = Drone(client, world, args.robot)
    except BaseException:
        client.disconnect()
        raise
    asyncio.run(main(client, bridge, drone, f"{world.parent_topic}/robots/{args.robot}/Hover", args))
    return 0


if __name__ == "__main__":
    sys.exit(run(sys.argv))
