"""compressed_image: the simulator's PNG bytes, unchanged, as image_transport's compressed transport reads
them; anything but PNG refused with a message that says how to get PNG."""

from __future__ import annotations

import io
import re
from pathlib import Path

import cv2
import numpy as np
import pytest
from sensor_msgs.msg import CompressedImage

from airsim_mapper.convert import registry
from airsim_mapper.convert.compressed_image import FORMAT, compressed_image
from airsim_mapper.convert.context import ConvertContext
from airsim_mapper.convert.errors import ConversionError, OversizedData

CTX = ConvertContext(frame_id="airsim_node/Drone1/FrontCamera/scene_camera_optical")
FRAME = np.random.default_rng(7).integers(0, 256, (24, 32, 3), dtype=np.uint8)  # BGR, as rendered


def png(frame: np.ndarray = FRAME) -> bytes:
    ok, encoded = cv2.imencode(".png", frame)  # what the simulator does with compress: true
    assert ok
    return encoded.tobytes()


def sim_image(encoding: str, data, width: int = 32, height: int = 24) -> dict:
    return {"time_stamp": 1_000_000_123, "width": width, "height": height, "encoding": encoding, "data": data}


def serialized(msg) -> bytes:
    buffer = io.BytesIO()
    msg.serialize(buffer)
    return buffer.getvalue()


def test_the_png_bytes_go_out_unchanged_and_decode_to_the_rendered_frame():
    data = png()
    msg = compressed_image(sim_image("PNG", data), CTX)
    assert msg.data is data  # not decoded, not copied
    assert msg.format == FORMAT == "bgr8; png compressed bgr8"
    assert (msg.header.stamp.secs, msg.header.stamp.nsecs, msg.header.frame_id) == (1, 123, CTX.frame_id)
    assert (msg._type, msg._md5sum) == (CompressedImage._type, CompressedImage._md5sum)
    received = CompressedImage()
    received.deserialize(serialized(msg))
    assert received.data == data and received.header.frame_id == CTX.frame_id
    # what compressed_image_transport's subscriber does: imdecode, encoding before ';', no colour swap
    decoded = cv2.imdecode(np.frombuffer(received.data, np.uint8), cv2.IMREAD_UNCHANGED)
    assert received.format.split(";")[0] == "bgr8" and np.array_equal(decoded, FRAME)


def test_a_memoryview_of_the_frame_is_written_as_it_is():
    data = png()
    from_bytes = compressed_image(sim_image("PNG", data), CTX)
    from_view = compressed_image(sim_image("PNG", memoryview(data)), CTX)
    assert serialized(from_view) == serialized(from_bytes)


@pytest.mark.parametrize("encoding", ["BGR", "16FC1", "GRAY8"])
def test_raw_pixels_are_refused_saying_how_to_get_png(encoding):
    with pytest.raises(ConversionError) as caught:
        registry.get("compressed_image")(sim_image(encoding, bytes(32 * 24 * 3)), CTX)
    text = str(caught.value)
    assert text.startswith(f"compressed_image: the simulator sent '{encoding}' pixels, not PNG")
    assert '"compress": true' in text and "image converter" in text


def test_an_empty_png_a_wrong_size_and_too_many_pixels_are_refused():
    convert = registry.get("compressed_image")
    with pytest.raises(ConversionError, match="PNG data is empty"):
        convert(sim_image("PNG", b""), CTX)
    with pytest.raises(ConversionError, match="PNG header says 32x24, the message 64x24"):
        convert(sim_image("PNG", png(), width=64), CTX)
    with pytest.raises(ConversionError, match="does not start with the PNG signature"):
        convert(sim_image("PNG", b"not a png at all, clearly"), CTX)
    with pytest.raises(OversizedData, match="over the limit of 100 pixels"):
        convert(sim_image("PNG", png()), ConvertContext(params={"max_pixels": 100}))


def test_the_camera_info_sent_on_the_disparity_topic_publishes_nothing():
    info = {"time_stamp": 1, "width": 32, "height": 24, "intrinsic_camera_matrix": [0.0] * 9}
    assert compressed_image(info, CTX) is None


DOC = Path(__file__).resolve().parents[2] / "docs" / "converters.md"
ROS = "/airsim_node/Drone1/DownCamera/scene_camera/image/compressed"
SIM = "/Sim/SceneDroneSensors/robots/Drone1/sensors/DownCamera/scene_camera"


def test_the_documented_rule_publishes_the_png_and_counts_raw_pixels_as_bridge_errors():
    """The mapping of docs/converters.md, run by the engine's own runners on the fake links."""
    from fakes import FakeRos, FakeSimLink
    from harness import SIM_CONFIG, wait_until

    from airsim_mapper.engine.bridges import BridgeParts
    from airsim_mapper.engine.hub import StreamHub
    from airsim_mapper.engine.runners import build
    from airsim_mapper.mapping.expand import expand
    from airsim_mapper.mapping.loader import load_mapping_text
    from airsim_mapper.mapping.scene import read_scene

    text = re.search(r"```yaml\n(.*?)```", DOC.read_text(encoding="utf-8"), re.S).group(1)
    mapping = load_mapping_text(text, str(SIM_CONFIG / "compressed.yaml"))
    specs = expand(mapping, read_scene(SIM_CONFIG, "scene_drone_sensors.jsonc"), "projectairsim")
    spec = next(spec for spec in specs if spec.ros == ROS)
    assert (spec.sim, spec.ros_type, spec.options.lazy) == (SIM, "sensor_msgs/CompressedImage", True)
    sim, ros = FakeSimLink(), FakeRos()
    bridge = build(spec, BridgeParts(sim, StreamHub(sim, ros.send_tf), ros, {}, lambda *_: None))
    bridge.start()
    assert SIM not in sim.subscriptions  # lazy: nothing from the simulator without a subscriber
    ros.publishers[ROS].subscribers(1)
    data = png()
    assert sim.deliver(SIM, sim_image("PNG", data)) == 1
    wait_until(lambda: ros.publishers[ROS].messages, 5, what="the compressed image")
    published = ros.publishers[ROS].messages[0]
    assert published.data is data and published.format == FORMAT
    sim.deliver(SIM, sim_image("BGR", FRAME.tobytes()))
    wait_until(lambda: bridge.stats.errors == 1, 5, what="the refused raw image")
    assert "not PNG" in bridge.stats.last_error and bridge.stats.messages == 1
    bridge.stop()
