"""The headless server's simulation tick with N drones, in one process: when its last pose is out.

Every pose of a tick carries the tick's sim time, and the server publishes the robots' poses one after the
other within the tick, so the last robot's pose leaves the tick's duration after its stamp: with ten
drones that delay is part of every pose latency a subscriber measures, the bridge's and the bare
forwarder's alike. The scene is the bench's drone scene (a 320x240 camera each, `scenes.robot_config`) on
a real `TopicHub`, with a raw pynng client subscribed to the poses and reading them on a thread of this
process, as the server's sender thread sends them; each tick integrates every robot and publishes its pose
as the server does. Wall time of each tick, idle between ticks as the server is.

    python -m tools.bench.server_tick [--drones 10] [--ticks 2000]
"""

from __future__ import annotations

import argparse
import contextlib
import json
import statistics
import threading
import time
from typing import Any

import pynng

from airsim_mapper.simserver.scene.config import parse_scene
from airsim_mapper.simserver.session import Session
from airsim_mapper.simserver.wire.protocol import FrameType, encode_frame
from airsim_mapper.simserver.wire.topics import TopicHub
from airsim_mapper.simserver.world.world_file import load_world
from tools.bench import scenes
from tools.bench.sampling import p99
from tools.rig import free_port

TICK_GAP_S = 0.003  # the server's physics tick period in the bench's scenes


def scene_text(drones: int) -> str:
    """The bench's drone scene with its robot config inlined, as the client sends it to LoadScene."""
    robot = scenes.robot_config(scenes.CameraSetup(320, 240, 0.1), lidar=False)
    return json.dumps(scenes.scene_config("tick", drones, robot))


def _drain(client: pynng.Pair0, stop: threading.Event, received: list[int]) -> None:
    while not stop.is_set():
        with contextlib.suppress(pynng.Timeout):
            client.recv()
            received[0] += 1


def run(drones: int, ticks: int) -> dict[str, Any]:
    """Tick durations (ms) over `ticks` ticks that publish every robot's pose to a subscribed client."""
    hub = TopicHub("127.0.0.1", free_port())
    hub.start()
    stop, received = threading.Event(), [0]
    with pynng.Pair0(dial=hub.url, recv_timeout=100) as client:
        reader = threading.Thread(target=_drain, args=(client, stop, received), daemon=True)
        try:
            session = Session(parse_scene(scene_text(drones)), load_world(None), hub)
            hub.set_table(session.topics(), session.topic_handlers())
            session.start()
            paths = [robot.pose_path for robot in session.robots.values()]
            for path in paths:
                client.send(encode_frame(path, b"", FrameType.SUBSCRIBE))
            deadline = time.monotonic() + 10.0
            while not all(map(hub.is_subscribed, paths)) and time.monotonic() < deadline:
                time.sleep(0.01)
            reader.start()
            durations = _ticks(session, ticks)
            session.stop()
            time.sleep(0.2)  # the last poses on their way
        finally:
            stop.set()
            if reader.is_alive():
                reader.join(timeout=2.0)
            hub.stop()
    durations.sort()
    p50 = statistics.median(durations)
    return {
        "drones": drones,
        "p50_ms": p50,
        "p99_ms": p99(durations),
        "us_per_drone": 1000.0 * p50 / drones,
        "poses_received": received[0],
    }


def _ticks(session: Session, ticks: int) -> list[float]:
    durations = []
    for _ in range(ticks):
        start = time.perf_counter()
        session.tick(publish_pose=True)
        durations.append((time.perf_counter() - start) * 1000.0)
        time.sleep(TICK_GAP_S)
    return durations


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--drones", type=int, default=10)
    parser.add_argument("--ticks", type=int, default=2000)
    args = parser.parse_args(argv)
    result = run(args.drones, args.ticks)
    print(
        f"{result['drones']} drones: a tick publishing every pose took {result['p50_ms']:.3f} ms at the "
        f"median, {result['p99_ms']:.3f} ms at p99 ({result['us_per_drone']:.0f} us per drone)"
    )
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
