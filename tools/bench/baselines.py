"""Transport baselines of the end-to-end benchmark, each a separate process.

- `rospy-pub`: a bare rospy publisher of a ready-made Image (1920x1080 bgr8) or PointCloud2 (100k points,
  the bridge's 20-byte layout) at a fixed rate, stamped with the wall clock; the probe subscribes to it.
- `pynng-send` / `pynng-recv`: the simulator leg alone. The sender packs and sends the same frames the
  headless server sends (protocol.py), stamped with the wall clock; the receiver reads them on a Pair0
  socket as the client does (one recv per frame) and measures latency from the stamp in the body.

    python -m tools.bench.baselines rospy-pub --kind image --rate 30
    python -m tools.bench.baselines pynng-send --kind image --rate 30 --port P
    python -m tools.bench.baselines pynng-recv --port P --out result.json
"""

from __future__ import annotations

import argparse
import contextlib
import time
from collections.abc import Callable
from typing import Any

import msgpack
import numpy as np

from airsim_mapper.engine.fast_frames import parse_frame_header
from airsim_mapper.simserver.wire import protocol
from tools.bench.probe import TopicRecord, summary, write_result

WIDTH, HEIGHT, POINTS = 1920, 1080, 100_000
RAW_TOPIC = "/bench/raw"


def ticker(rate: float) -> Callable[[], None]:
    """Sleeps until the next period boundary (no drift, no catch-up burst)."""
    period = 1.0 / rate
    state = {"next": time.monotonic()}

    def wait() -> None:
        state["next"] = max(state["next"] + period, time.monotonic() - period)
        delay = state["next"] - time.monotonic()
        if delay > 0:
            time.sleep(delay)

    return wait


def ros_message(kind: str) -> Any:
    from airsim_mapper.convert import registry
    from airsim_mapper.convert.context import ConvertContext
    from tools.bench import costs

    if kind == "image":
        converter, frame = "image", costs.image_frame(WIDTH, HEIGHT, "BGR")
    else:
        converter, frame = "pointcloud", costs.lidar_frame(POINTS)
    msg = registry.get(converter)(costs.client_unpack(frame), ConvertContext(frame_id="bench"))
    return costs.as_genpy(msg)  # what any rospy node publishes: genpy's message on bytes


def rospy_pub(kind: str, rate: float) -> int:
    import rospy

    rospy.init_node("bench_raw_publisher", anonymous=True)
    msg = ros_message(kind)
    publisher = rospy.Publisher(RAW_TOPIC, type(msg), queue_size=1)
    wait = ticker(rate)
    while not rospy.is_shutdown():
        msg.header.stamp = rospy.Time.from_sec(time.time())
        publisher.publish(msg)
        wait()
    return 0


def sim_message(kind: str) -> dict[str, Any]:
    rng = np.random.default_rng(0)
    if kind == "image":
        data = rng.integers(0, 256, WIDTH * HEIGHT * 3, dtype=np.uint8).tobytes()
        return {
            "time_stamp": 0,
            "height": HEIGHT,
            "width": WIDTH,
            "encoding": "BGR",
            "big_endian": False,
            "step": 1,
            "data": data,
        }
    return {
        "time_stamp": 0,
        "point_cloud": rng.normal(size=3 * POINTS).astype(np.float32),
        "segmentation_cloud": rng.integers(0, 255, POINTS).astype(np.int32),
        "intensity_cloud": rng.random(POINTS).astype(np.float32),
    }


def pynng_send(kind: str, rate: float, port: int) -> int:
    import pynng

    message = sim_message(kind)
    wait = ticker(rate)
    with pynng.Pair0(listen=f"tcp://127.0.0.1:{port}", send_timeout=1000) as sock:
        while True:
            message["time_stamp"] = time.time_ns()
            with contextlib.suppress(pynng.exceptions.Timeout):
                sock.send(protocol.encode_frame(RAW_TOPIC, protocol.pack(message)))
            wait()


def frame_stamp_ns(frame: bytes) -> int:
    """The body's leading time_stamp, read without unpacking the body."""
    header = parse_frame_header(frame)
    if header is None:
        raise ValueError("not a topics frame")
    unpacker = msgpack.Unpacker(raw=False)
    unpacker.feed(frame[header.body_start : header.body_start + 64])
    unpacker.read_map_header()
    if unpacker.unpack() != "time_stamp":
        raise ValueError("the body does not start with time_stamp")
    return unpacker.unpack()


def pynng_recv(port: int, warmup: float, duration: float, out: str) -> int:
    import pynng

    record = TopicRecord()
    with pynng.Pair0(recv_timeout=10_000) as sock:
        sock.dial(f"tcp://127.0.0.1:{port}", block=True)
        sock.recv()
        end_warmup = time.monotonic() + warmup
        while time.monotonic() < end_warmup:
            sock.recv()
        print("measuring", flush=True)
        start, cpu_start = time.monotonic(), time.process_time()
        while time.monotonic() - start < duration:
            frame = sock.recv()
            now_ns = time.time_ns()
            record.latencies_ms.append((now_ns - frame_stamp_ns(frame)) / 1e6)
            record.bytes += len(frame)
        seconds, cpu_s = time.monotonic() - start, time.process_time() - cpu_start
    result = {
        "seconds": seconds,
        "receiver_cpu_cores": cpu_s / seconds,
        "topics": {RAW_TOPIC: summary(record, seconds)},
    }
    write_result(out, result)
    print("done", flush=True)
    return 0


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("role", choices=["rospy-pub", "pynng-send", "pynng-recv"])
    parser.add_argument("--kind", choices=["image", "cloud"], default="image")
    parser.add_argument("--rate", type=float, default=30.0)
    parser.add_argument("--port", type=int, default=0)
    parser.add_argument("--warmup", type=float, default=2.0)
    parser.add_argument("--duration", type=float, default=8.0)
    parser.add_argument("--out", default="")
    args, _ros_args = parser.parse_known_args(argv)
    if args.role == "rospy-pub":
        return rospy_pub(args.kind, args.rate)
    if args.role == "pynng-send":
        return pynng_send(args.kind, args.rate, args.port)
    return pynng_recv(args.port, args.warmup, args.duration, args.out)


if __name__ == "__main__":
    raise SystemExit(main())
