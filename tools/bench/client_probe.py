"""Pose delivery through the bare 1.1.0 client under camera load, with and without fast frames (no ROS).

All topics share one Pair0 connection, so a pose frame waits behind every image frame queued before it,
and the client's single receive thread decodes each one: the faster that thread frees the socket, the
sooner the pose behind it arrives. This measures exactly that, without the bridge and without ROS:
pose rate and latency (receive time - stamp, real-time clock) idle, then with a 1080p camera subscribed.

    python -m tools.bench.client_probe --topicsport P --servicesport Q --simconfigpath DIR
        --scene FILE --pose TOPIC --camera TOPIC --out result.json [--fast-frames] [--seconds S]
"""

from __future__ import annotations

import argparse
import json
import threading
import time
from typing import Any

import numpy as np


class Arrivals:
    def __init__(self) -> None:
        self.lock = threading.Lock()
        self.samples: list[tuple[float, int]] = []

    def add(self, stamp_ns: int) -> None:
        with self.lock:
            self.samples.append((time.time(), stamp_ns))

    def between(self, start: float, end: float) -> dict[str, Any]:
        with self.lock:
            window = [(t, s) for t, s in self.samples if start <= t < end]
        latency = np.array([(t - s / 1e9) * 1e3 for t, s in window]) if window else np.zeros(0)
        out: dict[str, Any] = {"rate_hz": len(window) / (end - start)}
        if latency.size:
            out.update(
                latency_p50_ms=float(np.percentile(latency, 50)),
                latency_p99_ms=float(np.percentile(latency, 99)),
            )
        return out


def main(argv: list[str] | None = None) -> int:
    from projectairsim import ProjectAirSimClient, World

    from tools.bench.recv_proxy import install

    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--topicsport", type=int, required=True)
    parser.add_argument("--servicesport", type=int, required=True)
    parser.add_argument("--simconfigpath", required=True)
    parser.add_argument("--scene", required=True)
    parser.add_argument("--pose", required=True)
    parser.add_argument("--camera", required=True)
    parser.add_argument("--out", required=True)
    parser.add_argument("--fast-frames", action="store_true")
    parser.add_argument("--seconds", type=float, default=5.0)
    args = parser.parse_args(argv)
    client = ProjectAirSimClient("127.0.0.1", args.topicsport, args.servicesport)
    client.connect()
    try:
        fast = install(client, lambda topic: topic == args.camera) if args.fast_frames else None
        World(client, args.scene, sim_config_path=args.simconfigpath.rstrip("/") + "/")
        poses, images = Arrivals(), Arrivals()
        client.subscribe(args.pose, lambda _t, m: poses.add(m["time_stamp"]))
        time.sleep(1.0)
        idle_start = time.time()
        time.sleep(args.seconds)
        idle_end = time.time()

        def on_image(_topic: Any, message: Any) -> None:
            images.add((fast.resolve(message) if fast else message)["time_stamp"])

        client.subscribe(args.camera, on_image)
        time.sleep(1.0)
        load_start = time.time()
        time.sleep(args.seconds)
        load_end = time.time()
        result = {
            "fast_frames": args.fast_frames,
            "pose_idle": poses.between(idle_start, idle_end),
            "pose_load": poses.between(load_start, load_end),
            "camera_load": images.between(load_start, load_end),
        }
    finally:
        client.disconnect()
    with open(args.out, "w") as handle:
        json.dump(result, handle)
    print("done", flush=True)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
