"""A scene load while the old scene is still working: nothing the old scene publishes reaches the new one."""

from __future__ import annotations

import json
import threading
import time
from collections.abc import Iterator

import pytest
from harness import free_port

from airsim_mapper.simserver.server import ServerOptions, SimServer
from airsim_mapper.simserver.wire import protocol

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


@pytest.mark.parametrize("lane", ["camera_tick", "scan_tick"])
def test_a_scene_load_waits_for_a_sensor_step_in_progress_so_its_frame_is_not_the_new_scenes(server, lane):
    old = server.session
    stepping, finish = threading.Event(), threading.Event()

    def slow_step() -> bool:  # a render of the old scene, finishing after the load has begun
        stepping.set()
        finish.wait(10.0)
        server.hub.publish(POSE, {"from": "the old scene"})
        return False

    setattr(old, lane, slow_step)  # the lane's loop takes it on its next step
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


def test_a_render_that_hangs_holds_back_no_lidar_or_radar_sample(server):
    """Cameras and scans have a thread each: a starved render worker slows images, not scans."""
    from simserver.clientkit import scene_config

    server._load_scene({"scene_config": json.dumps(scene_config("scene_drone_sensors.jsonc"))})
    session = server.session
    rendering, release = threading.Event(), threading.Event()

    def hung_render() -> bool:
        rendering.set()
        release.wait(10.0)
        return False

    session.camera_tick = hung_render
    published: list[str] = []
    publish = server.hub.publish
    server.hub.publish = lambda path, message: published.append(path) or publish(path, message)
    sensors = "/Sim/SceneDroneSensors/robots/Drone1/sensors"
    lidar, radar = f"{sensors}/lidar1/lidar", f"{sensors}/radar1/radar_detections"
    for path in (lidar, radar):
        server.hub._subscribe(path)
    try:
        assert rendering.wait(5.0)
        time.sleep(1.0)
        # lidar1 reports at 10 Hz, radar1 detects every 0.1 s (sim time runs at wall time)
        assert published.count(lidar) >= 5 and published.count(radar) >= 5, (
            published.count(lidar),
            published.count(radar),
        )
    finally:
        release.set()
