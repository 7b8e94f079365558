"""image_transport's sibling topics of the shipped default mapping, end to end: the headless server, the
bridge node and this process as the subscriber. Each compressed frame is decoded as the stock plugins'
subscribers decode it and compared with the raw image of the same stamp."""

from __future__ import annotations

import os
import struct
import subprocess
import threading

import cv2
import numpy as np
import pytest
from bridgeharness import Stack
from harness import wait_until

from airsim_mapper.convert.image_transport import restored_depth

pytestmark = pytest.mark.live

CAMERA = "/airsim_node/Drone1/DownCamera"
COLOUR = f"{CAMERA}/scene_camera/image"
DEPTH = f"{CAMERA}/depth_planar_camera/image"
# JPEG at quality 80 of the headless server's DownCamera frame measured 41.5 dB (5.5 kB of 230 kB); a
# swapped colour order or a misplaced row is far below 25
MIN_PSNR_DB = 35.0
DEPTH_MAX = 100.0  # the default mapping's params.depth_max


@pytest.fixture(scope="module")
def rig(module_rig_factory) -> Stack:
    rig = module_rig_factory()
    rig.start_node("--scene", "scene_drone_sensors.jsonc", node_name="transport_bridge", wait_for=DEPTH)
    return rig


def same_stamp(raw_topic: str, raw_cls, compressed_topic: str, timeout: float = 60.0):
    """A raw message and the compressed one of the same stamp, from subscriptions to both."""
    import rospy
    from sensor_msgs.msg import CompressedImage

    lock = threading.Lock()
    seen: dict[str, dict[int, object]] = {"raw": {}, "compressed": {}}

    def keep(kind: str):
        def callback(msg) -> None:
            with lock:
                seen[kind][msg.header.stamp.to_nsec()] = msg

        return callback

    subscribers = [
        rospy.Subscriber(raw_topic, raw_cls, keep("raw"), queue_size=2, buff_size=2**25),
        rospy.Subscriber(
            compressed_topic, CompressedImage, keep("compressed"), queue_size=2, buff_size=2**25
        ),
    ]

    def common() -> int | None:
        with lock:
            stamps = seen["raw"].keys() & seen["compressed"].keys()
        return max(stamps) if stamps else None

    try:
        wait_until(
            lambda: common() is not None, timeout, what=f"{raw_topic} and {compressed_topic} at one stamp"
        )
    finally:
        for subscriber in subscribers:
            subscriber.unregister()
    stamp = common()
    return seen["raw"][stamp], seen["compressed"][stamp]


def psnr(a: np.ndarray, b: np.ndarray) -> float:
    mse = np.mean((a.astype(np.float64) - b.astype(np.float64)) ** 2)
    return float("inf") if mse == 0 else float(10 * np.log10(255.0**2 / mse))


def test_the_sibling_topics_exist_with_their_type_for_rostopic(rig: Stack):
    for topic in (
        f"{COLOUR}/compressed",
        f"{DEPTH}/compressedDepth",
        "/airsim_node/Drone1/Chase/scene_camera/image/compressed",
    ):
        result = subprocess.run(
            ["rostopic", "type", topic], capture_output=True, text=True, timeout=30, env=dict(os.environ)
        )
        assert (result.returncode, result.stdout.strip()) == (0, "sensor_msgs/CompressedImage"), result.stderr


def test_compressed_is_a_jpeg_of_the_raw_image_of_the_same_stamp(rig: Stack):
    from sensor_msgs.msg import Image

    raw, compressed = same_stamp(COLOUR, Image, f"{COLOUR}/compressed")
    assert compressed.format == "bgr8; jpeg compressed bgr8"
    assert compressed.header.frame_id == raw.header.frame_id
    assert bytes(compressed.data[:3]) == b"\xff\xd8\xff"
    decoded = cv2.imdecode(np.frombuffer(compressed.data, np.uint8), cv2.IMREAD_COLOR)
    pixels = np.frombuffer(raw.data, np.uint8).reshape(raw.height, raw.width, 3)
    assert decoded.shape == pixels.shape
    measured = psnr(decoded, pixels)
    print(f"JPEG PSNR {measured:.1f} dB, {len(compressed.data)} of {len(raw.data)} bytes")
    assert measured >= MIN_PSNR_DB


