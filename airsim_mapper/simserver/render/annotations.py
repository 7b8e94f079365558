"""Bounding-box annotations of camera images, as the real server computes them (`annotation-settings`).

Config (a camera sensor's `annotation-settings`, read as core_sim `camera.cpp` LoadAnnotationSettings does):
`enabled` (default false), `object-ids` (exact object names; missing or empty turns annotations off),
`bbox3D-settings.alignment` (`"oriented"`, the default, or `"axis"`), `bbox2D-settings.alignment` (only
axis-aligned 2D boxes exist, as in the real server), `distance-filter-enabled` (default false) and
`distance-filter-range` (metres, default 10).

Per capture, for every listed object that exists in the world (UnrealCamera `GetBoundingBoxes`):
- `bbox3d`: centre (world NED), full size and orientation. Oriented: the object's own box and yaw; axis:
  the world-axis-aligned box around it, identity orientation. A sphere's box is the cube around it.
- the 8 corners of the object's oriented box, in Unreal's `FOrientedBox::CalcVertices` order (x, then y,
  then up, each - before +; up is NED -z), are projected with the camera's pinhole model (the one
  `camera_info_message` publishes: f = (w/2)/tan(fov/2) on both axes, principal point (w/2, h/2), camera
  looking along its body +x, FRD). `bbox3d_in_image_space` holds each corner's pixel, truncated to an
  integer and clamped to [0, w] x [0, h]; `bbox3d_in_projection_space` its normalised device coordinates
  (x right, y up, z = 0.1 m / depth: Unreal's reversed-z with its 10 cm near plane), each clamped to
  [-1, 1]. A corner behind the camera is (0, 0) and (0, 0, 0).
- `bbox2d`: the rectangle around the corners in front of the camera (after clamping), as centre and size.
  An object is annotated when that rectangle has an area (> 0.0001 px^2): at least one corner in front of
  the camera and the box reaching into the image. There is no occlusion test (the real server has none):
  an object hidden behind another is still annotated.

The image size and field of view are those of the camera's scene capture (image type 0), for every image
type of the capture, as in the real server; without a type-0 setting the real defaults (256 x 144, 90 deg).
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from airsim_mapper.common.geometry import quat_to_matrix
from airsim_mapper.simserver.errors import SimServerError
from airsim_mapper.simserver.world.world import World, WorldObject

NEAR_PLANE_M = 0.1  # Unreal's GNearClippingPlane (10 cm)
MIN_AREA_PX2 = 0.0001
ALIGNMENTS = ("oriented", "axis")
DEFAULT_SIZE = (256, 144)
DEFAULT_FOV_DEG = 90.0
# corner k of CalcVertices: signs along the box's x, y and Unreal up (= NED -z)
CORNER_SIGNS = np.array(
    [(sx, sy, -su) for sx in (-1.0, 1.0) for sy in (-1.0, 1.0) for su in (-1.0, 1.0)], dtype=np.float64
)


class AnnotationError(SimServerError, ValueError):
    """An `annotation-settings` value is invalid; the message names the key."""


@dataclass(frozen=True)
class AnnotationSettings:
    object_ids: tuple[str, ...]
    oriented: bool = True  # bbox3D-settings.alignment
    distance_filter_m: float | None = None

    @classmethod
    def from_config(cls, camera: Mapping[str, Any]) -> AnnotationSettings | None:
        """The settings of a camera sensor config; None when annotations are off."""
        cfg = camera.get("annotation-settings")
        if not cfg:
            return None
        if not isinstance(cfg, Mapping):
            raise AnnotationError(f"'annotation-settings' must be an object, got {cfg!r}")
        ids = cfg.get("object-ids", [])
        if not isinstance(ids, list) or not all(isinstance(i, str) for i in ids):
            raise AnnotationError(f"'annotation-settings.object-ids' must be a list of names, got {ids!r}")
        if not ids or not bool(cfg.get("enabled", False)):
            return None
        for key in ("bbox2D-settings", "bbox3D-settings"):
            alignment = (cfg.get(key) or {}).get("alignment", "oriented")
            if alignment not in ALIGNMENTS:
                raise AnnotationError(
                    f"'annotation-settings.{key}.alignment' must be 'oriented' or 'axis', got {alignment!r}"
                )
        distance = None
        if cfg.get("distance-filter-enabled", False):
            distance = cfg.get("distance-filter-range", 10.0)
            if isinstance(distance, bool) or not isinstance(distance, (int, float)) or not distance >= 0:
                raise AnnotationError(
                    f"'annotation-settings.distance-filter-range' must be a number >= 0, got {distance!r}"
                )
            distance = float(distance)
        oriented = (cfg.get("bbox3D-settings") or {}).get("alignment", "oriented") == "oriented"
        return cls(tuple(dict.fromkeys(ids)), oriented, distance)


@dataclass(frozen=True)
class Boxes:
    """N oriented boxes: centres (N, 3), half extents (N, 3) and rotations (N, 3, 3), world NED."""

    names: tuple[str, ...]
    center: np.ndarray
    half: np.ndarray
    rotation: np.ndarray

    def corners(self) -> np.ndarray:
        """(N, 8, 3) world corners in CalcVertices order."""
        local = CORNER_SIGNS[None, :, :] * self.half[:, None, :]
        return self.center[:, None, :] + np.einsum("nij,nkj->nki", self.rotation, local)

    def yaw_quaternions(self) -> np.ndarray:
        """(N, 4) w, x, y, z of each box's rotation (a yaw about NED z)."""
        yaw = np.arctan2(self.rotation[:, 1, 0], self.rotation[:, 0, 0])
        zeros = np.zeros_like(yaw)
        return np.stack([np.cos(yaw / 2), zeros, zeros, np.sin(yaw / 2)], axis=1)

    def axis_half(self) -> np.ndarray:
        """(N, 3) half extents of the world-axis-aligned box around each box."""
        return np.einsum("nij,nj->ni", np.abs(self.rotation), self.half)


