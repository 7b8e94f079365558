"""The headless server's own camera frame times: one camera, all seven image types, as the server runs it.

Builds the server's camera path in this process: a loaded scene (`Session`) whose robot has one camera
capturing the seven image types at WIDTH x HEIGHT every 1/HZ s, the render worker (a child process at
nice +10, as the server starts it) and the topics channel, with a subscriber on the seven image topics
reading every frame off the socket in a thread. It then runs the server's camera thread loop
(`Session.camera_tick`) for `seconds` of wall time and reports, per capture, the render (worker round
trip) and the rest (encoding, messages, the topic cache and the sender queue), and the rates: captures
made and frames delivered per second, per topic.

    .venv/bin/python -m tools.camera_probe [--seconds 8] [--hz 30] [--json]
"""

from __future__ import annotations

import argparse
import json
import os
import socket
import statistics
import threading
import time
from collections import Counter
from pathlib import Path
from typing import Any

import pynng

from airsim_mapper.simserver.render.camera_model import IMAGE_TYPES
from airsim_mapper.simserver.render.render_worker import RENDER_NICE, RenderWorker
from airsim_mapper.simserver.scene.config import IMAGE_TYPE_NAMES, parse_scene
from airsim_mapper.simserver.session import Session
from airsim_mapper.simserver.wire import protocol
from airsim_mapper.simserver.wire.topics import TopicHub
from airsim_mapper.simserver.world.world_file import load_world

WIDTH, HEIGHT, HZ = 1280, 720, 30.0
TARGET_HZ = 30.0  # target: all seven types of one 1280x720 camera at 30 Hz on 2 cores (llvmpipe)


def probe_scene(width: int, height: int, hz: float) -> dict[str, Any]:
    """A scene with one drone at 4 m whose camera looks ahead and down over the blocks, all seven types."""
    captures = [
        {
            "image-type": t,
            "width": width,
            "height": height,
            "fov-degrees": 90,
            "capture-enabled": True,
            "streaming-enabled": False,
            "pixels-as-float": False,
            "compress": False,
        }
        for t in IMAGE_TYPES
    ]
    camera = {
        "id": "Cam",
        "type": "camera",
        "enabled": True,
        "parent-link": "Frame",
        "capture-interval": 1.0 / hz,
        "origin": {"xyz": "0 0 0", "rpy-deg": "0 -20 30"},
        "capture-settings": captures,
    }
    robot = {"physics-type": "fast-physics", "controller": {"type": "simple-flight-api"}, "sensors": [camera]}
    actor = {"type": "robot", "name": "Drone1", "origin": {"xyz": "0 0 -4", "rpy-deg": "0 0 0"}}
    return {
        "id": "SceneCameraProbe",
        "actors": [{**actor, "robot-config": robot}],
        "clock": {"type": "steppable"},
    }


def free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def frame_topic(raw: bytes) -> str:
    """The topic of a server frame (array of 3: fixint type, topic as raw str, body) without its body."""
    marker = raw[2]
    if marker & 0xE0 == 0xA0:
        start, size = 3, marker & 0x1F
    elif marker == 0xDA:
        start, size = 5, int.from_bytes(raw[3:5], "big")
    else:
        raise ValueError(f"unexpected topic marker 0x{marker:02x}")
    return raw[start : start + size].decode()


class Drain:
    """A topics client that subscribes to `paths` and counts every frame it reads, per topic."""

    def __init__(self, port: int, paths: list[str]) -> None:
        self.counts: Counter[str] = Counter()
        self.bytes = 0
        self._socket = pynng.Pair0(dial=f"tcp://127.0.0.1:{port}", recv_timeout=200)
        for path in paths:
            self._socket.send(protocol.encode_frame(path, b"", protocol.FrameType.SUBSCRIBE))
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._run, name="drain", daemon=True)
        self._thread.start()

    def _run(self) -> None:
        while not self._stop.is_set():
            try:
                raw = self._socket.recv()
            except pynng.Timeout:
                continue
            except pynng.Closed:
                return
            self.counts[frame_topic(raw)] += 1  # the body is not decoded: that is the client's cost
            self.bytes += len(raw)

    def close(self) -> None:
        self._stop.set()
        self._socket.close()
        self._thread.join(timeout=2.0)


def cpu_seconds(pid: int) -> float:
    """User + system CPU seconds of a process (all its threads) so far."""
    fields = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()
    return (int(fields[11]) + int(fields[12])) / os.sysconf("SC_CLK_TCK")


