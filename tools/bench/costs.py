"""Per-message CPU cost, from the simulator's frame bytes to a serialised ROS message (one process).

Each case is one frame, packed exactly as the headless server (and the C++ server) packs it, taken through:
- bridge: the node's path. The frame's header parsed where the frame lies (`SimLink.dispatch`), the body
  decoded in place (`receive.unpack_message`: large bodies straight into numpy arrays and pixel views), the
  bridge's converter, and the message serialised as the node publishes it (`publish.serialized`: a head,
  then the pixels or points from where they are, for one `sendmsg`);
- bridge, one buffer: the same message decoded through msgpack's outer unpacking (a copy of the body) and
  serialised into one buffer, as for a message that waits in a connection's queue;
- client: the client's msgpack unpacking of the full frame, the bridge's converter, serialisation;
- reference: the client's unpacking, the old bridge's algorithm (reference.py), serialisation;
- bare: genpy serialisation of an already built message holding the same data (what rospy alone costs).
Times are CPU time of this process (`time.process_time`), median over repeats; the bridge and the bare
serialisation, whose ratio is a target, are timed in turn, call by call.
"""

from __future__ import annotations

import io
import statistics
import time
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import msgpack
import numpy as np
from rospy.msg import serialize_message

from airsim_mapper.convert import registry
from airsim_mapper.convert.buffer_data import BufferData
from airsim_mapper.convert.context import ConvertContext
from airsim_mapper.convert.errors import ConversionError
from airsim_mapper.engine.fast_frames import parse_frame_header
from airsim_mapper.engine.publish import serialized
from airsim_mapper.engine.receive import unpack_message
from airsim_mapper.simserver.wire import protocol
from tools.bench import reference
from tools.bench.results import BGR, DEPTH, DEPTH_FLOAT, LIDAR, RADAR

FULL_HD = (1920, 1080)
SMALL = (320, 240)  # the per-pixel reference runs here and is scaled by the pixel count
LIDAR_POINTS = 100_000
RADAR_DETECTIONS = 200
STAMP_NS = 1_700_000_000_000_000_000


@dataclass(frozen=True)
class Case:
    name: str
    frame: bytes
    converter: str
    reference: Callable[[dict], Any] | None
    reference_frame: bytes | None = None  # the reference's own input (a smaller frame), if different
    reference_scale: float = 1.0  # reference time multiplier (pixel count ratio)
    repeat: int = 15


def serialize(msg: Any) -> bytes:
    buffer = io.BytesIO()
    msg.serialize(buffer)
    return buffer.getvalue()


def client_unpack(frame: bytes) -> Any:
    """The 1.1.0 client's receive path: outer frame with raw=True, then the body with raw=False."""
    return msgpack.unpackb(msgpack.unpackb(frame, raw=True)[2], raw=False)


def _frame(topic: str, message: dict) -> bytes:
    return protocol.encode_frame(topic, protocol.pack(message))


def image_frame(width: int, height: int, encoding: str, seed: int = 0) -> bytes:
    rng = np.random.default_rng(seed)
    message: dict[str, Any] = {
        "time_stamp": STAMP_NS,
        "height": height,
        "width": width,
        "encoding": encoding,
        "big_endian": False,
        "step": 1,
        "data": b"",
        "data_float": [],
        "pos_x": 0.0,
        "pos_y": 0.0,
        "pos_z": -4.0,
        "rot_w": 1.0,
        "rot_x": 0.0,
        "rot_y": 0.0,
        "rot_z": 0.0,
        "annotations": [],
    }
    depth = (rng.random(width * height) * 100).astype(np.float32)
    if encoding == "BGR":
        message["data"] = rng.integers(0, 256, width * height * 3, dtype=np.uint8).tobytes()
    elif encoding == "16FC1":
        message["data"] = depth.astype("<f2").tobytes()
    else:  # the git server's 32FC1: pixels as a msgpack float32 array
        message["data_float"] = depth
    return _frame("/Sim/Bench/robots/Drone1/sensors/Camera/scene_camera", message)


