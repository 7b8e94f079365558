"""Camera rendering by ray casting: one shared cast per frame serves every requested image type.

The camera looks along its body +x (FRD: x forward, y right, z down). Pixel (u, v) (column, row, top-left
origin) looks along (1, (u - w/2)/f, (v - h/2)/f) with f = (w/2)/tan(fov/2), the pinhole model that
`camera_info_message` publishes, so projecting a point with K lands on the pixel that sees it.

Image types (Project AirSim numbering): 0 scene (BGR, Lambert-shaded object colours, checkered ground,
sky), 1 depth planar and 2 depth perspective (16FC1, float16 metres, +inf where nothing is hit),
3 segmentation (BGR colour of the segmentation id, black for sky), 4 depth vis (BGR grey, perspective depth
/ max depth, white beyond), 5 disparity normalized (BGR grey, 1 m / planar depth clipped to 1, black sky),
6 surface normals (BGR of the world NED normal mapped from [-1, 1] to [0, 255] as R=x, G=y, B=z; black sky).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from functools import lru_cache

import numpy as np

from airsim_mapper.geometry import quat_to_matrix
from airsim_mapper.simserver.world import GROUND_INDEX, MISS_INDEX, World

SCENE, DEPTH_PLANAR, DEPTH_PERSPECTIVE, SEGMENTATION, DEPTH_VIS, DISPARITY_NORMALIZED, SURFACE_NORMALS = (
    range(7)
)
IMAGE_TYPES = tuple(range(7))
DEPTH_TYPES = (DEPTH_PLANAR, DEPTH_PERSPECTIVE)
DEFAULT_MAX_DISTANCE = 10000.0  # metres a camera ray travels before it counts as sky
DEFAULT_MAX_DEPTH_VIS = 100.0  # metres that map to white in depth vis (capture setting max-depth-meters)
SUN_DIRECTION = np.array(
    [-0.3, 0.4, -0.866], dtype=np.float32
)  # towards the sun, world NED (high, south-east)
_AMBIENT = np.float32(0.35)
_FOG_DISTANCE = np.float32(1500.0)


class CameraError(ValueError):
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


def _bgr(channels: np.ndarray, width: int, height: int) -> RenderedImage:
    """Image from (3, N) channel rows (B, G, R) of values already in 0-255."""
    pixels = np.empty((channels.shape[1], 3), dtype=np.uint8)
    for c in range(3):
        pixels[:, c] = channels[c]
    return RenderedImage("BGR", width, height, pixels.tobytes())


def _gray(values: np.ndarray, width: int, height: int) -> RenderedImage:
    level = (np.clip(values, 0.0, 1.0) * np.float32(255.0) + np.float32(0.5)).astype(np.uint8)
    return RenderedImage("BGR", width, height, np.repeat(level, 3).tobytes())


def _scene(world: World, position: np.ndarray, dirs: np.ndarray, hits) -> np.ndarray:
    """Shaded colours as (3, N) float32 B, G, R rows."""
    index = hits.object_index
    colors = world.colors_of(index)  # (3, N)
    normal = hits.normal.T  # (3, N)
    sun = SUN_DIRECTION / np.linalg.norm(SUN_DIRECTION)
    lambert = np.clip(sun[0] * normal[0] + sun[1] * normal[1] + sun[2] * normal[2], 0.0, 1.0)
    light = _AMBIENT + (np.float32(1.0) - _AMBIENT) * lambert
    ground = index == GROUND_INDEX
    with np.errstate(invalid="ignore"):
        px = position[0] + dirs[0] * hits.distance
        py = position[1] + dirs[1] * hits.distance
    cells = np.floor(np.where(ground, px, 0.0) / 2.0) + np.floor(np.where(ground, py, 0.0) / 2.0)
    light *= np.where(ground & (cells % 2 == 1), np.float32(0.85), np.float32(1.0))
    # haze towards the sky colour with distance; the sky itself brightens towards the horizon
    hit = index != MISS_INDEX
    haze = np.where(hit, -np.expm1(-np.where(hit, hits.distance, 0.0) / _FOG_DISTANCE), np.float32(1.0))
    horizon = np.clip(np.float32(1.0) + dirs[2], 0.0, 1.0) * np.float32(0.25)
    keep = (np.float32(1.0) - haze) * light
    out = np.empty(colors.shape, dtype=np.float32)
    for channel, sky in enumerate(world.sky_color_bgr):
        sky_px = np.float32(sky) + (np.float32(255.0 - sky)) * horizon
        out[channel] = colors[channel] * keep + sky_px * haze
    return out


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
            out[kind] = _bgr(np.clip(_scene(world, origin, dirs, hits), 0.0, 255.0) + 0.5, width, height)
        elif kind in DEPTH_TYPES:
            depth = planar if kind == DEPTH_PLANAR else perspective
            out[kind] = RenderedImage("16FC1", width, height, depth.astype("<f2").tobytes())
        elif kind == SEGMENTATION:
            palette = segmentation_palette().T  # (3, 256)
            out[kind] = _bgr(np.take(palette, hits.segmentation_id % 256, axis=1), width, height)
        elif kind == DEPTH_VIS:
            out[kind] = _gray(perspective / np.float32(max_depth_vis), width, height)
        elif kind == DISPARITY_NORMALIZED:
            with np.errstate(divide="ignore"):
                out[kind] = _gray(np.float32(1.0) / np.maximum(planar, np.float32(1e-6)), width, height)
        else:  # SURFACE_NORMALS: B = z, G = y, R = x
            normal = hits.normal.T[::-1]
            encoded = np.where(
                hits.hit, (normal + np.float32(1.0)) * np.float32(127.5) + np.float32(0.5), 0.0
            )
            out[kind] = _bgr(encoded, width, height)
    return out
