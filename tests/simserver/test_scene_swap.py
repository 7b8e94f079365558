"""A scene load while the old scene is still working: nothing the old scene publishes reaches the new one."""

from __future__ import annotations

import json
import threading
from collections.abc import Iterator

import pytest
from harness import free_port

from airsim_mapper.simserver import protocol
from airsim_mapper.simserver.server import ServerOptions, SimServer

POSE = "/Sim/SceneBasicDrone/robots/Drone1/actual_pose"  # the default scene's, and the reloaded one's
SAME_ID = {
    "id": "SceneBasicDrone",
    "actors": [
        {
            "type": "robot",
            "name": "Drone1",
            "origin": {"xyz": "5 0 -4", "rpy-deg": "0 0 0"},
            "robot-config": {"physics-type": "fast-physics", "sensors": []},
        }
    ],
    "clock": {"type": "steppable"},
}


@pytest.fixture
def server() -> Iterator[SimServer]:
    """A running in-process server on free loopback ports, with its renderer in process."""
    server = SimServer(ServerOptions("127.0.0.1", free_port(), free_port(), render_nice=None))
    server.start()
    try:
        yield server
    finally:
        server.stop()


def test_a_scene_load_waits_for_a_sensor_step_in_progress_so_its_frame_is_not_the_new_scenes(server):
    old = server.session
    stepping, finish = threading.Event(), threading.Event()

    def slow_step() -> bool:  # a render of the old scene, finishing after the load has begun
        stepping.set()
        finish.wait(10.0)
        server.hub.publish(POSE, {"from": "the old scene"})
        return False

    old.sensor_tick = slow_step  # the sensor loop takes it on its next step
    assert stepping.wait(5.0)
    load = threading.Thread(target=server._load_scene, args=({"scene_config": json.dumps(SAME_ID)},))
    load.start()
    load.join(0.3)
    assert load.is_alive()  # the swap waits for the step
    finish.set()
    load.join(10.0)
    assert not load.is_alive() and server.session is not old
    cached = protocol.decode_body(server.hub.cached(POSE))
    assert cached["position"]["x"] == 5.0  # the new scene's first pose, not the old scene's late frame
