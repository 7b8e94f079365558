"""The OpenGL renderer against the ray caster (the reference), pixel by pixel, for all seven image types.

Fixed scenes: the built-in world and a test world with yawed boxes, a sphere half under the ground and a
sphere around one camera, seen from poses that look at walls, edges, the ground, the horizon and the sky,
and from inside a box and a sphere (surfaces are one-sided). A pixel agrees when:
- depth (16FC1): both are +inf, or both are finite and within 1 cm or one float16 step of each other;
- segmentation, and scene and surface normals on flat surfaces (boxes, ground, sky): the same bytes;
- depth vis, disparity, and scene and normals on spheres (shaded per pixel): within 1 per channel (float32
  rounding before the truncation to 8 bits).
Pixels on a silhouette edge, a checker line or the far horizon may see something else in float32 than the
ray caster saw in its arithmetic: at most `EDGE_FRACTION` of an image may disagree, and every pixel away
from any edge (its 3x3 neighbourhood one surface, nearer than `FAR_M`) must agree.

No skip: without EGL these tests fail loudly (`make setup` installs Mesa's EGL).
"""

from __future__ import annotations

import logging
import math
import threading

import numpy as np
import pytest

from airsim_mapper.common.geometry import quat_from_rpy, quat_to_matrix
from airsim_mapper.simserver.render import camera_model, gl_renderer, raycast_renderer, rendering
from airsim_mapper.simserver.render.camera_model import RenderRequest
from airsim_mapper.simserver.world.world import World
from airsim_mapper.simserver.world.world_file import load_world, world_from_dict

EDGE_FRACTION = 0.005  # of an image's pixels: edges may disagree, nothing else
FAR_M = 200.0  # beyond this the horizon's grazing rays amplify float32 rounding; only the fraction applies
WIDTH, HEIGHT, FOV = 320, 240, 80.0

TEST_WORLD = {
    "ground": {"segmentation-id": 3, "color-bgr": [60, 120, 80]},
    "sky": {"color-bgr": [230, 200, 140]},
    "objects": [
        {"name": "Wall", "shape": "box", "center": [12.0, 1.3, -4.0], "size": [2.0, 9.0, 8.0],
         "yaw-deg": 17.0, "segmentation-id": 40, "color-bgr": [200, 120, 40]},
        {"name": "Crate", "shape": "box", "center": [6.0, -5.0, -1.0], "size": [2.0, 2.0, 2.0],
         "yaw-deg": -35.0, "segmentation-id": 41, "color-bgr": [40, 90, 210]},
        {"name": "Buried", "shape": "sphere", "center": [8.0, 5.0, 0.0], "radius": 2.5,
         "segmentation-id": 42, "color-bgr": [0, 140, 255]},
        {"name": "Bubble", "shape": "sphere", "center": [-20.0, 0.0, -3.0], "radius": 3.0,
         "segmentation-id": 43, "color-bgr": [180, 60, 180]},
        {"name": "Roof", "shape": "box", "center": [-20.0, 20.0, -6.0], "size": [10.0, 10.0, 0.5],
         "segmentation-id": 44, "color-bgr": [90, 90, 90]},
    ],
}  # fmt: skip

POSES = {  # name: (world, position, roll, pitch, yaw)
    "default oblique": ("default", (0.0, 0.0, -4.0), 0.0, -0.2, 0.6),
    "default wall": ("default", (21.3, 0.7, -4.3), 0.0, 0.03, 0.02),
    "default down": ("default", (0.4, -0.3, -4.0), 0.0, -math.pi / 2 + 0.01, 0.2),
    "default ball": ("default", (14.2, 13.9, -3.5), 0.0, -0.05, math.pi / 4 + 0.01),
    "default sky": ("default", (0.0, 0.0, -5.0), 0.0, math.pi / 2 - 0.01, 0.0),
    "test wall and crate": ("test", (0.2, 0.1, -2.0), 0.05, -0.1, -0.15),
    "test buried sphere": ("test", (1.0, 4.0, -1.5), 0.0, -0.15, 0.1),
    "test rolled horizon": ("test", (0.0, 0.0, -10.0), 0.4, -0.05, 0.7),
    "test inside the bubble": ("test", (-20.0, 0.0, -3.0), 0.0, 0.0, 0.3),
    "test inside the wall": ("test", (12.0, 1.3, -4.0), 0.0, -0.1, 0.0),
    "test under the roof": ("test", (-21.0, 19.0, -2.0), 0.0, math.pi / 3, 0.4),
}


