"""The camera model both renderers share: image types, pinhole, palette, lighting and the render request.

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

`raycast_renderer.py` (the numpy reference) and `gl_renderer.py` (OpenGL) both draw these images from a
`RenderRequest`; `rendering.py` chooses between them.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import lru_cache

import numpy as np

from airsim_mapper.simserver.errors import SimServerError
from airsim_mapper.simserver.world.world import World

SCENE, DEPTH_PLANAR, DEPTH_PERSPECTIVE, SEGMENTATION, DEPTH_VIS, DISPARITY_NORMALIZED, SURFACE_NORMALS = (
    range(7)
)
IMAGE_TYPES = tuple(range(7))
DEPTH_TYPES = (DEPTH_PLANAR, DEPTH_PERSPECTIVE)
DEFAULT_MAX_DISTANCE = 10000.0  # metres a camera ray travels before it counts as sky
DEFAULT_MAX_DEPTH_VIS = 100.0  # metres that map to white in depth vis (capture setting max-depth-meters)
# towards the sun, world NED: high in the south-east
SUN_DIRECTION = np.array([-0.3, 0.4, -0.866], dtype=np.float32)
AMBIENT = np.float32(0.35)  # the light a surface facing away from the sun still gets
FOG_DISTANCE = np.float32(1500.0)  # metres at which a surface is hazed half way to the sky colour


class CameraError(SimServerError, ValueError):
    """Invalid render request (size, field of view or image type)."""


@dataclass(frozen=True)
class RenderedImage:
    encoding: str  # "BGR" or "16FC1"
    width: int
    height: int
    data: bytes | memoryview  # row-major, top-left origin, channels interleaved, no padding


@dataclass(frozen=True, eq=False)
class RenderRequest:
    """One camera's render: its world NED pose (orientation w, x, y, z), image size, horizontal field of
    view and the image types wanted (drawn in one pass), with depth vis's white range and the sky range."""

    position: np.ndarray
    orientation: np.ndarray
    width: int
    height: int
    fov_deg: float
    image_types: tuple[int, ...] | list[int]
    max_depth_vis: float = DEFAULT_MAX_DEPTH_VIS
    max_distance: float = DEFAULT_MAX_DISTANCE

    @property
    def kinds(self) -> list[int]:
        """The requested image types in request order, each once."""
        return list(dict.fromkeys(self.image_types))

    def layout(self) -> dict[int, tuple[str, int, int]]:
        """Each image type's (encoding, byte offset, byte size) when the images lie one after another in
        one buffer, in request order (how the render worker hands its images over)."""
        out, offset = {}, 0
        for kind in self.kinds:
            encoding, size = ("16FC1", 2) if kind in DEPTH_TYPES else ("BGR", 3)
            size *= self.width * self.height
            out[kind] = (encoding, offset, size)
            offset += size
        return out

    @property
    def nbytes(self) -> int:
        """The size of the buffer `layout` fills."""
        return sum(size for _, _, size in self.layout().values())

    def check(self) -> None:
        """CameraError if the size, field of view or an image type is invalid."""
        width, height, fov_deg = self.width, self.height, self.fov_deg
        if not (isinstance(width, int) and isinstance(height, int) and width > 0 and height > 0):
            raise CameraError(f"image size must be positive integers, got {width!r} x {height!r}")
        if not 0.0 < float(fov_deg) < 180.0:
            raise CameraError(f"fov-degrees must be between 0 and 180 (exclusive), got {fov_deg!r}")
        unknown = [t for t in self.image_types if t not in IMAGE_TYPES]
        if unknown:
            raise CameraError(f"unknown image type {unknown[0]!r} (expected 0-6)")


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
def palette_rows() -> np.ndarray:
    """(3, 256) B, G, R rows of the segmentation palette."""
    rows = np.ascontiguousarray(segmentation_palette().T)
    rows.flags.writeable = False
    return rows


def segmentation_color(segmentation_id: int) -> tuple[int, int, int]:
    """BGR colour used for one segmentation id in segmentation images."""
    return tuple(int(c) for c in segmentation_palette()[int(segmentation_id) % 256])


def sun() -> np.ndarray:
    """The unit vector towards the sun (float32, world NED)."""
    return (SUN_DIRECTION / np.linalg.norm(SUN_DIRECTION)).astype(np.float32)


def light(cos_sun: np.ndarray) -> np.ndarray:
    """The light on a surface whose normal has cosine `cos_sun` with the sun: ambient plus Lambert."""
    one = np.float32(1.0)
    return AMBIENT + (one - AMBIENT) * np.clip(cos_sun, 0.0, 1.0)


def face_constants(world: World) -> tuple[np.ndarray, np.ndarray]:
    """Per face code (see `World.face_table`): (3, F) float32 lit B, G, R colours and (3, F) uint8 colours
    of the face's normal (x -> R, y -> G, z -> B; black for code 0, the sky)."""
    normals, colors = world.face_table
    shade = (colors * light(sun() @ normals)).astype(np.float32)
    lut = np.where(np.arange(normals.shape[1]) > 0, (normals[::-1] + 1.0) * 127.5 + 0.5, 0.0).astype(np.uint8)
    return shade, lut
