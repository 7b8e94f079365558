"""Benchmark of the headless server's sensor rendering on one core (not a test).

Prints the frame time of one 640x480 camera for each image type alone and for all seven types together
(`camera.render`: OpenGL unless AIRSIM_MAPPER_RENDERER=raycast; llvmpipe's threads count, so the CPU time
is that of all cores), and the time of one 10 Hz scan of a 100k points/s lidar, against the targets: all
seven types < 50 ms (20 Hz), one lidar scan < 100 ms (10 Hz).

    .venv/bin/python -m tools.bench.sim_render [--frames N] [--json]
"""

from __future__ import annotations

import os

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")  # one core, as the target says
os.environ.setdefault("OMP_NUM_THREADS", "1")

import argparse
import json
import time
from collections.abc import Callable

import numpy as np

from airsim_mapper.common.geometry import quat_from_rpy
from airsim_mapper.simserver.render.camera_model import RenderRequest
from airsim_mapper.simserver.render.rendering import render
from airsim_mapper.simserver.sensors.lidar_model import LidarModel
from airsim_mapper.simserver.world.world_file import load_world
from tools import render_timing

WIDTH, HEIGHT, FOV = 640, 480, 90.0
TYPE_NAMES = (
    "scene",
    "depth_planar",
    "depth_perspective",
    "segmentation",
    "depth_vis",
    "disparity",
    "normals",
)
CAMERA_TARGET_MS, LIDAR_TARGET_MS = 50.0, 100.0
POSES = render_timing.POSES[:3]  # oblique view of the blocks, close to a wall, looking down at the pad
LIDAR = {
    "id": "bench_lidar",
    "number-of-channels": 16,
    "range": 100.0,
    "points-per-second": 100000,
    "horizontal-rotation-frequency": 10.0,
    "vertical-fov-upper-deg": 15.0,
    "vertical-fov-lower-deg": -45.0,
    "report-azimuth-elevation-range": True,
}


def cpu_ms(fn: Callable[[int], object], frames: int) -> float:
    """Median CPU time (ms) of `fn(i)` over `frames` calls: CPU time of this process, not wall time, so
    that other load on the machine does not count."""
    return render_timing.median_ms(fn, frames, time.process_time)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--frames", type=int, default=15, help="frames per measurement (default 15)")
    parser.add_argument("--json", action="store_true", help="print one JSON object instead of a table")
    args = parser.parse_args()
    world = load_world()

    def camera(types: list[int]) -> Callable[[int], object]:
        return lambda i: render(world, RenderRequest(*POSES[i % len(POSES)], WIDTH, HEIGHT, FOV, types))

    results: dict[str, float] = {}
    for kind, name in enumerate(TYPE_NAMES):
        results[f"camera_{name}_ms"] = cpu_ms(camera([kind]), args.frames)
    results["camera_all_seven_ms"] = cpu_ms(camera(list(range(7))), args.frames)
    model = LidarModel.from_config(LIDAR)
    position, orientation = np.array([0.0, 0.0, -4.0]), quat_from_rpy(0.0, 0.0, 0.0)
    results["lidar_scan_ms"] = cpu_ms(
        lambda i: model.scan(world, position, orientation, i * 100_000_000, (i + 1) * 100_000_000),
        args.frames,
    )
    results["lidar_points_per_scan"] = float(model.points_per_second / model.rotation_hz)
    if args.json:
        print(json.dumps({k: round(v, 2) for k, v in results.items()}))
        return
    load = os.getloadavg()[0]
    cores = os.cpu_count()
    print(f"CPU time per frame, median of {args.frames} frames (load average {load:.1f} on {cores} cores)")
    print(f"camera {WIDTH}x{HEIGHT}, fov {FOV:g} deg, {len(POSES)} poses in turn")
    for name in TYPE_NAMES:
        print(f"  {name:<20s} {results[f'camera_{name}_ms']:7.1f} ms")
    seven = results["camera_all_seven_ms"]
    verdict = "meets" if seven < CAMERA_TARGET_MS else "misses"
    target = f"{verdict} the {CAMERA_TARGET_MS:g} ms target for 20 Hz"
    print(f"  {'all seven together':<20s} {seven:7.1f} ms  ({target})")
    scan = results["lidar_scan_ms"]
    verdict = "meets" if scan < LIDAR_TARGET_MS else "misses"
    print(
        f"lidar 100k points/s at 10 Hz: {scan:.1f} ms per scan of "
        f"{results['lidar_points_per_scan']:.0f} points "
        f"({verdict} the {LIDAR_TARGET_MS:g} ms target)"
    )


if __name__ == "__main__":
    main()