@pytest.fixture(scope="module")
def worlds() -> dict[str, World]:
    gl_renderer.renderer()  # no skip: without EGL this fails loudly (`make setup` installs it)
    return {"default": load_world(), "test": world_from_dict(TEST_WORLD, "<test world>")}


def pixels(image: camera_model.RenderedImage) -> np.ndarray:
    if image.encoding == "16FC1":
        return np.frombuffer(image.data, dtype="<f2").reshape(image.height, image.width).astype(np.float32)
    return np.frombuffer(image.data, dtype=np.uint8).reshape(image.height, image.width, 3).astype(np.int16)


def interior(segmentation: np.ndarray, depth: np.ndarray, cells: np.ndarray) -> np.ndarray:
    """Pixels whose 3x3 neighbourhood shows one surface (one segment colour and one ground checker cell),
    nearer than FAR_M, or sky."""
    code = (segmentation[..., 0] * 65536 + segmentation[..., 1] * 256 + segmentation[..., 2]) * 4 + cells
    padded = np.pad(code, 1, mode="edge")
    same = np.ones(code.shape, dtype=bool)
    for dy in (-1, 0, 1):
        for dx in (-1, 0, 1):
            same &= padded[1 + dy : 1 + dy + code.shape[0], 1 + dx : 1 + dx + code.shape[1]] == code
    return same & ((depth < FAR_M) | np.isinf(depth))


def checker_cells(position, orientation, depth: np.ndarray) -> np.ndarray:
    """(H, W) 0-3: the 2 m ground cell (x and y parity) each pixel's hit lies in (float64), 0 for the sky."""
    rays = quat_to_matrix(orientation) @ camera_model.camera_rays(WIDTH, HEIGHT, FOV).astype(np.float64)
    with np.errstate(invalid="ignore"):
        hit = np.asarray(position, float)[:, None] + rays * depth.astype(np.float64).ravel()
        cell = np.floor(np.nan_to_num(hit[:2] / 2.0, posinf=0.0, neginf=0.0)).astype(np.int64) & 1
    return (cell[0] * 2 + cell[1]).reshape(depth.shape)


def agreement(kind: int, gl: np.ndarray, ray: np.ndarray, flat: np.ndarray) -> np.ndarray:
    """Per pixel: does the GL pixel agree with the ray caster's (rules in the module docstring)?"""
    if kind in camera_model.DEPTH_TYPES:
        both_inf = np.isinf(gl) & np.isinf(ray)
        finite = np.isfinite(gl) & np.isfinite(ray)
        with np.errstate(invalid="ignore", over="ignore"):
            step = np.spacing(np.maximum(np.abs(ray), np.abs(gl)).astype(np.float16)).astype(np.float32)
            close = np.abs(gl - ray) <= np.maximum(0.01, step)
        return both_inf | (finite & close)
    diff = np.abs(gl - ray).max(axis=2)
    if kind == camera_model.SEGMENTATION:
        return diff == 0
    if kind in (camera_model.SCENE, camera_model.SURFACE_NORMALS):
        return np.where(flat, diff == 0, diff <= 1)
    return diff <= 1  # depth vis, disparity