def boxes_of(objects: Sequence[WorldObject]) -> Boxes:
    """The oriented boxes of world objects (a sphere's is the cube around it)."""
    half = np.array([o.size / 2.0 for o in objects], dtype=np.float64).reshape(-1, 3)
    yaw = np.array([o.yaw if o.shape == "box" else 0.0 for o in objects], dtype=np.float64)
    cos, sin = np.cos(yaw), np.sin(yaw)
    rotation = np.zeros((yaw.size, 3, 3))
    rotation[:, 0, 0], rotation[:, 0, 1], rotation[:, 1, 0], rotation[:, 1, 1] = cos, -sin, sin, cos
    rotation[:, 2, 2] = 1.0
    center = np.array([o.center for o in objects], dtype=np.float64).reshape(-1, 3)
    return Boxes(tuple(o.name for o in objects), center, half, rotation)


@dataclass(frozen=True)
class Projection:
    """Corners seen from a camera: (N, 8) in front, (N, 8, 2) clamped integer pixels, (N, 8, 3) NDC."""

    in_front: np.ndarray
    pixels: np.ndarray
    ndc: np.ndarray


def project(
    points: np.ndarray,
    position: np.ndarray,
    orientation: np.ndarray,
    width: int,
    height: int,
    fov_deg: float,
) -> Projection:
    """Project world NED points (..., 3) into a camera at a world pose (orientation w, x, y, z)."""
    rotation = quat_to_matrix(np.asarray(orientation, dtype=float))
    local = (np.asarray(points, dtype=np.float64) - np.asarray(position, dtype=np.float64)) @ rotation
    depth = local[..., 0]
    in_front = depth > 0.0
    f = (width / 2.0) / math.tan(math.radians(fov_deg) / 2.0)
    safe = np.where(in_front, depth, 1.0)
    u = width / 2.0 + f * local[..., 1] / safe
    v = height / 2.0 + f * local[..., 2] / safe
    pixels = np.stack([np.clip(np.trunc(u), 0, width), np.clip(np.trunc(v), 0, height)], axis=-1)
    ndc = np.stack(
        [(u - width / 2.0) / (width / 2.0), (height / 2.0 - v) / (height / 2.0), NEAR_PLANE_M / safe], axis=-1
    )
    ndc = np.clip(ndc, -1.0, 1.0)
    pixels[~in_front] = 0.0
    ndc[~in_front] = 0.0
    return Projection(in_front, pixels, ndc)


def rectangles(projection: Projection) -> tuple[np.ndarray, np.ndarray]:
    """(N, 2) min and (N, 2) max pixel of each box's corners in front of the camera (NaN if none is)."""
    front = projection.in_front[..., None]
    low = np.where(front, projection.pixels, np.inf).min(axis=1)
    high = np.where(front, projection.pixels, -np.inf).max(axis=1)
    none = ~projection.in_front.any(axis=1)
    low[none], high[none] = np.nan, np.nan
    return low, high


def _xy(v: np.ndarray) -> dict[str, float]:
    return {"x": float(v[0]), "y": float(v[1])}


def _xyz(v: np.ndarray) -> dict[str, float]:
    return {"x": float(v[0]), "y": float(v[1]), "z": float(v[2])}


def annotate(
    world: World,
    settings: AnnotationSettings,
    position: np.ndarray,
    orientation: np.ndarray,
    width: int,
    height: int,
    fov_deg: float,
) -> list[dict[str, Any]]:
    """The `annotations` list of one capture from a camera at a world NED pose."""
    objects = [o for o in (world.object_named(i) for i in settings.object_ids) if o is not None]
    if not objects:
        return []
    boxes = boxes_of(objects)
    projection = project(boxes.corners(), position, orientation, width, height, fov_deg)
    low, high = rectangles(projection)
    size = high - low
    with np.errstate(invalid="ignore"):
        keep = size[:, 0] * size[:, 1] > MIN_AREA_PX2
        if settings.distance_filter_m is not None:
            distance = np.linalg.norm(boxes.center - np.asarray(position, dtype=np.float64), axis=1)
            keep &= distance <= settings.distance_filter_m
    if settings.oriented:
        half, quats = boxes.half, boxes.yaw_quaternions()
    else:
        half, quats = boxes.axis_half(), np.tile([1.0, 0.0, 0.0, 0.0], (len(objects), 1))
    out = []
    for n in np.nonzero(keep)[0]:  # one dict per annotated object (a handful), not per pixel
        w, x, y, z = (float(c) for c in quats[n])
        out.append(
            {
                "object_id": boxes.names[n],
                "bbox2d": {"center": _xy((low[n] + high[n]) / 2.0), "size": _xy(size[n])},
                "bbox3d": {
                    "center": _xyz(boxes.center[n]),
                    "size": _xyz(2.0 * half[n]),
                    "quaternion": {"w": w, "x": x, "y": y, "z": z},
                },
                "bbox3d_in_image_space": [_xy(p) for p in projection.pixels[n]],
                "bbox3d_in_projection_space": [_xyz(p) for p in projection.ndc[n]],
            }
        )
    return out
