"""Which engine renders the headless server's cameras: OpenGL (moderngl on EGL) or Embree (embreex)?

A one-off measurement behind docs/rendering.md, on the built-in world at 1280x720, four poses in turn:
- embree: the world tessellated (boxes 12 triangles; spheres as UV spheres of `--sphere-segments`; the
  ground two large triangles), one `rtcIntersect` of every pixel's ray, then the numpy work that only
  turns hits into a scene image (per-pixel normal lookup, Lambert, checker, haze) as camera_model.py does;
- gl: `gl_renderer` for the scene image and for all seven types (hits, shading, encodings, read back);
- raycast: `raycast_renderer.render_raycast`, the numpy reference.
Wall ms per render, median. embreex is not a project dependency: `pip install embreex==4.4.0.post1`.

    .venv/bin/python -m tools.render_probe [--renders N] [--sphere-segments N]
"""

from __future__ import annotations

import argparse
from collections.abc import Callable

import numpy as np

from airsim_mapper.common.geometry import quat_to_matrix
from airsim_mapper.simserver.render import camera_model, gl_renderer, raycast_renderer
from airsim_mapper.simserver.render.camera_model import RenderRequest
from airsim_mapper.simserver.world.world import World
from airsim_mapper.simserver.world.world_file import load_world
from tools.render_timing import POSES, median_ms

WIDTH, HEIGHT, FOV = 1280, 720, 90.0


def triangles(world: World, segments: int) -> tuple[np.ndarray, np.ndarray]:
    """(T, 3, 3) float32 triangles of the world and (T,) int32 owner (-1 ground, else object index)."""
    tris, owner = [[[-1e5, -1e5, 0.0], [1e5, -1e5, 0.0], [-1e5, 1e5, 0.0]]], [-1]
    tris.append([[1e5, -1e5, 0.0], [1e5, 1e5, 0.0], [-1e5, 1e5, 0.0]])
    owner.append(-1)
    for i, obj in enumerate(world.objects):
        if obj.shape == "box":
            cube = gl_renderer._cube(  # the GL renderer's own box tessellation
                np.asarray(obj.center, float),
                np.array(
                    [[np.cos(obj.yaw), np.sin(obj.yaw), 0], [-np.sin(obj.yaw), np.cos(obj.yaw), 0], [0, 0, 1]]
                ),
                np.asarray(obj.size, float) / 2,
            )
            points = [p for _, p in cube]
            tris += [points[k : k + 3] for k in range(0, len(points), 3)]
            owner += [i] * (len(points) // 3)
        else:
            r, c = obj.size[0] / 2, np.asarray(obj.center, float)
            theta = np.linspace(0, np.pi, segments + 1)
            phi = np.linspace(0, 2 * np.pi, 2 * segments + 1)
            grid = c + r * np.stack(
                [np.outer(np.sin(theta), np.cos(phi)), np.outer(np.sin(theta), np.sin(phi)),
                 np.outer(np.cos(theta), np.ones_like(phi))], -1
            )  # fmt: skip
            for a in range(segments):
                for b in range(2 * segments):
                    tris += [[grid[a, b], grid[a + 1, b], grid[a + 1, b + 1]]]
                    tris += [[grid[a, b], grid[a + 1, b + 1], grid[a, b + 1]]]
                    owner += [i, i]
    return np.asarray(tris, dtype=np.float32), np.asarray(owner, dtype=np.int32)


def embree_scene_render(world: World, segments: int) -> Callable[[int], object]:
    from embreex import rtcore_scene
    from embreex.mesh_construction import TriangleMesh

    tris, owner = triangles(world, segments)
    scene = rtcore_scene.EmbreeScene()
    TriangleMesh(scene, tris)
    rays = camera_model.camera_rays(WIDTH, HEIGHT, FOV)
    colours = world.colors_of(owner).T  # (T, 3)
    sun = (camera_model.SUN_DIRECTION / np.linalg.norm(camera_model.SUN_DIRECTION)).astype(np.float32)
    sky = np.asarray(world.sky_color_bgr, np.float32)

    def render(i: int) -> bytes:
        position, orientation = POSES[i % len(POSES)]
        dirs = np.ascontiguousarray((quat_to_matrix(orientation).astype(np.float32) @ rays).T)
        origins = np.broadcast_to(np.asarray(position, np.float32), dirs.shape).copy()
        hits = scene.run(origins, dirs, output=1)
        prim, t, normal = hits["primID"], hits["tfar"], hits["Ng"]
        hit = prim >= 0
        t = np.where(hit, t, np.inf)
        normal /= np.linalg.norm(normal, axis=1, keepdims=True) + 1e-12
        light = camera_model._AMBIENT + (1 - camera_model._AMBIENT) * np.clip(np.abs(normal @ sun), 0, 1)
        shade = colours[np.maximum(prim, 0)] * light[:, None]
        d = np.minimum(t, 1e30).astype(np.float32)
        point = origins + dirs * np.where(hit, d, 0)[:, None]
        odd = ((np.floor(point[:, 0] / 2) + np.floor(point[:, 1] / 2)).astype(np.int64) & 1).astype(bool)
        haze = d / (d + 1500.0)
        keep = (1 - haze) * np.where(odd & (owner[np.maximum(prim, 0)] == -1), 0.85, 1.0)
        return (shade * keep[:, None] + sky * haze[:, None]).astype(np.uint8).tobytes()

    return render


def embree_hits(world: World, segments: int) -> Callable[[int], object]:
    """One intersection query of every pixel's ray (embreex traces them one by one, on one thread)."""
    from embreex import rtcore_scene
    from embreex.mesh_construction import TriangleMesh

    scene = rtcore_scene.EmbreeScene()
    TriangleMesh(scene, triangles(world, segments)[0])
    rays = camera_model.camera_rays(WIDTH, HEIGHT, FOV)

    def hits(i: int) -> object:
        position, orientation = POSES[i % len(POSES)]
        dirs = np.ascontiguousarray((quat_to_matrix(orientation).astype(np.float32) @ rays).T)
        return scene.run(np.broadcast_to(np.asarray(position, np.float32), dirs.shape).copy(), dirs, output=1)

    return hits


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--renders", type=int, default=20)
    parser.add_argument("--sphere-segments", type=int, default=32)
    args = parser.parse_args()
    from airsim_mapper.common.tuning import limit_blas_threads

    limit_blas_threads(1)
    world = load_world()
    gl = gl_renderer.renderer()

    def gl_types(types: list[int]) -> Callable[[int], object]:
        return lambda i: gl.render(world, RenderRequest(*POSES[i % len(POSES)], WIDTH, HEIGHT, FOV, types))

    rows = {
        "embree: hits only": median_ms(embree_hits(world, args.sphere_segments), args.renders),
        "embree: hits + numpy scene shading": median_ms(
            embree_scene_render(world, args.sphere_segments), args.renders
        ),
        "gl: scene image": median_ms(gl_types([camera_model.SCENE]), args.renders),
        "gl: all seven types": median_ms(gl_types(list(camera_model.IMAGE_TYPES)), args.renders),
        "raycast: scene image": median_ms(
            lambda i: raycast_renderer.render_raycast(
                world, RenderRequest(*POSES[i % len(POSES)], WIDTH, HEIGHT, FOV, [0])
            ),
            5,
        ),
    }
    print(f"{WIDTH}x{HEIGHT}, median wall ms per render ({gl.description})")
    for name, ms in rows.items():
        print(f"  {name:<40s} {ms:7.1f} ms  {1e3 / ms:6.1f}/s")


if __name__ == "__main__":
    main()