@pytest.mark.parametrize("pose", list(POSES))
def test_every_image_type_matches_the_ray_caster_pixel_by_pixel(worlds, pose):
    world_name, position, roll, pitch, yaw = POSES[pose]
    world = worlds[world_name]
    args = (
        np.array(position),
        quat_from_rpy(roll, pitch, yaw),
        WIDTH,
        HEIGHT,
        FOV,
        list(camera_model.IMAGE_TYPES),
    )
    gl = {k: pixels(v) for k, v in gl_renderer.render(world, RenderRequest(*args)).items()}
    ray = {k: pixels(v) for k, v in raycast_renderer.render_raycast(world, RenderRequest(*args)).items()}
    seg, depth = ray[camera_model.SEGMENTATION], ray[camera_model.DEPTH_PERSPECTIVE]
    sphere_ids = [o.segmentation_id for o in world.objects if o.shape == "sphere"]
    on_sphere = np.zeros(depth.shape, dtype=bool)
    for i in sphere_ids:
        on_sphere |= (seg == camera_model.segmentation_color(i)).all(axis=2)
    inside = interior(seg, depth, checker_cells(args[0], args[1], depth))
    for kind in camera_model.IMAGE_TYPES:
        agrees = agreement(kind, gl[kind], ray[kind], ~on_sphere)
        fraction = 1.0 - agrees.mean()
        assert fraction <= EDGE_FRACTION, f"{pose}: type {kind}: {fraction:.2%} of the pixels differ"
        stray = np.argwhere(inside & ~agrees)
        assert stray.size == 0, (
            f"{pose}: type {kind}: pixels away from any edge differ, e.g. (row, col) {stray[:3]}"
        )


def test_the_poses_see_what_they_are_meant_to(worlds):
    """The fixed scenes do cover boxes, spheres, ground and sky, and the one-sided views see through."""
    seen = {}
    for pose, (world_name, position, roll, pitch, yaw) in POSES.items():
        world = worlds[world_name]
        args = (
            np.array(position),
            quat_from_rpy(roll, pitch, yaw),
            WIDTH,
            HEIGHT,
            FOV,
            [camera_model.SEGMENTATION],
        )
        seg = pixels(gl_renderer.render(world, RenderRequest(*args))[camera_model.SEGMENTATION])
        colours = {tuple(int(c) for c in p) for p in seg.reshape(-1, 3)[::7]}
        names = {
            o.name for o in world.objects if camera_model.segmentation_color(o.segmentation_id) in colours
        }
        if camera_model.segmentation_color(world.ground_segmentation_id) in colours:
            names.add("ground")
        if (0, 0, 0) in colours:
            names.add("sky")
        seen[pose] = names
    assert {"Wall", "Crate", "ground", "sky"} <= seen["test wall and crate"]
    assert {"Buried", "ground"} <= seen["test buried sphere"]
    assert "Bubble" not in seen["test inside the bubble"]  # a camera inside a sphere sees out of it
    assert "Wall" not in seen["test inside the wall"]
    assert seen["default sky"] == {"sky"}
    assert "OrangeBall" in seen["default ball"]


def test_render_falls_back_to_the_ray_caster_once_without_a_gl_context(monkeypatch, caplog):
    def unavailable() -> gl_renderer.GLRenderer:
        raise gl_renderer.GLUnavailable("cannot create an OpenGL context: no EGL here")

    world = load_world()
    args = (np.array([0.0, 0.0, -4.0]), quat_from_rpy(0.0, -0.3, 0.0), 32, 24, 90.0, [0, 1, 3])
    monkeypatch.setattr(gl_renderer, "renderer", unavailable)
    rendering.select_renderer("gl")
    try:
        with caplog.at_level(logging.ERROR, logger="airsim_mapper.simserver.rendering"):
            first = rendering.render(world, RenderRequest(*args))
            second = rendering.render(world, RenderRequest(*args))
        assert rendering.renderer_name() == "raycast"
    finally:
        rendering.select_renderer(None)
    want = raycast_renderer.render_raycast(world, RenderRequest(*args))
    assert first == want and second == want
    errors = [r.getMessage() for r in caplog.records]
    assert len(errors) == 1 and "no EGL here" in errors[0] and "ray caster" in errors[0]


