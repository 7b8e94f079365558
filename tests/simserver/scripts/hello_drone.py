"""A hello-drone mission written only against the public `projectairsim` client API.

Usage: hello_drone.py ADDRESS TOPICS_PORT SERVICES_PORT SIM_CONFIG_DIR
Loads scene_drone_sensors.jsonc, takes off, flies, reads sensors and lands; prints what it saw.
"""

from __future__ import annotations

import asyncio
import sys
import threading

from projectairsim import Drone, ProjectAirSimClient, World
from projectairsim.utils import unpack_image


async def mission(client: ProjectAirSimClient, sim_config: str) -> None:
    world = World(client, "scene_drone_sensors.jsonc", delay_after_load_sec=0, sim_config_path=sim_config)
    drone = Drone(client, world, "Drone1")
    seen = threading.Event()
    client.subscribe(drone.sensors["DownCamera"]["scene_camera"], lambda _t, _m: seen.set())
    drone.enable_api_control()
    drone.arm()
    print("takeoff", await (await drone.takeoff_async()))
    print("move", await (await drone.move_by_velocity_async(2.0, 0.0, -1.0, 1.0)))
    images = drone.get_images("DownCamera", [0, 1])
    print("image", unpack_image(images[0]).shape, "depth", unpack_image(images[1]).shape)
    print("imu", sorted(drone.get_imu_data("IMU1")))
    print("subscribed image", seen.wait(5.0))
    print("land", await (await drone.land_async()))
    print("landed state", drone.get_landed_state())
    drone.disarm()
    drone.disable_api_control()


def main() -> int:
    address, topics_port, services_port, sim_config = sys.argv[1:5]
    client = ProjectAirSimClient(address, int(topics_port), int(services_port))
    client.connect()
    try:
        asyncio.run(mission(client, sim_config))
    finally:
        client.disconnect()
    return 0


if __name__ == "__main__":
    sys.exit(main())
