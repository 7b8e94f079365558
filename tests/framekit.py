"""Topic frames packed the way the simulator packs them, and what the 1.1.0 client decodes from them."""

from __future__ import annotations

from typing import Any

import msgpack
import numpy as np

from airsim_mapper.simserver.wire import protocol

LIDAR_TOPIC = "/Sim/Scene/robots/Drone1/sensors/lidar1/lidar"
POINTS = 5000


def client_decode(frame: bytes) -> tuple[str, Any]:
    """What the 1.1.0 client's receive thread does with a frame (client.py __recv_topic)."""
    outer = msgpack.unpackb(frame, raw=True)
    return outer[1].decode("utf-8"), msgpack.unpackb(outer[2], raw=False)


def lidar_message(points: int = POINTS, seed: int = 0) -> dict[str, Any]:
    rng = np.random.default_rng(seed)
    return {
        "time_stamp": 1_700_000_000_123_456_789,
        "point_cloud": rng.normal(size=3 * points).astype(np.float32),
        "azimuth_elevation_range_cloud": np.zeros(0, dtype=np.float32),
        "segmentation_cloud": rng.integers(-5, 300, points).astype(np.int32),
        "intensity_cloud": rng.random(points).astype(np.float32),
        "laser_index_cloud": rng.integers(0, 16, points).astype(np.int32),
        "pose": {
            "position": {"x": 1.0, "y": 2.0, "z": -3.5},
            "orientation": {"w": 1.0, "x": 0, "y": 0, "z": 0},
        },
    }


def lidar_frame(points: int = POINTS, seed: int = 0) -> bytes:
    """A lidar frame packed exactly like the headless server (and the C++ server) packs it."""
    return protocol.encode_frame(LIDAR_TOPIC, protocol.pack(lidar_message(points, seed)))


def image_frame(topic: str = "/cam/scene_camera", width: int = 64, height: int = 48) -> bytes:
    rng = np.random.default_rng(1)
    pixels = rng.integers(0, 256, width * height * 3, dtype=np.uint8).tobytes()
    body = {
        "time_stamp": 5,
        "height": height,
        "width": width,
        "encoding": "BGR",
        "big_endian": False,
        "step": 1,
        "data": pixels,
        "pos_x": 0.5,
        "rot_w": 1.0,
        "annotations": [],
    }
    return msgpack.packb([2, topic, msgpack.packb(body, use_bin_type=True)], use_bin_type=False)
