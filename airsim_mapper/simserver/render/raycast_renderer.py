"""Camera rendering by the numpy ray caster: the reference renderer, and the fallback without OpenGL.

One shared cast per frame serves every requested image type (the images of `camera_model.py`);
tests/simserver/test_gl_renderer.py compares the OpenGL renderer with this one pixel by pixel.
"""

from __future__ import annotations

import numpy as np

from airsim_mapper.common.geometry import quat_to_matrix
from airsim_mapper.simserver.render.camera_model import (
    DEPTH_PLANAR,
    DEPTH_TYPES,
    DEPTH_VIS,
    DISPARITY_NORMALIZED,
    FOG_DISTANCE,
    SCENE,
    SEGMENTATION,
    RenderedImage,
    RenderRequest,
    camera_rays,
    face_constants,
    light,
    palette_rows,
    sun,
)
from airsim_mapper.simserver.world.world import World


def _bgr(channels, width: int, height: int) -> RenderedImage:
    """Image from three channel rows (B, G, R) of N values in 0-255 (cast to uint8, truncating)."""
    pixels = np.empty((width * height, 3), dtype=np.uint8)
    for c in range(3):
        pixels[:, c] = channels[c]
    return RenderedImage("BGR", width, height, pixels.tobytes())


def _gray(level: np.ndarray, width: int, height: int) -> RenderedImage:
    """Grey BGR image from N levels in 0-255 (values above 255 must not occur)."""
    gray = level.astype(np.uint8)
    return _bgr((gray, gray, gray), width, height)


def _sphere_pixels(hits) -> np.ndarray:
    return np.nonzero(hits.face < 0)[0]


def _scene(world: World, position: np.ndarray, dirs: np.ndarray, hits) -> np.ndarray:
    """Shaded colours as (3, N) float32 B, G, R rows in 0-255."""
    shade, _ = face_constants(world)  # flat faces: one value each
    one = np.float32(1.0)
    slots = np.maximum(hits.face, 0).astype(np.intp)
    out = np.empty((3, slots.size), dtype=np.float32)
    for c in range(3):
        np.take(shade[c], slots, out=out[c], mode="clip")
    curved = _sphere_pixels(hits)
    if curved.size:  # spheres: Lambert per pixel
        base = world.colors_of(hits.object_index[curved])
        out[:, curved] = base * light(hits.normal[curved] @ sun())
    # 2 m checker on the ground, and haze towards the sky colour with distance (misses are all sky)
    distance = np.minimum(hits.distance, np.float32(1e30))
    with np.errstate(invalid="ignore"):
        cell_x = np.floor(position[0] * np.float32(0.5) + dirs[0] * (distance * np.float32(0.5)))
        cell_y = np.floor(position[1] * np.float32(0.5) + dirs[1] * (distance * np.float32(0.5)))
        odd = ((cell_x + cell_y).astype(np.int64) & 1).astype(bool) & (hits.face == 1)
    haze = distance / (distance + FOG_DISTANCE)
    keep = (one - haze) * np.where(odd, np.float32(0.85), one)
    for c, sky in enumerate(world.sky_color_bgr):
        out[c] *= keep
        out[c] += np.float32(sky) * haze
    return out


def _normal_colors(world: World, hits) -> np.ndarray:
    """(3, N) B, G, R rows encoding the world normal (x -> R, y -> G, z -> B); black where nothing is hit."""
    _, lut = face_constants(world)
    slots = np.maximum(hits.face, 0).astype(np.intp)
    out = np.empty((3, slots.size), dtype=np.uint8)
    for c in range(3):
        np.take(lut[c], slots, out=out[c], mode="clip")
    curved = _sphere_pixels(hits)
    if curved.size:
        out[:, curved] = ((hits.normal[curved].T[::-1] + 1.0) * 127.5 + 0.5).astype(np.uint8)
    return out


def render_raycast(world: World, request: RenderRequest) -> dict[int, RenderedImage]:
    """The requested images of a camera, ray cast; CameraError if the request is invalid."""
    request.check()
    types = request.kinds
    if not types:
        return {}
    width, height = request.width, request.height
    local = camera_rays(width, height, float(request.fov_deg))
    rotation = quat_to_matrix(np.asarray(request.orientation, dtype=float)).astype(np.float32)
    dirs = rotation @ local  # (3, N) world directions
    origin = np.asarray(request.position, dtype=np.float32).reshape(3)
    hits = world.raycast_columns(origin, dirs, request.max_distance, unit=True)
    perspective = hits.distance
    planar = perspective * local[0]
    out: dict[int, RenderedImage] = {}
    for kind in types:
        if kind == SCENE:
            out[kind] = _bgr(_scene(world, origin, dirs, hits), width, height)
        elif kind in DEPTH_TYPES:
            depth = planar if kind == DEPTH_PLANAR else perspective
            out[kind] = RenderedImage("16FC1", width, height, depth.astype("<f2").tobytes())
        elif kind == SEGMENTATION:
            ids = (hits.segmentation_id & 255).astype(np.intp)
            palette = palette_rows()
            out[kind] = _bgr([np.take(palette[c], ids, mode="clip") for c in range(3)], width, height)
        elif kind == DEPTH_VIS:  # 0 at the camera, 255 at max depth and beyond
            scale = np.float32(255.0 / request.max_depth_vis)
            level = np.minimum(perspective * scale + np.float32(0.5), 255.0)
            out[kind] = _gray(level, width, height)
        elif kind == DISPARITY_NORMALIZED:  # 1 m / planar depth: 255 up to 1 m, 0 for the sky
            with np.errstate(divide="ignore"):
                level = np.minimum(np.float32(255.0) / planar + np.float32(0.5), 255.0)
            out[kind] = _gray(level, width, height)
        else:  # SURFACE_NORMALS
            out[kind] = _bgr(_normal_colors(world, hits), width, height)
    return out
