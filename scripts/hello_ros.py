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
from collections.abc import Callable
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))  # run from a checkout without install

from airsim_mapper.common.ports import SERVICES_PORT, TOPICS_PORT  # noqa: E402

log = logging.getLogger("rosout.hello_ros")


def parse_args(argv: list[str]) -> argparse.Namespace:
    parser = argparse.ArgumentParser(
        description="Fly Drone1 to the orange ball and back while bridging to ROS."
    )
    parser.add_argument("--address", default="127.0.0.1")
    parser.add_argument("--nodename", default=None)
    parser.add_argument("--simconfigpath", default=str(ROOT / "sim_config"))
    parser.add_argument("--servicesport", type=int, default=SERVICES_PORT)
    parser.add_argument("--topicsport", type=int, default=TOPICS_PORT)
    parser.add_argument("--mapping", default="default", help="mapping YAML file or shipped mapping name")
    parser.add_argument("--scene", default="scene_drone_sensors.jsonc")
    parser.add_argument("--robot", default="Drone1")
    parser.add_argument("--target", default="17 17 -4", help="NED point near the orange ball, 'x y z' metres")
    parser.add_argument("--speed", type=float, default=4.0, help="m/s")
    parser.add_argument("--seconds", type=float, default=0.0, help="stop after this long (0: until Ctrl-C)")
    return parser.parse_args(argv)


async def mission(
    drone, target: tuple[float, float, float], speed: float, stopped: Callable[[], bool]
) -> None:
    """Take off, then shuttle between the launch pad and the ball until `stopped()` (ROS shut down)."""
    drone.enable_api_control()
    drone.arm()
    await (await drone.takeoff_async())
    home = (0.0, 0.0, target[2])
    legs = 0
    while not stopped():
        for x, y, z in (target, home):
            if stopped():  # a pre-empted move returned: start no new one
                return
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
    task = asyncio.create_task(mission(drone, target, args.speed, rospy.is_shutdown))
    deadline = time.monotonic() + args.seconds if args.seconds > 0 else None
    while not rospy.is_shutdown() and not task.done():
        if deadline is not None and time.monotonic() > deadline:
            rospy.signal_shutdown("mission time is up")
            break
        await asyncio.sleep(0.2)  # yield to the mission between checks
    await stop_mission(client, bridge, task, hover_method)


async def stop_mission(client, bridge, task: asyncio.Task, hover_method: str) -> None:
    """Hold the drone where it is, let the pending requests end, stop the bridge and disconnect."""
    # Hover pre-empts the running move: the simulator answers its pending request (false) and the mission,
    # seeing ROS shut down, starts no other. So no request is left pending when the sockets close (the
    # client would log its ConnectionReset with a traceback), and the drone holds its position.
    with contextlib.suppress(Exception):
        client.request({"method": f"{hover_method}", "params": {}, "version": 1.0})
    others = asyncio.all_tasks() - {asyncio.current_task()}  # the mission and the client's request tasks
    if others:
        await asyncio.wait(others, timeout=3.0)
    task.cancel()
    bridge.shutdown()
    client.disconnect()
    await asyncio.wait({task}, timeout=5)


def quiet_closed_contexts() -> None:
    """pynng prints "Exception ignored in Context.__del__ ... Closed" for each request context collected
    after the client closed its socket: harmless at exit, so not printed; anything else still is."""
    from pynng.exceptions import Closed

    default = sys.unraisablehook

    def hook(unraisable) -> None:
        if not isinstance(unraisable.exc_value, Closed):
            default(unraisable)

    sys.unraisablehook = hook


def run(argv: list[str]) -> int:
    import rospy
    from projectairsim import Drone, ProjectAirSimClient, World

    from airsim_mapper.wrapper import ProjectAirSimWrapper, redirect_client_log

    args = parse_args(rospy.myargv(argv)[1:])
    rospy.init_node(args.nodename or "projectairsim", anonymous=args.nodename is None)
    redirect_client_log()
    quiet_closed_contexts()
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
