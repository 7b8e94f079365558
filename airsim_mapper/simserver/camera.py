"""Camera rendering: OpenGL (`gl_renderer.py`) by default, and the numpy ray caster here as the reference.

`render` draws with OpenGL in this process's own headless context (Mesa's llvmpipe without a GPU). Where no
context can be made it logs that once and ray casts instead (`render_raycast`: one shared cast per frame
serves every requested image type). `AIRSIM_MAPPER_RENDERER=raycast` (or `airsim-mapper-sim --renderer
raycast`, or `select_renderer`) chooses the ray caster; both produce the images described below, and
tests/simserver/test_gl_renderer.py compares them pixel by pixel.

The camera looks along its body +x (FRD: x forward, y right, z down). Pixel (u, v) (column, row, top-left
origin) looks along (1, (u - w/2)/f, (v - h/2)/f) with f = (w/2)/tan(fov/2), the pinhole model that
`camera_info_message` publishes, so projecting a point with K lands on the pixel that sees it.

Image types (Project AirSim numbering):
0 scene: BGR; object colours shaded by a fixed sun (Lambert plus ambient), the ground checkered in 2 m
  squares, distant surfaces hazed towards the sky colour.
1 depth planar, 2 depth perspective: 16FC1 (float16 metres), +inf where nothing is hit.
3 segmentation: BGR colour of the segmentation id (`segmentation_color`), black for the sky.
4 depth vis: BGR grey, perspective depth / max depth (white at and beyond it).
5 disparity normalized: BGR grey, 1 m / planar depth clipped to 1, black sky.
6 surface normals: BGR of the world NED normal mapped from [-1, 1] to [0, 255] as R=x, G=y, B=z; black sky.
"""

from __future__ import annotations

import logging
import math
import os
from collections.abc import Sequence
from dataclasses import dataclass
from functools import lru_cache

import numpy as np

from airsim_mapper.geometry import quat_to_matrix
from airsim_mapper.simserver.errors import SimServerError
from airsim_mapper.simserver.world import World

LOG = logging.getLogger("airsim_mapper.simserver.camera")
RENDERER_ENV = "AIRSIM_MAPPER_RENDERER"
RENDERERS = ("gl", "raycast")
SCENE, DEPTH_PLANAR, DEPTH_PERSPECTIVE, SEGMENTATION, DEPTH_VIS, DISPARITY_NORMALIZED, SURFACE_NORMALS = (
    range(7)
)
IMAGE_TYPES = tuple(range(7))
DEPTH_TYPES = (DEPTH_PLANAR, DEPTH_PERSPECTIVE)
DEFAULT_MAX_DISTANCE = 10000.0  # metres a camera ray travels before it counts as sky
DEFAULT_MAX_DEPTH_VIS = 100.0  # metres that map to white in depth vis (capture setting max-depth-meters)
# towards the sun, world NED: high in the south-east
SUN_DIRECTION = np.array([-0.3, 0.4, -0.866], dtype=np.float32)
_AMBIENT = np.float32(0.35)
_FOG_DISTANCE = np.float32(1500.0)


class CameraError(SimServerError, ValueError):
    """Invalid render request (size, field of view or image type)."""


@dataclass(frozen=True)
class RenderedImage:
    encoding: str  # "BGR" or "16FC1"
    width: int
    height: int
    data: bytes  # row-major, top-left origin, channels interleaved, no padding


def focal_length(width: int, fov_deg: float) -> float:
    """Pixels; the same for both axes, from the horizontal field of view (as the real server does)."""
    return (width / 2.0) / math.tan(math.radians(fov_deg) / 2.0)


def camera_info_message(width: int, height: int, fov_deg: float) -> dict:
    """CameraInfo exactly as the real server builds it (protocol.md §5.5)."""
    f = focal_length(width, fov_deg)
    return {
        "width": int(width),
        "height": int(height),
        "distortion_model": "",
        "distortion_params": [0.0] * 5,
        "intrinsic_camera_matrix": [f, 0.0, width / 2.0, 0.0, f, height / 2.0, 0.0, 0.0, 1.0],
        "rectification_matrix": [1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0],
        "projection_matrix": [1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0],
    }


