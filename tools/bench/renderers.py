"""Camera renders per second of the headless server's two renderers, side by side in one process.

The OpenGL renderer (`gl_renderer`, llvmpipe without a GPU) and the numpy ray caster (`raycast_renderer`)
render the same camera poses over the built-in world, one render after another in this process, as the
render worker does: 1280x720 scene, all seven types at 1280x720, 1920x1080 scene. Renders per second are
1 / the median wall time of one render (the figure that bounds a camera's rate); CPU time per render is
reported beside it (llvmpipe renders on as many threads as there are cores).

    .venv/bin/python -m tools.bench.renderers [--json]
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import time
from collections.abc import Callable
from typing import Any

from airsim_mapper.simserver.render import camera_model, gl_renderer, raycast_renderer
from airsim_mapper.simserver.render.camera_model import RenderRequest
from airsim_mapper.simserver.world.world_file import load_world
from tools.bench import tables
from tools.render_timing import POSES

CASES = {  # name: (width, height, image types)
    "scene 1280x720": (1280, 720, (camera_model.SCENE,)),
    "all seven 1280x720": (1280, 720, camera_model.IMAGE_TYPES),
    "scene 1920x1080": (1920, 1080, (camera_model.SCENE,)),
}
TARGETS = {"scene 1280x720": 60.0, "all seven 1280x720": 30.0, "scene 1920x1080": 30.0}  # renders/s, GL
FOV = 90.0
GL_RENDERS, RAYCAST_RENDERS = 40, 6  # per case; the ray caster takes 0.1-0.3 s a render


def measure(fn: Callable[[int], object], renders: int) -> dict[str, float]:
    """Median wall and CPU ms of `fn(i)` over `renders` calls after two warm-up calls."""
    fn(0)
    fn(1)
    wall, cpu = [], []
    for i in range(renders):
        w, c = time.perf_counter(), time.process_time()
        fn(i)
        wall.append((time.perf_counter() - w) * 1e3)
        cpu.append((time.process_time() - c) * 1e3)
    median = statistics.median(wall)
    return {"renders_per_s": 1e3 / median, "wall_ms": median, "cpu_ms": statistics.median(cpu)}


def run(gl_renders: int = GL_RENDERS, raycast_renders: int = RAYCAST_RENDERS) -> dict[str, Any]:
    """{"gl": {case: figures}, "raycast": {case: figures}, "gl_renderer": description} (GL errors kept)."""
    from airsim_mapper.common.tuning import limit_blas_threads

    limit_blas_threads(1)  # as in the render worker: the ray caster's products are small
    world = load_world()
    out: dict[str, Any] = {"gl": {}, "raycast": {}}
    try:
        gl = gl_renderer.renderer()
        out["gl_renderer"] = gl.description
    except gl_renderer.GLUnavailable as exc:
        gl = None
        out["gl_error"] = str(exc)
    for name, (width, height, types) in CASES.items():

        def call(render: Callable[..., object], size=(width, height), types=types) -> Callable[[int], object]:
            return lambda i: render(world, RenderRequest(*POSES[i % len(POSES)], *size, FOV, list(types)))

        if gl is not None:
            out["gl"][name] = measure(call(gl.render), gl_renders)
        out["raycast"][name] = measure(call(raycast_renderer.render_raycast), raycast_renders)
    return out


def table(results: dict[str, Any]) -> str:
    rows = []
    for name in CASES:
        gl, ray = results["gl"].get(name), results["raycast"][name]
        rows.append(
            [
                name,
                "-" if gl is None else f"{gl['renders_per_s']:.1f}",
                "-" if gl is None else f"{gl['cpu_ms']:.1f}",
                f"{ray['renders_per_s']:.1f}",
                f"{ray['cpu_ms']:.1f}",
                "-" if gl is None else f"{gl['renders_per_s'] / ray['renders_per_s']:.1f}x",
                f">= {TARGETS[name]:g}",
            ]
        )
    header = [
        "camera render, one process",
        "GL /s",
        "GL CPU ms",
        "raycast /s",
        "raycast CPU ms",
        "GL/raycast",
    ]
    note = f"GL: {results.get('gl_renderer') or results.get('gl_error')}; {os.cpu_count()} cores"
    return tables.table([*header, "target /s"], rows) + "\n" + note


def targets(results: dict[str, Any]) -> list[tuple[str, float | None, float]]:
    """(target name, GL renders/s or None, limit) per case."""
    gl = results["gl"]
    return [
        (f"camera {name}, GL renders/s in one process", gl.get(name, {}).get("renders_per_s"), limit)
        for name, limit in TARGETS.items()
    ]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--json", action="store_true", help="print one JSON object instead of a table")
    args = parser.parse_args()
    results = run()
    print(json.dumps(results, indent=1) if args.json else table(results))


if __name__ == "__main__":
    main()