def lidar_frame(points: int = LIDAR_POINTS, seed: int = 0) -> bytes:
    rng = np.random.default_rng(seed)
    message = {
        "time_stamp": STAMP_NS,
        "point_cloud": rng.normal(scale=20.0, size=3 * points).astype(np.float32),
        "azimuth_elevation_range_cloud": np.zeros(0, dtype=np.float32),
        "segmentation_cloud": rng.integers(0, 255, points).astype(np.int32),
        "intensity_cloud": rng.random(points).astype(np.float32),
        "laser_index_cloud": rng.integers(0, 16, points).astype(np.int32),
        "pose": {
            "position": {"x": 0.0, "y": 0.0, "z": -4.0},
            "orientation": {"w": 1.0, "x": 0, "y": 0, "z": 0},
        },
    }
    return _frame("/Sim/Bench/robots/Drone1/sensors/lidar1/lidar", message)


def radar_frame(detections: int = RADAR_DETECTIONS, seed: int = 0) -> bytes:
    rng = np.random.default_rng(seed)
    rows = rng.random((detections, 5)) + 0.1
    message = {
        "time_stamp": STAMP_NS,
        "radar_detections": [
            {"range": r * 50, "azimuth": a - 0.5, "elevation": e - 0.5, "velocity": v, "rcs_sqm": s}
            for r, a, e, v, s in rows.tolist()
        ],
        "pose": {
            "position": {"x": 0.0, "y": 0.0, "z": -4.0},
            "orientation": {"w": 1.0, "x": 0, "y": 0, "z": 0},
        },
    }
    return _frame("/Sim/Bench/robots/Drone1/sensors/radar1/radar_detections", message)


def as_genpy(msg: Any) -> Any:
    """The same message as plain genpy builds it: a Buffer* message (a BufferImage, a BufferPointCloud2)
    becomes its genpy class holding bytes.

    The bare-serialisation baseline is genpy's own serialiser on bytes, as any rospy node would publish.
    """
    if isinstance(msg, BufferData):
        plain = msg._genpy_class
        fields = {name: getattr(msg, name) for name in plain.__slots__}
        return plain(**{**fields, "data": bytes(msg.data)})
    return msg


def cases() -> list[Case]:
    scale = (FULL_HD[0] * FULL_HD[1]) / (SMALL[0] * SMALL[1])
    small_depth = image_frame(*SMALL, "32FC1")

    def depth(name: str, encoding: str, repeat: int = Case.repeat) -> Case:
        """A 1080p depth image; the per-pixel reference on the small one, scaled."""
        frame = image_frame(*FULL_HD, encoding)
        return Case(name, frame, "image", reference.depth_32fc1_to_image, small_depth, scale, repeat)

    return [
        Case(BGR, image_frame(*FULL_HD, "BGR"), "image", reference.bgr_to_image),
        depth(DEPTH, "16FC1"),
        depth(DEPTH_FLOAT, "32FC1", repeat=5),
        Case(LIDAR, lidar_frame(), "pointcloud", reference.lidar_to_cloud),
        Case(RADAR, radar_frame(), "radar_scan", reference.radar_to_scan, repeat=50),
    ]


def cpu_ms(fn: Callable[[], Any], repeat: int) -> float:
    """Median CPU time (ms) of `fn` over `repeat` calls after one warm-up call."""
    return side_by_side_cpu_ms((fn,), repeat)[0]


def side_by_side_cpu_ms(fns: tuple[Callable[[], Any], ...], repeat: int) -> list[float]:
    """Median CPU time (ms) of each of `fns`, called in turn `repeat` times after one warm-up call each, so
    that a slow moment of the host weighs on all of them alike."""
    for fn in fns:
        fn()
    samples: list[list[float]] = [[] for _ in fns]
    for _ in range(repeat):
        for fn, taken in zip(fns, samples):
            start = time.process_time()
            fn()
            taken.append((time.process_time() - start) * 1e3)
    return [statistics.median(taken) for taken in samples]