def test_a_size_beyond_the_drivers_limit_is_ray_cast_with_a_warning_and_gl_goes_on(caplog):
    world = load_world()
    pose = (np.array([0.0, 0.0, -4.0]), quat_from_rpy(0.0, -0.3, 0.0))
    limit = gl_renderer.renderer().ctx.info["GL_MAX_RENDERBUFFER_SIZE"]
    rendering.select_renderer("gl")
    try:
        with caplog.at_level(logging.WARNING, logger="airsim_mapper.simserver.rendering"):
            wide = rendering.render(world, RenderRequest(*pose, limit + 1, 2, 90.0, [0, 1]))
        assert wide == raycast_renderer.render_raycast(
            world, RenderRequest(*pose, limit + 1, 2, 90.0, [0, 1])
        )
        assert f"OpenGL cannot render {limit + 1}x2" in caplog.text and "ray casting this one" in caplog.text
        assert rendering.renderer_name() == "gl"
        assert rendering.render(world, RenderRequest(*pose, 64, 48, 90.0, [0])) == gl_renderer.render(
            world, RenderRequest(*pose, 64, 48, 90.0, [0])
        )
    finally:
        rendering.select_renderer(None)


def test_the_renderer_is_chosen_by_the_environment(monkeypatch, caplog):
    try:
        for value, want in (("raycast", "raycast"), ("GL", "gl"), ("", "gl"), ("vulkan", "gl")):
            monkeypatch.setenv(rendering.RENDERER_ENV, value)
            rendering.select_renderer(None)
            assert rendering.renderer_name() == want
        assert "vulkan" in caplog.text
        with pytest.raises(camera_model.CameraError, match="unknown renderer 'vulkan'"):
            rendering.select_renderer("vulkan")
    finally:
        rendering.select_renderer(None)


def test_the_gl_renderer_keeps_one_context_and_reuses_its_resources(worlds):
    world = worlds["default"]
    gl = gl_renderer.renderer()
    assert gl_renderer.renderer() is gl
    assert gl.description  # "llvmpipe (LLVM ...), 4.5 (Core Profile) Mesa ..." here; a GPU's driver elsewhere
    for size in ((64, 48), (32, 24), (64, 48)):
        gl_renderer.render(
            world, RenderRequest(np.zeros(3) - [0, 0, 3], quat_from_rpy(0, 0, 0), *size, 90.0, [0, 2])
        )
    assert {(w, h) for w, h, _ in gl._framebuffers} >= {(64, 48), (32, 24)}
    assert len(gl._programs) >= 1 and len(gl._scenes) >= 1


def test_a_render_from_another_thread_gives_the_same_images(worlds):
    """The context is made current in whichever thread renders (the server's sensor thread, in process)."""
    args = (np.array([0.0, 0.0, -4.0]), quat_from_rpy(0.0, -0.2, 0.6), 64, 48, 90.0, [0, 2, 3])
    here = gl_renderer.render(worlds["default"], RenderRequest(*args))
    there: dict[str, object] = {}
    world = worlds["default"]
    thread = threading.Thread(
        target=lambda: there.update(images=gl_renderer.render(world, RenderRequest(*args)))
    )
    thread.start()
    thread.join()
    assert there["images"] == here


@pytest.mark.parametrize(
    ("width", "height", "fov"), [(1, 1, 90.0), (33, 17, 30.0), (101, 57, 170.0), (7, 300, 60.0)]
)
def test_odd_sizes_and_fields_of_view_match_the_ray_caster(worlds, width, height, fov):
    """The pinhole holds for odd and tiny sizes, wide and narrow views (the principal point at w/2, h/2)."""
    world = worlds["default"]
    for position, rpy in (((0.0, 0.0, -4.0), (0.0, -0.3, 0.5)), ((20.0, 20.0, -3.0), (0.0, 0.0, 0.0))):
        args = (np.array(position), quat_from_rpy(*rpy), width, height, fov, list(camera_model.IMAGE_TYPES))
        gl = {k: pixels(v) for k, v in gl_renderer.render(world, RenderRequest(*args)).items()}
        ray = {k: pixels(v) for k, v in raycast_renderer.render_raycast(world, RenderRequest(*args)).items()}
        for kind in camera_model.IMAGE_TYPES:
            differ = (~agreement(kind, gl[kind], ray[kind], np.ones((height, width), dtype=bool))).sum()
            assert differ <= EDGE_FRACTION * width * height + 1, (position, kind, differ)