@lru_cache(maxsize=32)
def camera_rays(width: int, height: int, fov_deg: float) -> np.ndarray:
    """(3, H*W) float32 unit ray directions in the camera frame (FRD), row-major from the top-left pixel."""
    f = focal_length(width, fov_deg)
    u = (np.arange(width, dtype=np.float64) - width / 2.0) / f
    v = (np.arange(height, dtype=np.float64) - height / 2.0) / f
    uu, vv = np.meshgrid(u, v)
    rays = np.stack([np.ones_like(uu).ravel(), uu.ravel(), vv.ravel()])
    rays /= np.sqrt((rays * rays).sum(axis=0))
    rays = rays.astype(np.float32)
    rays.flags.writeable = False
    return rays


@lru_cache(maxsize=1)
def segmentation_palette() -> np.ndarray:
    """(256, 3) uint8 BGR colour of each segmentation id; id 0 (nothing) is black, the rest are distinct."""
    ids = np.arange(256, dtype=np.float64)
    hue = (ids * 0.618033988749895) % 1.0
    sat = 0.55 + 0.45 * ((ids * 7) % 5) / 4.0
    val = 0.6 + 0.4 * ((ids * 3) % 4) / 3.0
    k = (hue[:, None] * 6.0 + np.array([5.0, 3.0, 1.0])) % 6.0  # r, g, b channel phases
    rgb = val[:, None] - val[:, None] * sat[:, None] * np.clip(np.minimum(k, 4.0 - k), 0.0, 1.0)
    palette = np.round(rgb[:, ::-1] * 255.0).astype(np.uint8)
    palette[0] = 0
    palette.flags.writeable = False
    return palette


@lru_cache(maxsize=1)
def _palette_rows() -> np.ndarray:
    """(3, 256) B, G, R rows of the segmentation palette."""
    rows = np.ascontiguousarray(segmentation_palette().T)
    rows.flags.writeable = False
    return rows


def segmentation_color(segmentation_id: int) -> tuple[int, int, int]:
    """BGR colour used for one segmentation id in segmentation images."""
    return tuple(int(c) for c in segmentation_palette()[int(segmentation_id) % 256])


def _check_request(width: int, height: int, fov_deg: float, image_types: Sequence[int]) -> None:
    if not (isinstance(width, int) and isinstance(height, int) and width > 0 and height > 0):
        raise CameraError(f"image size must be positive integers, got {width!r} x {height!r}")
    if not 0.0 < float(fov_deg) < 180.0:
        raise CameraError(f"fov-degrees must be between 0 and 180 (exclusive), got {fov_deg!r}")
    unknown = [t for t in image_types if t not in IMAGE_TYPES]
    if unknown:
        raise CameraError(f"unknown image type {unknown[0]!r} (expected 0-6)")


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
    normals, colors = world.face_table
    sun = SUN_DIRECTION / np.linalg.norm(SUN_DIRECTION)
    one = np.float32(1.0)
    light = _AMBIENT + (one - _AMBIENT) * np.clip(sun @ normals, 0.0, 1.0)  # flat faces: one value each
    shade = (colors * light).astype(np.float32)
    slots = np.maximum(hits.face, 0).astype(np.intp)
    out = np.empty((3, slots.size), dtype=np.float32)
    for c in range(3):
        np.take(shade[c], slots, out=out[c], mode="clip")
    curved = _sphere_pixels(hits)
    if curved.size:  # spheres: Lambert per pixel
        lambert = np.clip(hits.normal[curved] @ sun, 0.0, 1.0)
        base = world.colors_of(hits.object_index[curved])
        out[:, curved] = base * (_AMBIENT + (one - _AMBIENT) * lambert)
    # 2 m checker on the ground, and haze towards the sky colour with distance (misses are all sky)
    distance = np.minimum(hits.distance, np.float32(1e30))
    with np.errstate(invalid="ignore"):
        cell_x = np.floor(position[0] * np.float32(0.5) + dirs[0] * (distance * np.float32(0.5)))
        cell_y = np.floor(position[1] * np.float32(0.5) + dirs[1] * (distance * np.float32(0.5)))
        odd = ((cell_x + cell_y).astype(np.int64) & 1).astype(bool) & (hits.face == 1)
    haze = distance / (distance + _FOG_DISTANCE)
    keep = (one - haze) * np.where(odd, np.float32(0.85), one)
    for c, sky in enumerate(world.sky_color_bgr):
        out[c] *= keep
        out[c] += np.float32(sky) * haze
    return out