def bridge_unpack(frame: bytes) -> Any:
    """A frame's message as the bridge's receive loop decodes it: the header parsed in place, as
    `SimLink.dispatch` does for a large frame, then `unpack_message` on a view of the body."""
    header = parse_frame_header(frame)
    if header is None:
        raise AssertionError("a cost case's frame must be large enough for the bridge's header parser")
    return unpack_message(memoryview(frame)[header.body_start : header.body_end], fast=True)[0]


def one_buffer_unpack(frame: bytes) -> Any:
    """A frame's message decoded after msgpack's outer unpacking, which copies the body."""
    return unpack_message(msgpack.unpackb(frame, raw=True)[2], fast=True)[0]


def node_serialize(msg: Any) -> tuple[Any, ...]:
    """The message as the node hands it to a connection, length prefix first: in parts where it serialises
    apart (a Buffer* message, `publish.serialized`), otherwise rospy's publish buffer."""
    serialize_apart = getattr(msg, "serialize_apart", None)
    if serialize_apart is not None:
        return serialized(msg, serialize_apart, 0)
    buffer = io.BytesIO()
    serialize_message(buffer, 0, msg)
    return (buffer.getvalue(),)


def sent_bytes(parts: tuple[Any, ...]) -> bytes:
    """The message that `node_serialize`'s parts put on the wire, without its length prefix."""
    return b"".join(parts)[4:]


def measure_case(case: Case) -> dict[str, Any]:
    convert = registry.get(case.converter)
    ctx = ConvertContext(frame_id="bench")

    def bridge() -> tuple[Any, ...]:
        return node_serialize(convert(bridge_unpack(case.frame), ctx))

    def one_buffer() -> bytes:
        return serialize(convert(one_buffer_unpack(case.frame), ctx))

    def client() -> bytes:
        return serialize(convert(client_unpack(case.frame), ctx))

    plain = as_genpy(convert(client_unpack(case.frame), ctx))
    result: dict[str, Any] = {
        "frame_bytes": len(case.frame),
        "client_path_ms": cpu_ms(client, case.repeat),
        "unpack_client_ms": cpu_ms(lambda: client_unpack(case.frame), case.repeat),
        "unpack_fast_ms": cpu_ms(lambda: bridge_unpack(case.frame), case.repeat),
    }
    try:
        expected = client()
        same = sent_bytes(bridge()) == expected and one_buffer() == expected
    except ConversionError as exc:  # a converter that cannot take numpy input yet: say so in the results
        result["bridge_error"] = str(exc)
        result["bare_serialize_ms"] = cpu_ms(lambda: serialize(plain), case.repeat)
        return result
    if not same:
        raise AssertionError(f"{case.name}: the fast path serialises differently from the client path")
    result["bridge_ms"], result["one_buffer_ms"], result["bare_serialize_ms"] = side_by_side_cpu_ms(
        (bridge, one_buffer, lambda: serialize(plain)), case.repeat
    )
    result["ratio_to_bare_serialize"] = result["bridge_ms"] / max(result["bare_serialize_ms"], 1e-6)
    if case.reference is not None:
        ref_frame = case.reference_frame or case.frame
        ref_repeat = 1 if case.reference_scale > 1 else max(3, case.repeat // 3)
        measured = cpu_ms(lambda: serialize(case.reference(client_unpack(ref_frame))), ref_repeat)
        result["reference_ms"] = measured * case.reference_scale
        result["reference_extrapolated"] = case.reference_scale > 1
        if "bridge_ms" in result:
            result["speedup_vs_reference"] = result["reference_ms"] / max(result["bridge_ms"], 1e-6)
    return result


def run() -> dict[str, dict[str, Any]]:
    return {case.name: measure_case(case) for case in cases()}