def test_compressed_depth_restores_the_raw_depth_within_the_quantisation(rig: Stack):
    from sensor_msgs.msg import Image

    raw, compressed = same_stamp(DEPTH, Image, f"{DEPTH}/compressedDepth")
    assert compressed.format == "32FC1; compressedDepth png"
    fmt, a, b = struct.unpack_from("<iff", compressed.data)
    assert fmt == 0 and a == 10100.0 and b == np.float32(1.0 - 10100.0 / DEPTH_MAX)
    assert bytes(compressed.data[12:20]) == b"\x89PNG\r\n\x1a\n"
    quantised = cv2.imdecode(np.frombuffer(compressed.data[12:], np.uint8), cv2.IMREAD_UNCHANGED)
    assert quantised.dtype == np.uint16 and quantised.shape == (raw.height, raw.width)
    restored = restored_depth(quantised, a, b)
    depth = np.frombuffer(raw.data, "<f4").reshape(raw.height, raw.width)
    valid = (depth > 0) & (depth < DEPTH_MAX)
    assert valid.any()
    assert np.isnan(restored[~valid]).all()
    near, far = depth[valid], restored[valid]
    assert (far >= near - 1e-4).all()
    assert (far - near <= far**2 / a * 1.001 + 1e-4).all()  # at most one step, d^2 / A, further away


def test_format_png_is_the_raw_image_exactly(rig_factory, tmp_path):
    from sensor_msgs.msg import Image

    mapping = tmp_path / "png.yaml"
    mapping.write_text(
        "version: 1\nextends: default\nrules:\n"
        "  - {name: camera_image_compressed, params: {format: png, png_level: 1}}\n"
    )
    stack = rig_factory()  # in its own namespace: the module's node serves the default names meanwhile
    stack.start_node(
        "--scene",
        "scene_drone_sensors.jsonc",
        "--mapping",
        str(mapping),
        "--namespace",
        "png",
        node_name="png_bridge",
        wait_for=f"/png{DEPTH}",
    )
    raw, compressed = same_stamp(f"/png{COLOUR}", Image, f"/png{COLOUR}/compressed")
    assert compressed.format == "bgr8; png compressed bgr8"
    decoded = cv2.imdecode(np.frombuffer(compressed.data, np.uint8), cv2.IMREAD_UNCHANGED)
    pixels = np.frombuffer(raw.data, np.uint8).reshape(raw.height, raw.width, 3)
    np.testing.assert_array_equal(decoded, pixels)


def test_the_topics_ros_parameters_override_the_mapping_as_the_plugins_read_them(rig: Stack, rig_factory):
    """`<topic>/jpeg_quality` set before the node starts: a smaller JPEG than the default quality's; a
    `png_level` out of its bounds warned by name and bound, and the mapping's value kept."""
    import rospy
    from sensor_msgs.msg import Image

    low = f"/lowq{COLOUR}/compressed"
    rospy.set_param(f"{low}/jpeg_quality", 5)
    rospy.set_param(f"{low}/png_level", 42)
    try:
        stack = rig_factory()
        node = stack.start_node(
            "--scene",
            "scene_drone_sensors.jsonc",
            "--namespace",
            "lowq",
            node_name="lowq_bridge",
            wait_for=f"/lowq{DEPTH}",
        )
        raw, small = same_stamp(f"/lowq{COLOUR}", Image, low)
    finally:
        rospy.delete_param(f"{low}/jpeg_quality")
        rospy.delete_param(f"{low}/png_level")
    _raw, default = same_stamp(COLOUR, Image, f"{COLOUR}/compressed")
    decoded = cv2.imdecode(np.frombuffer(small.data, np.uint8), cv2.IMREAD_COLOR)
    assert decoded.shape == (raw.height, raw.width, 3)
    print(f"JPEG at quality 5: {len(small.data)} bytes, at the default 80: {len(default.data)}")
    assert len(small.data) < 0.6 * len(default.data)
    said = f"parameter {low}/png_level = 42 ignored: it must be an integer from 1 to 9; keeping"
    wait_until(lambda: said in node.output(), 10, what="the warning of png_level")