def _normal_colors(world: World, hits) -> np.ndarray:
    """(3, N) B, G, R rows encoding the world normal (x -> R, y -> G, z -> B); black where nothing is hit."""
    normals, _ = world.face_table
    lut = np.where(np.arange(normals.shape[1]) > 0, (normals[::-1] + 1.0) * 127.5 + 0.5, 0.0).astype(np.uint8)
    slots = np.maximum(hits.face, 0).astype(np.intp)
    out = np.empty((3, slots.size), dtype=np.uint8)
    for c in range(3):
        np.take(lut[c], slots, out=out[c], mode="clip")
    curved = _sphere_pixels(hits)
    if curved.size:
        out[:, curved] = ((hits.normal[curved].T[::-1] + 1.0) * 127.5 + 0.5).astype(np.uint8)
    return out


class _Choice:
    """The renderer this process uses: None until the first render reads RENDERER_ENV."""

    name: str | None = None


def select_renderer(name: str | None) -> None:
    """Use `name` ("gl" or "raycast") from now on in this process; None reads RENDERER_ENV again."""
    if name is not None and name not in RENDERERS:
        raise CameraError(f"unknown renderer {name!r} (expected one of {', '.join(RENDERERS)})")
    _Choice.name = name


def renderer_name() -> str:
    """The renderer `render` uses in this process: "gl" or "raycast"."""
    if _Choice.name is None:
        wanted = os.environ.get(RENDERER_ENV, "gl").strip().lower() or "gl"
        if wanted not in RENDERERS:
            LOG.error("%s=%r is not one of %s; using gl", RENDERER_ENV, wanted, ", ".join(RENDERERS))
            wanted = "gl"
        _Choice.name = wanted
    return _Choice.name


def render(
    world: World,
    position: np.ndarray,
    orientation: np.ndarray,
    width: int,
    height: int,
    fov_deg: float,
    image_types: Sequence[int],
    max_depth_vis: float = DEFAULT_MAX_DEPTH_VIS,
    max_distance: float = DEFAULT_MAX_DISTANCE,
) -> dict[int, RenderedImage]:
    """Render the requested image types for a camera at a world NED pose (orientation w, x, y, z)."""
    types = list(dict.fromkeys(image_types))
    _check_request(width, height, fov_deg, types)
    args = (position, orientation, width, height, fov_deg, types, max_depth_vis, max_distance)
    if not types:
        return {}
    if renderer_name() == "gl":
        from airsim_mapper.simserver import gl_renderer

        try:
            return gl_renderer.render(world, *args)
        except gl_renderer.GLUnavailable as exc:
            LOG.error("camera images: %s; rendering with the numpy ray caster from now on (much slower)", exc)
            _Choice.name = "raycast"
        except gl_renderer.GLRenderError as exc:
            LOG.warning("camera images: %s; ray casting this one", exc)
    return render_raycast(world, *args)


def render_raycast(
    world: World,
    position: np.ndarray,
    orientation: np.ndarray,
    width: int,
    height: int,
    fov_deg: float,
    image_types: Sequence[int],
    max_depth_vis: float = DEFAULT_MAX_DEPTH_VIS,
    max_distance: float = DEFAULT_MAX_DISTANCE,
) -> dict[int, RenderedImage]:
    """`render` by the numpy ray caster: the reference renderer, and the fallback without OpenGL."""
    types = list(dict.fromkeys(image_types))
    _check_request(width, height, fov_deg, types)
    if not types:
        return {}
    local = camera_rays(width, height, float(fov_deg))
    rotation = quat_to_matrix(np.asarray(orientation, dtype=float)).astype(np.float32)
    dirs = rotation @ local  # (3, N) world directions
    origin = np.asarray(position, dtype=np.float32).reshape(3)
    hits = world.raycast_columns(origin, dirs, max_distance, unit=True)
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
            palette = _palette_rows()
            out[kind] = _bgr([np.take(palette[c], ids, mode="clip") for c in range(3)], width, height)
        elif kind == DEPTH_VIS:  # 0 at the camera, 255 at max depth and beyond
            level = np.minimum(perspective * np.float32(255.0 / max_depth_vis) + np.float32(0.5), 255.0)
            out[kind] = _gray(level, width, height)
        elif kind == DISPARITY_NORMALIZED:  # 1 m / planar depth: 255 up to 1 m, 0 for the sky
            with np.errstate(divide="ignore"):
                level = np.minimum(np.float32(255.0) / planar + np.float32(0.5), 255.0)
            out[kind] = _gray(level, width, height)
        else:  # SURFACE_NORMALS
            out[kind] = _bgr(_normal_colors(world, hits), width, height)
    return out
