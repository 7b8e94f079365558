"""Simulator data too large to take: a PNG bomb, a frame over --max-frame-mb, an image without pixels and a
frame of an unknown type are each dropped and counted, the node's memory stays small and good images go on."""

from __future__ import annotations

import time

import cv2
import msgpack
import numpy as np
import pytest
from harness import Rig, RosMaster, wait_until

from airsim_mapper.simserver.wire.protocol import encode_frame
from reliability.fake_server import FakeSimServer, message_frame
from reliability.relkit import SimPorts, probe, stamps, start_node, statuses

SIM = "/Sim/SceneDroneSensors/robots/Drone1"
CAMERA = f"{SIM}/sensors/Chase/scene_camera"
IMAGE = "/airsim_node/Drone1/Chase/scene_camera/image"
BRIDGE = "camera_image[Drone1/Chase/scene_camera]"
BOMB_SIDE = 16000  # 768 MB once decoded


def camera_image(encoding: str, data: bytes, width: int, height: int) -> dict:
    return {"time_stamp": 1, "encoding": encoding, "width": width, "height": height, "data": data}


def png_bomb() -> bytes:
    """A real PNG of 16000x16000 zeros is ~750 kB; its header alone is what matters: a small PNG whose
    IHDR claims 16000x16000."""
    data = bytearray(cv2.imencode(".png", np.zeros((2, 2, 3), dtype=np.uint8))[1].tobytes())
    data[16:24] = BOMB_SIDE.to_bytes(4, "big") * 2
    return bytes(data)


def camera_frames() -> list[bytes]:
    good = message_frame(CAMERA, camera_image("BGR", bytes(4 * 3 * 3), 4, 3))
    return [
        good,
        message_frame(CAMERA, camera_image("PNG", png_bomb(), BOMB_SIDE, BOMB_SIDE)),
        good,
        message_frame(CAMERA, camera_image("BGR", bytes(2 * 1024 * 1024), 1024, 683)),  # 2 MB > 1 MB
        good,
        message_frame(CAMERA, camera_image("BGR", b"", 0, 0)),
        good,
        encode_frame(CAMERA, msgpack.packb(camera_image("BGR", bytes(36), 4, 3)), frame_type=7),
    ]


@pytest.fixture
def fake(launcher: Rig) -> tuple[FakeSimServer, SimPorts]:
    ports = SimPorts.free()
    sim = FakeSimServer(
        "127.0.0.1", ports.topics, ports.services, "SceneDroneSensors", {CAMERA: camera_frames()}
    )
    yield sim, ports
    sim.close()


def rss_mb(pid: int) -> float:
    with open(f"/proc/{pid}/status") as status:
        line = next(line for line in status if line.startswith("VmRSS:"))
    return int(line.split()[1]) / 1024


def test_oversized_and_empty_images_are_dropped_and_counted_and_memory_stays_small(
    launcher: Rig, ros_master: RosMaster, fake: tuple[FakeSimServer, SimPorts]
):
    _sim, ports = fake
    node = start_node(launcher, ports, "--scene", "scene_drone_sensors.jsonc", "--max-frame-mb", "1")
    status = probe(launcher, "status", "status", "rel")
    images = probe(launcher, "image", "watch", IMAGE)  # camera bridges are lazy

    def last() -> dict:
        reports = statuses(status)
        return reports[-1] if reports else {}

    wait_until(lambda: len(stamps(images)) > 20, 60, what="good images between the bad ones")
    wait_until(lambda: last().get("oversized_frames", 0) >= 4, 20, what="counted oversized frames")
    report = last()
    assert report["state"] == "connected" and report["sim_losses"] == 0
    assert report["bad_frames"] >= 1  # the frame of type 7
    assert report["bridge_errors"][BRIDGE] >= 2  # the bomb and the 0x0 image
    rss = rss_mb(node.pid)
    print(f"node RSS {rss:.0f} MB")
    assert rss < 400  # the bomb alone would have taken 768 MB
    log = node.output()
    # one warning per bridge per 5 s: the first of the bomb and the empty image is what shows
    assert any(
        text in log
        for text in ("image: 16000x16000 is over the limit of 50000000 pixels", "0x0 has no pixels")
    )
    # the link also warns once per 5 s, for the oversized frame or the one of an unknown type
    assert any(
        text in log
        for text in (
            "MB frame dropped: over the 1 MB limit (--max-frame-mb)",
            "frame of unknown type 7 dropped",
        )
    )
    assert "Traceback" not in log
    assert node.alive()


def test_memory_returns_after_large_images(launcher: Rig, ros_master: RosMaster):
    good = message_frame(CAMERA, camera_image("BGR", bytes(4 * 3 * 3), 4, 3))
    side = 5770  # 99.9 MB once decoded: just under the byte cap
    large = cv2.imencode(".png", np.full((side, side, 3), 7, dtype=np.uint8))[1].tobytes()
    ports = SimPorts.free()
    sim = FakeSimServer("127.0.0.1", ports.topics, ports.services, "SceneDroneSensors", {CAMERA: [good]})
    try:
        node = start_node(launcher, ports, "--scene", "scene_drone_sensors.jsonc")
        images = probe(launcher, "image", "watch", IMAGE)
        wait_until(lambda: len(stamps(images)) > 20, 60, what="small images")
        time.sleep(2.0)
        before = rss_mb(node.pid)
        seen = len(stamps(images))
        sim.feeds[CAMERA] = [message_frame(CAMERA, camera_image("PNG", large, side, side))]
        wait_until(lambda: len(stamps(images)) >= seen + 5, 120, what="large images")
        peak = rss_mb(node.pid)
        sim.feeds[CAMERA] = [good]
        seen = len(stamps(images))
        wait_until(lambda: len(stamps(images)) >= seen + 50, 60, what="small images again")
        time.sleep(2.0)
        after = rss_mb(node.pid)
        print(
            f"node RSS {before:.0f} MB before, {peak:.0f} MB with {side}x{side} images, {after:.0f} MB after"
        )
        assert after - before < 30.0, "memory should return after large frames"
    finally:
        sim.close()
