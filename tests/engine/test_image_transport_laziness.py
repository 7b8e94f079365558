"""The default mapping's image_transport rules on the engine's own runners (fake links): nothing is encoded
while the compressed topic has no subscriber, even with the raw image watched; with one, the frame is
encoded off the receive thread, on the image stream's worker."""

from __future__ import annotations

import threading

import numpy as np
from fakes import FakeRos, FakeSimLink
from harness import ROOT, SIM_CONFIG, wait_until

from airsim_mapper.convert import image_transport
from airsim_mapper.engine.bridges import BridgeParts
from airsim_mapper.engine.hub import StreamHub
from airsim_mapper.engine.runners import build
from airsim_mapper.mapping.expand import expand
from airsim_mapper.mapping.loader import load_mapping
from airsim_mapper.mapping.scene import read_scene

CAMERA = "Drone1/DownCamera/scene_camera"
SIM = "/Sim/SceneDroneSensors/robots/Drone1/sensors/DownCamera/scene_camera"
RAW = "/airsim_node/Drone1/DownCamera/scene_camera/image"
COMPRESSED = f"{RAW}/compressed"
FRAME = np.full((12, 16, 3), 90, np.uint8)


def frame(stamp: int) -> dict:
    return {"time_stamp": stamp, "width": 16, "height": 12, "encoding": "BGR", "data": FRAME.tobytes()}


def test_no_subscriber_on_compressed_means_no_encode_and_one_means_encoding_on_the_worker(monkeypatch):
    encodes: list[str] = []
    real = image_transport.encode_jpeg

    def counted(pixels, quality=80):
        encodes.append(threading.current_thread().name)
        return real(pixels, quality)

    monkeypatch.setattr(image_transport, "encode_jpeg", counted)
    scene = read_scene(SIM_CONFIG, "scene_drone_sensors.jsonc")
    specs = expand(load_mapping(ROOT / "mappings" / "default.yaml"), scene, "projectairsim")
    wanted = {f"camera_image[{CAMERA}]", f"camera_image_compressed[{CAMERA}]"}
    sim, ros = FakeSimLink(), FakeRos()
    services = BridgeParts(sim, StreamHub(sim, ros.send_tf), ros, {}, lambda *_: None)
    bridges = [build(spec, services) for spec in specs if spec.name in wanted]
    for bridge in bridges:
        bridge.start()
    try:
        ros.publishers[RAW].subscribers(1)  # the raw image watched, compressed not
        for stamp in range(1, 6):
            sim.deliver(SIM, frame(stamp))
            wait_until(lambda stamp=stamp: len(ros.publishers[RAW].messages) == stamp, 5, what="raw image")
        assert encodes == [] and ros.publishers[COMPRESSED].messages == []

        ros.publishers[COMPRESSED].subscribers(1)
        receiver = threading.current_thread().name
        sim.deliver(SIM, frame(10))
        wait_until(lambda: ros.publishers[COMPRESSED].messages, 5, what="the compressed image")
        published = ros.publishers[COMPRESSED].messages[0]
        assert published.format == "bgr8; jpeg compressed bgr8"
        assert encodes == [f"stream:{SIM}"] and receiver not in encodes  # the image stream's worker

        ros.publishers[COMPRESSED].subscribers(0)
        sim.deliver(SIM, frame(11))
        wait_until(lambda: len(ros.publishers[RAW].messages) == 7, 5, what="raw image")
        assert len(encodes) == 1
    finally:
        for bridge in bridges:
            bridge.stop()
