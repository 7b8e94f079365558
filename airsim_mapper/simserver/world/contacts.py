"""Sphere contacts: how deep a sphere (a robot's collision body) overlaps boxes and spheres.

Pure numpy over the World's per-object tables (`World.collide_sphere` picks the deepest collidable one).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True, eq=False)
class Contact:
    """The deepest overlap of a sphere (a robot's collision body) with a world object."""

    object_name: str
    segmentation_id: int
    position: np.ndarray  # centre of the colliding sphere (world NED)
    impact_point: np.ndarray  # closest point on the object's surface (world NED)
    normal: np.ndarray  # unit vector from the object towards the sphere centre
    penetration_depth: float


def _yaw_rotate(cos: np.ndarray, sin: np.ndarray, x, y):
    """Rotate (x, y) by +yaw (object local -> world)."""
    return cos * x - sin * y, sin * x + cos * y


def box_contacts(
    c: np.ndarray,
    radius: float,
    box_center: np.ndarray,
    box_half: np.ndarray,
    box_cos: np.ndarray,
    box_sin: np.ndarray,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Per box: penetration depth, closest surface point and unit normal of a sphere at `c` (world NED).

    The boxes are given by their centres (B, 3), half sizes (B, 3) and the cosine and sine of their yaws.
    """
    cos = box_cos.astype(np.float64)
    sin = box_sin.astype(np.float64)
    half = box_half.astype(np.float64)
    rel = c - box_center.astype(np.float64)
    local = np.stack([cos * rel[:, 0] + sin * rel[:, 1], -sin * rel[:, 0] + cos * rel[:, 1], rel[:, 2]], 1)
    closest = np.clip(local, -half, half)
    gap = local - closest
    dist = np.linalg.norm(gap, axis=1)
    outside = dist > 1e-9
    # inside: push out through the nearest face
    face_dist = half - np.abs(local)
    axis = np.argmin(face_dist, axis=1)
    rows = np.arange(axis.size)
    sign = np.where(local[rows, axis] >= 0.0, 1.0, -1.0)
    inside_n = np.zeros_like(local)
    inside_n[rows, axis] = sign
    inside_p = local.copy()
    inside_p[rows, axis] = sign * half[rows, axis]
    with np.errstate(invalid="ignore", divide="ignore"):
        out_n = gap / np.where(outside, dist, 1.0)[:, None]
    local_n = np.where(outside[:, None], out_n, inside_n)
    local_p = np.where(outside[:, None], closest, inside_p)
    depth = np.where(outside, radius - dist, radius + face_dist[rows, axis])
    nx, ny = _yaw_rotate(cos, sin, local_n[:, 0], local_n[:, 1])
    px, py = _yaw_rotate(cos, sin, local_p[:, 0], local_p[:, 1])
    normals = np.stack([nx, ny, local_n[:, 2]], 1)
    points = np.stack([px, py, local_p[:, 2]], 1) + box_center
    return depth, points, normals


def sphere_contacts(
    c: np.ndarray, radius: float, sphere_center: np.ndarray, sphere_radius: np.ndarray
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Per sphere (centres (S, 3), radii (S,)): depth, surface point and normal, as `box_contacts`."""
    centers = sphere_center.astype(np.float64)
    radii = sphere_radius.astype(np.float64)
    rel = c - centers
    dist = np.linalg.norm(rel, axis=1)
    normals = np.where(
        (dist > 1e-9)[:, None],
        rel / np.where(dist > 1e-9, dist, 1.0)[:, None],
        np.array([0.0, 0.0, -1.0]),
    )
    points = centers + normals * radii[:, None]
    return radius + radii - dist, points, normals
