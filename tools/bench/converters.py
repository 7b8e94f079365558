"""Micro-benchmark of the converters' hot paths (not a test): prints per-message times.

Run: .venv/bin/python -m tools.bench.converters [--repeat N]
"""

from __future__ import annotations

import argparse
import io
import statistics
import time
from collections.abc import Callable
from typing import Any

import numpy as np

from airsim_mapper.convert import registry
from airsim_mapper.convert.context import ConvertContext

W, H = 1920, 1080
POINTS = 100_000


def measure(fn: Callable[[], Any], repeat: int) -> tuple[float, float]:
    """(median, min) wall time in milliseconds over `repeat` calls after one warm-up call."""
    fn()
    times = []
    for _ in range(repeat):
        start = time.perf_counter()
        fn()
        times.append((time.perf_counter() - start) * 1e3)
    return statistics.median(times), min(times)


def cases() -> list[tuple[str, str, Any, ConvertContext]]:
    rng = np.random.default_rng(0)
    ctx = ConvertContext(frame_id="bench")
    bgr = {"time_stamp": 1, "width": W, "height": H, "encoding": "BGR", "data": bytes(W * H * 3)}
    depth = (rng.random(W * H) * 100).astype("<f2")
    depth16 = {"time_stamp": 1, "width": W, "height": H, "encoding": "16FC1", "data": depth.tobytes()}
    xyz = rng.normal(size=3 * POINTS).astype(np.float32)
    intensity = rng.random(POINTS).astype(np.float32)
    segmentation = rng.integers(0, 255, POINTS).astype(np.int32)
    lidar_lists = {
        "time_stamp": 1,
        "point_cloud": xyz.tolist(),
        "intensity_cloud": intensity.tolist(),
        "segmentation_cloud": segmentation.tolist(),
    }
    lidar_arrays = {
        "time_stamp": 1,
        "point_cloud": xyz,
        "intensity_cloud": intensity,
        "segmentation_cloud": segmentation,
    }
    detection = {"range": 10.0, "azimuth": 0.1, "elevation": 0.0, "velocity": 1.0, "rcs_sqm": 2.0}
    detections = [dict(detection) for _ in range(1000)]
    pose = {
        "time_stamp": 1,
        "position": {"x": 1, "y": 2, "z": 3},
        "orientation": {"w": 1, "x": 0, "y": 0, "z": 0},
    }
    enu = ConvertContext(frame_id="bench", convention="enu")
    return [
        ("image BGR 1920x1080 (no copy)", "image", bgr, ctx),
        ("image 16FC1 1920x1080 -> 32FC1", "image", depth16, ctx),
        ("camera_info 1920x1080 (cached)", "camera_info", bgr, ctx),
        ("pointcloud 100k points (lists)", "pointcloud", lidar_lists, ctx),
        ("pointcloud 100k points (arrays)", "pointcloud", lidar_arrays, ctx),
        ("pointcloud 100k points (arrays, ENU)", "pointcloud", lidar_arrays, enu),
        ("radar_scan 1000 detections", "radar_scan", {"time_stamp": 1, "radar_detections": detections}, ctx),
        ("pose (ENU)", "pose", pose, enu),
    ]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--repeat", type=int, default=20)
    args = parser.parse_args()
    print(f"{'case':40s} {'convert median':>15s} {'min':>9s} {'serialise':>11s}")
    for label, name, msg, ctx in cases():
        convert = registry.get(name)
        median, best = measure(lambda convert=convert, msg=msg, ctx=ctx: convert(msg, ctx), args.repeat)
        out = convert(msg, ctx)
        serial, _ = measure(lambda out=out: out.serialize(io.BytesIO()), max(3, args.repeat // 4))
        print(f"{label:40s} {median:12.3f} ms {best:6.3f} ms {serial:8.3f} ms")


if __name__ == "__main__":
    main()