def run(
    seconds: float = 8.0, hz: float = HZ, width: int = WIDTH, height: int = HEIGHT, nice: int = RENDER_NICE
) -> dict[str, Any]:
    """Frame times (ms) and rates (Hz) of the server's camera path over `seconds` after a 2 s warm-up,
    and the CPU time per capture of the server (this process: camera loop, sender, and the subscriber's
    reading) and of the render worker (llvmpipe's threads included), which a busy machine does not
    change as it changes the wall times."""
    world = load_world()
    worker = RenderWorker(world, nice)
    render_ms: list[float] = []

    def timed_render(request):
        start = time.perf_counter()
        try:
            return worker.render(request)
        finally:
            render_ms.append((time.perf_counter() - start) * 1e3)

    port = free_port()
    hub = TopicHub("127.0.0.1", port)
    hub.start()
    session = Session(parse_scene(json.dumps(probe_scene(width, height, hz))), world, hub, timed_render)
    hub.set_table(session.topics(), session.topic_handlers())
    session.start()
    camera = next(iter(session.robots["Drone1"].cameras.values()))
    paths = [camera.topic(t) for t in IMAGE_TYPES]
    drain = Drain(port, paths)
    frame_ms: list[float] = []
    try:
        deadline = time.monotonic() + 2.0  # warm-up: the worker starts, the subscriptions arrive
        while time.monotonic() < deadline:
            session.camera_tick()
            time.sleep(0.002)
        render_ms.clear()
        drain.counts.clear()
        captures = 0
        worker_pid = worker.pid
        cpu_start = time.process_time(), cpu_seconds(worker_pid) if worker_pid else 0.0
        started = time.monotonic()
        while time.monotonic() - started < seconds:
            t0 = time.perf_counter()
            if session.camera_tick():
                frame_ms.append((time.perf_counter() - t0) * 1e3)
                captures += 1
            else:
                time.sleep(0.002)  # the server's camera thread waits about this long when nothing is due
        elapsed = time.monotonic() - started
        server_cpu = time.process_time() - cpu_start[0]
        worker_cpu = cpu_seconds(worker_pid) - cpu_start[1] if worker_pid else 0.0
        hub.flush(2.0)
        delivered = {IMAGE_TYPE_NAMES[t]: drain.counts[camera.topic(t)] / elapsed for t in IMAGE_TYPES}
    finally:
        drain.close()
        session.stop()
        hub.stop()
        worker.close()
    rest = [f - r for f, r in zip(frame_ms, render_ms)]
    return {
        "width": width,
        "height": height,
        "requested_hz": hz,
        "captures_per_s": captures / elapsed,
        "frame_ms_p50": statistics.median(frame_ms) if frame_ms else None,
        "frame_ms_p90": statistics.quantiles(frame_ms, n=10)[-1] if len(frame_ms) >= 10 else None,
        "render_ms_p50": statistics.median(render_ms) if render_ms else None,
        "rest_ms_p50": statistics.median(rest) if rest else None,
        "server_cpu_ms_per_capture": server_cpu * 1e3 / max(captures, 1),
        "worker_cpu_ms_per_capture": worker_cpu * 1e3 / max(captures, 1),
        "delivered_hz": delivered,
        "delivered_min_hz": min(delivered.values()),
    }


def _ms(value: float | None) -> str:
    return "-" if value is None else f"{value:.1f} ms"


def table(result: dict[str, Any]) -> str:
    lines = [
        f"server camera, all seven types {result['width']}x{result['height']} at "
        f"{result['requested_hz']:g} Hz (render worker + topics channel, in one process):",
        f"  captures/s {result['captures_per_s']:.1f}; frame p50 {_ms(result['frame_ms_p50'])} "
        f"(render {_ms(result['render_ms_p50'])}, rest {_ms(result['rest_ms_p50'])}), p90 "
        f"{_ms(result['frame_ms_p90'])}",
        f"  CPU per capture: server {result['server_cpu_ms_per_capture']:.1f} ms, render worker "
        f"{result['worker_cpu_ms_per_capture']:.1f} ms",
        "  delivered Hz: " + ", ".join(f"{k} {v:.1f}" for k, v in result["delivered_hz"].items()),
    ]
    return "\n".join(lines)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seconds", type=float, default=8.0)
    parser.add_argument("--hz", type=float, default=HZ)
    parser.add_argument("--nice", type=int, default=RENDER_NICE, help="the render worker's nice increment")
    parser.add_argument("--json", action="store_true", help="print one JSON object instead of a table")
    args = parser.parse_args()
    result = run(args.seconds, args.hz, nice=args.nice)
    print(json.dumps(result, indent=1) if args.json else table(result))


if __name__ == "__main__":
    main()
