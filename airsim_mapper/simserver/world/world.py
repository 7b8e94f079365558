"""The world the headless server senses: a ground plane at NED z = 0 plus boxes and spheres.

Everything is pure numpy (float32, rays in blocks of 32k). `World.raycast` tests every ray against every
object's bounding sphere at once (a (objects x rays) matrix product), then runs the exact test over the
surviving (ray, object) pairs as flat vectors: a slab test in the box's yawed frame, or the quadratic for a
sphere; the nearest of the pairs and the ground plane wins per ray.
Surfaces are one-sided: a ray that starts inside an object does not see that object (back faces are
culled), and the ground is seen only from above (z < 0).

The ray cast, the single-ray queries (`surface_below`, `range_along`) and the sphere collisions share
the World's per-object tables (the boxes' centres, half sizes and yaws, the spheres' centres and radii); the
ray cast and the queries are here, the overlap of a sphere with those tables is `contacts.py`'s. A World is
built from a world file by `world_file.py`.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from airsim_mapper.simserver.world.contacts import Contact, box_contacts, sphere_contacts

GROUND_INDEX = -1
MISS_INDEX = -2
MISS_SEGMENTATION_ID = 0
_EPS = 1e-4  # hits closer than this are ignored (self hits at the ray origin)
_CHUNK = 32768  # rays per broadcast block: bounds the (rays x objects) temporaries
_UP = np.array([0.0, 0.0, -1.0], dtype=np.float32)  # ground normal in NED
# face codes of a hit: none, ground, then 6 per box; a sphere hit s is coded -1 - s
_FACE_NONE, _FACE_GROUND, _FACE_BOX0 = 0, 1, 2


@dataclass(frozen=True, eq=False)
class WorldObject:
    """One solid: a box (size = full extents along its yawed x, y, z) or a sphere (size = diameter x 3)."""

    name: str
    shape: str
    center: np.ndarray
    size: np.ndarray
    yaw: float
    segmentation_id: int
    color_bgr: tuple[int, int, int]
    collidable: bool = True

    @property
    def radius(self) -> float:
        """Bounding radius: the sphere's radius, or half the box diagonal."""
        if self.shape == "sphere":
            return float(self.size[0]) / 2.0
        return float(np.linalg.norm(self.size)) / 2.0


@dataclass(frozen=True, eq=False)
class Hits:
    """Per-ray results of `World.raycast` (N rays)."""

    distance: np.ndarray  # (N,) float32, metres along the unit ray, +inf on a miss
    object_index: np.ndarray  # (N,) int32, index into World.objects, -1 ground, -2 miss
    normal: np.ndarray  # (N, 3) float32, unit surface normal in world NED (zeros on a miss)
    segmentation_id: np.ndarray  # (N,) int32, the ground has its own id, a miss is 0
    # (N,) int32 face code: 0 miss, 1 ground, 2 + 6 b + 2 axis + (1 for the + face) for the b-th box,
    # -1 - s for the s-th sphere (in World.objects order); flat faces index World.face_table
    face: np.ndarray | None = None

    @property
    def hit(self) -> np.ndarray:
        return self.object_index != MISS_INDEX


class World:
    """Ground plane at z = 0 plus objects; answers ray casts and sphere collisions."""

    def __init__(
        self,
        objects: Sequence[WorldObject],
        ground_segmentation_id: int = 1,
        ground_color_bgr: tuple[int, int, int] = (70, 130, 90),
        sky_color_bgr: tuple[int, int, int] = (235, 206, 135),
        source: str = "<built-in>",
    ) -> None:
        self.objects: tuple[WorldObject, ...] = tuple(objects)
        self.ground_segmentation_id = int(ground_segmentation_id)
        self.ground_color_bgr = tuple(int(c) for c in ground_color_bgr)
        self.sky_color_bgr = tuple(int(c) for c in sky_color_bgr)
        self.source = source
        boxes = [i for i, o in enumerate(self.objects) if o.shape == "box"]
        spheres = [i for i, o in enumerate(self.objects) if o.shape == "sphere"]
        f32 = np.float32
        self._box_index = np.array(boxes, dtype=np.intp)
        self._box_center = np.array([self.objects[i].center for i in boxes], dtype=f32).reshape(-1, 3)
        self._box_half = np.array([self.objects[i].size / 2.0 for i in boxes], dtype=f32).reshape(-1, 3)
        yaws = np.array([self.objects[i].yaw for i in boxes], dtype=np.float64)
        self._box_cos = np.cos(yaws).astype(f32)
        self._box_sin = np.sin(yaws).astype(f32)
        self._sphere_index = np.array(spheres, dtype=np.intp)
        self._sphere_center = np.array([self.objects[i].center for i in spheres], dtype=f32).reshape(-1, 3)
        self._sphere_radius = np.array([self.objects[i].size[0] / 2.0 for i in spheres], dtype=f32)
        # columns of the candidate table: boxes first, then spheres
        self._column_object = np.concatenate([self._box_index, self._sphere_index]).astype(np.intp)
        column_objects = [self.objects[i] for i in self._column_object]
        self._bound_center64 = np.array([o.center for o in column_objects], dtype=np.float64).reshape(-1, 3)
        self._bound_center = self._bound_center64.astype(f32)
        self._bound_r2 = np.array([o.radius**2 for o in column_objects], dtype=f32) * f32(1.0001)
        self._bound_c2 = (self._bound_center**2).sum(axis=1)
        self._bound_radius = np.array([o.radius for o in column_objects], dtype=np.float64)
        self._box_top = (self._box_center[:, 2] - self._box_half[:, 2]).astype(np.float64)
        self._box_cols = np.ascontiguousarray(self._box_center.T)  # (3, B)
        self._box_half_cols = np.ascontiguousarray(self._box_half.T)
        self._sphere_cols = np.ascontiguousarray(self._sphere_center.T)  # (3, S)
        self._face_normals = self._face_normal_table()
        seg = [o.segmentation_id for o in self.objects]
        # lookup by object_index + 2: miss, ground, objects...
        self._segmentation_lookup = np.array(
            [MISS_SEGMENTATION_ID, self.ground_segmentation_id, *seg], dtype=np.int32
        )
        colors = [self.sky_color_bgr, self.ground_color_bgr, *(o.color_bgr for o in self.objects)]
        self._color_lookup = np.array(colors, dtype=np.float32).reshape(-1, 3)
        self._by_name = {o.name: o for o in self.objects}
        face_owner = np.concatenate([[MISS_INDEX, GROUND_INDEX], np.repeat(self._box_index, 6)]).astype(
            np.intp
        )
        self._face_colors = np.ascontiguousarray(self._color_lookup[face_owner + 2].T)

    def _face_normal_table(self) -> np.ndarray:
        """(3, 2 + 6B) world normals by face code: none, ground, then box b's -x, +x, -y, +y, -z, +z faces."""
        table = np.zeros((3, _FACE_BOX0 + 6 * self._box_index.size), dtype=np.float32)
        table[:, _FACE_GROUND] = _UP
        for b in range(self._box_index.size):
            cos, sin = float(self._box_cos[b]), float(self._box_sin[b])
            axes = np.array([[cos, sin, 0.0], [-sin, cos, 0.0], [0.0, 0.0, 1.0]])  # local axes in world
            for axis in range(3):
                table[:, _FACE_BOX0 + 6 * b + 2 * axis] = -axes[axis]
                table[:, _FACE_BOX0 + 6 * b + 2 * axis + 1] = axes[axis]
        return table

    @property
    def face_table(self) -> tuple[np.ndarray, np.ndarray]:
        """Per face code >= 0 (see Hits.face): (3, F) world normals and (3, F) base B, G, R colours.

        Code 0 (miss) has a zero normal and the sky colour; code 1 is the ground.
        """
        return self._face_normals, self._face_colors

    def object_named(self, name: str) -> WorldObject | None:
        return self._by_name.get(name)

    @property
    def current(self) -> World:
        """This world; a changing world (`objects.LiveWorld`) answers its newest one."""
        return self

    def colors_of(self, object_index: np.ndarray) -> np.ndarray:
        """(3, N) base B, G, R rows (float32, 0-255) of each hit: sky for a miss, ground, or the object."""
        slots = np.asarray(object_index).astype(np.intp) + 2
        out = np.empty((3, slots.size), dtype=np.float32)
        for c in range(3):
            np.take(self._color_lookup[:, c], slots, out=out[c], mode="clip")
        return out

    # ---------------------------------------------------------------- ray casting
    def raycast(self, origins: np.ndarray, directions: np.ndarray, max_range: float) -> Hits:
        """Intersect rays with the ground and every object; hits beyond `max_range` count as misses.

        `origins` is (N, 3) or one shared (3,) origin; `directions` (N, 3) need not be unit length (the
        returned distance is along the normalised direction).
        """
        dirs = np.asarray(directions, dtype=np.float32).reshape(-1, 3)
        return self.raycast_columns(origins, np.ascontiguousarray(dirs.T), max_range)

    def raycast_columns(
        self, origins: np.ndarray, directions: np.ndarray, max_range: float, unit: bool = False
    ) -> Hits:
        """`raycast` with directions given column-wise, (3, N): the fast layout for large N.

        `unit=True` promises unit-length directions and skips normalising them.
        """
        d = np.asarray(directions, dtype=np.float32)
        count = d.shape[1]
        if not unit:
            norms = np.sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2])
            d = d / np.where(norms == 0.0, np.float32(1.0), norms)
        o = np.asarray(origins, dtype=np.float32)
        shared = o.ndim == 1
        o = o.reshape(3, 1) if shared else np.ascontiguousarray(o.reshape(-1, 3).T)
        if not shared and o.shape[1] != count:
            raise ValueError(f"raycast: {o.shape[1]} origins for {count} directions")
        distance = np.empty(count, dtype=np.float32)
        index = np.empty(count, dtype=np.int32)
        face = np.empty(count, dtype=np.int32)
        local_origin = self._box_local_origins(o) if shared else None
        for start in range(0, count, _CHUNK):
            stop = min(start + _CHUNK, count)
            block_o = o if shared else np.ascontiguousarray(o[:, start:stop])
            distance[start:stop], index[start:stop], face[start:stop] = self._cast_block(
                block_o, np.ascontiguousarray(d[:, start:stop]), local_origin
            )
        miss = ~(distance <= np.float32(max_range))
        distance[miss] = np.inf
        index[miss] = MISS_INDEX
        face[miss] = _FACE_NONE
        normal = self._normals(o, d, distance, face)
        segmentation = np.take(self._segmentation_lookup, index.astype(np.intp) + 2, mode="clip")
        return Hits(distance, index, normal.T, segmentation, face)

    def _box_local_origins(self, o: np.ndarray) -> np.ndarray:
        """(3, B) one shared ray origin expressed in every box's frame."""
        rel = o - self._box_cols
        cos, sin = self._box_cos, self._box_sin
        return np.stack([cos * rel[0] + sin * rel[1], -sin * rel[0] + cos * rel[1], rel[2]])

    def _cast_block(self, o: np.ndarray, d: np.ndarray, local_origin: np.ndarray | None):
        """Nearest hit distance, object index and face code of one block of rays (o (3, 1|n), d (3, n)).

        A cheap bounding-sphere test over (objects x rays), two small matrix products, selects candidate
        pairs; only those pairs run the exact slab (box) or quadratic (sphere) test, vectorised over the
        pair list.
        """
        n = d.shape[1]
        with np.errstate(divide="ignore", invalid="ignore"):
            ground = np.where((d[2] > 1e-6) & (o[2] < 0.0), -o[2] / d[2], np.float32(np.inf))
        best = ground.astype(np.float32, copy=False)
        on_ground = best < np.inf
        best_index = np.where(on_ground, np.int32(GROUND_INDEX), np.int32(MISS_INDEX))
        best_face = on_ground.astype(np.int32)  # _FACE_GROUND or _FACE_NONE
        if not self.objects:
            return best, best_index, best_face
        c = self._bound_center  # (K, 3)
        if o.shape[1] == 1:
            # one origin: a ray can reach bounding sphere k only if its projection on the centre
            # direction is at least sqrt(|centre - origin|^2 - r^2); origins inside the sphere always can
            rel = c - o[:, 0]
            dist2 = (rel * rel).sum(axis=1)
            gap = dist2 - self._bound_r2
            threshold = np.where(gap > 0.0, np.sqrt(np.maximum(gap, 0.0)), -np.inf).astype(np.float32)
            candidate = rel.astype(np.float32) @ d >= threshold[:, None]
        else:
            proj = c @ d - (o * d).sum(axis=0)  # (centre - origin) . d, (K, n)
            dist2 = self._bound_c2[:, None] - 2.0 * (c @ o) + (o * o).sum(axis=0)  # |centre - origin|^2
            r2 = self._bound_r2[:, None]
            candidate = (dist2 - proj * proj <= r2) & ((proj > 0.0) | (dist2 <= r2))
        flat = np.flatnonzero(candidate)
        cols, rays = np.divmod(flat, n)  # pairs come grouped by object
        if rays.size == 0:
            return best, best_index, best_face
        pair_t = np.empty(rays.size, dtype=np.float32)
        pair_face = np.empty(rays.size, dtype=np.int32)
        n_box = self._box_index.size
        # pairs are sorted by column (boxes first, then spheres): per-object values spread by repetition
        bounds = np.searchsorted(cols, np.arange(len(self.objects) + 1))
        counts = np.diff(bounds)
        split = int(bounds[n_box])
        for part, is_sphere in ((slice(0, split), False), (slice(split, rays.size), True)):
            r = rays[part]
            if r.size == 0:
                continue
            pair_o = o if o.shape[1] == 1 else np.take(o, r, axis=1, mode="clip")
            pair_d = np.take(d, r, axis=1, mode="clip")
            if is_sphere:
                pair_t[part], pair_face[part] = self._sphere_pairs(pair_o, pair_d, counts[n_box:])
            else:
                pair_t[part], pair_face[part] = self._box_pairs(pair_o, pair_d, counts[:n_box], local_origin)
        table = np.full((len(self.objects), n), np.inf, dtype=np.float32)
        table.ravel()[flat] = pair_t
        nearest = table.min(axis=0)
        closer = nearest < best
        # the winning pair of each ray is the one whose distance equals the ray's nearest distance
        winner = (pair_t == np.take(nearest, rays, mode="clip")) & np.take(closer, rays, mode="clip")
        won = rays[winner]
        best_index[won] = np.take(self._column_object, cols[winner], mode="clip")
        best_face[won] = pair_face[winner]
        return np.where(closer, nearest, best), best_index, best_face

    def _box_pairs(self, o: np.ndarray, d: np.ndarray, counts: np.ndarray, local_origin: np.ndarray | None):
        """Entry distance (+inf on a miss) and face code of each pair (slab test in the box frame).

        The pairs are grouped by box: the first counts[0] belong to box 0, and so on.
        """
        cos, sin = np.repeat(self._box_cos, counts), np.repeat(self._box_sin, counts)
        if local_origin is not None:
            local_o = [np.repeat(local_origin[a], counts) for a in range(3)]
        else:
            rel = [o[a] - np.repeat(self._box_cols[a], counts) for a in range(3)]
            local_o = [cos * rel[0] + sin * rel[1], -sin * rel[0] + cos * rel[1], rel[2]]
        local_d = (cos * d[0] + sin * d[1], -sin * d[0] + cos * d[1], d[2])
        near = far = face = None
        with np.errstate(divide="ignore", invalid="ignore"):
            for axis in range(3):
                da = local_d[axis]
                inv = np.float32(1.0) / da  # +-inf for a ray parallel to the slab
                exit_half = np.copysign(np.repeat(self._box_half_cols[axis], counts), da)
                entry = (exit_half + local_o[axis]) * -inv
                leave = (exit_half - local_o[axis]) * inv
                # the + face is entered when travelling towards -axis; NaN (grazing) never wins
                code = (da < 0.0).astype(np.int32) + np.int32(2 * axis)
                if near is None:
                    near, far, face = entry, leave, code
                    continue
                face = np.where(entry > near, code, face)
                near = np.fmax(near, entry)
                far = np.fmin(far, leave)
            t = np.where((near <= far) & (near > _EPS), near, np.float32(np.inf))
        first_face = _FACE_BOX0 + 6 * np.arange(counts.size, dtype=np.int32)
        return t, np.repeat(first_face, counts) + face

    def _sphere_pairs(self, o: np.ndarray, d: np.ndarray, counts: np.ndarray):
        """Entry distance (+inf on a miss) and face code of each pair, grouped by sphere like `_box_pairs`."""
        rel = [o[a] - np.repeat(self._sphere_cols[a], counts) for a in range(3)]
        b = d[0] * rel[0] + d[1] * rel[1] + d[2] * rel[2]
        radius = np.repeat(self._sphere_radius, counts)
        c = rel[0] * rel[0] + rel[1] * rel[1] + rel[2] * rel[2] - radius * radius
        disc = b * b - c
        with np.errstate(invalid="ignore"):
            t = -b - np.sqrt(disc)
        t = np.where((disc >= 0.0) & (t > _EPS), t, np.float32(np.inf)).astype(np.float32)
        return t, np.repeat(-1 - np.arange(counts.size, dtype=np.int32), counts)

    def _normals(self, o: np.ndarray, d: np.ndarray, distance: np.ndarray, face: np.ndarray) -> np.ndarray:
        """(3, N) unit world normals at the hit points (zeros where nothing is hit)."""
        slots = np.maximum(face, 0).astype(np.intp)
        normal = np.empty(d.shape, dtype=np.float32)
        for a in range(3):
            np.take(self._face_normals[a], slots, out=normal[a], mode="clip")
        rays = np.nonzero(face < 0)[0]
        if rays.size:
            s = (-1 - face[rays]).astype(np.intp)
            pair_o = o if o.shape[1] == 1 else np.take(o, rays, axis=1, mode="clip")
            dist = np.take(distance, rays, mode="clip")
            radius = np.take(self._sphere_radius, s, mode="clip")
            for a in range(3):
                point = pair_o[a] + np.take(d[a], rays, mode="clip") * dist
                normal[a, rays] = (point - np.take(self._sphere_cols[a], s, mode="clip")) / radius
        return normal

    def surface_below(self, position: Sequence[float], max_range: float) -> float | None:
        """z of the first surface a ray cast straight down (+z) from `position` meets within `max_range`.

        The same answer as `raycast` with direction (0, 0, 1), by the same rules (one-sided surfaces, the
        ground seen from above), without its per-call overhead: motion asks it twice per tick.
        """
        x, y, z = (float(v) for v in position)
        nearest = -z if z < 0.0 else math.inf  # the ground plane
        if self._box_index.size:
            rx, ry = x - self._box_cols[0], y - self._box_cols[1]
            lx = self._box_cos * rx + self._box_sin * ry
            ly = self._box_cos * ry - self._box_sin * rx
            over = (np.abs(lx) <= self._box_half_cols[0]) & (np.abs(ly) <= self._box_half_cols[1])
            t = self._box_top - z
            t = t[over & (t > _EPS)]
            if t.size:
                nearest = min(nearest, float(t.min()))
        if self._sphere_index.size:
            cx, cy, cz = self._sphere_cols
            r2 = self._sphere_radius * self._sphere_radius
            d2 = (x - cx) ** 2 + (y - cy) ** 2
            over = d2 <= r2
            t = cz - np.sqrt(np.where(over, r2 - d2, 0.0)) - z
            t = t[over & (t > _EPS)]
            if t.size:
                nearest = min(nearest, float(t.min()))
        return z + nearest if nearest <= max_range else None

    def range_along(
        self, origin: Sequence[float], direction: Sequence[float], max_range: float
    ) -> float | None:
        """Distance along `direction` from `origin` to the first surface within `max_range`, or None.

        The same answer as `raycast` for one ray, by the same rules (the ground seen from above only,
        one-sided surfaces, hits within `_EPS` of the origin ignored), without its per-call overhead: the
        distance sensor asks once per reading, 100 times a second.
        """
        ox, oy, oz = (float(v) for v in origin)
        dx, dy, dz = (float(v) for v in direction)
        norm = math.sqrt(dx * dx + dy * dy + dz * dz)
        if norm == 0.0:
            return None
        dx, dy, dz = dx / norm, dy / norm, dz / norm
        nearest = -oz / dz if dz > 1e-6 and oz < 0.0 else math.inf  # the ground plane
        if self._box_index.size:
            cos, sin = self._box_cos, self._box_sin
            rx, ry, rz = ox - self._box_cols[0], oy - self._box_cols[1], oz - self._box_cols[2]
            local_o = (cos * rx + sin * ry, cos * ry - sin * rx, rz)
            local_d = (cos * dx + sin * dy, cos * dy - sin * dx, np.full_like(cos, dz))
            near, far = None, None
            with np.errstate(divide="ignore", invalid="ignore"):
                for axis in range(3):  # the slab test of `_box_pairs`, over boxes instead of pairs
                    da = local_d[axis]
                    exit_half = np.copysign(self._box_half_cols[axis], da)
                    entry = (exit_half + local_o[axis]) * -(1.0 / da)
                    leave = (exit_half - local_o[axis]) * (1.0 / da)
                    near = entry if near is None else np.fmax(near, entry)
                    far = leave if far is None else np.fmin(far, leave)
                t = near[(near <= far) & (near > _EPS)]
            if t.size:
                nearest = min(nearest, float(t.min()))
        if self._sphere_index.size:
            cx, cy, cz = self._sphere_cols
            rx, ry, rz = ox - cx, oy - cy, oz - cz
            b = dx * rx + dy * ry + dz * rz
            disc = b * b - (rx * rx + ry * ry + rz * rz - self._sphere_radius * self._sphere_radius)
            t = -b - np.sqrt(np.maximum(disc, 0.0))
            t = t[(disc >= 0.0) & (t > _EPS)]
            if t.size:
                nearest = min(nearest, float(t.min()))
        return nearest if nearest <= max_range and math.isfinite(nearest) else None

    # ---------------------------------------------------------------- collisions
    def collide_sphere(self, center: np.ndarray, radius: float) -> Contact | None:
        """Deepest overlap of a sphere with a collidable object (the ground is not considered)."""
        c = np.asarray(center, dtype=np.float64).reshape(3)
        if not self.objects:
            return None
        reach = self._bound_radius + radius
        if (((self._bound_center64 - c) ** 2).sum(axis=1) > reach * reach).all():
            return None  # far from every object's bounding sphere: the common case, kept cheap
        best: tuple[float, int, np.ndarray, np.ndarray] | None = None
        candidates = []
        if self._box_index.size:
            depth, points, normals = box_contacts(
                c, radius, self._box_center, self._box_half, self._box_cos, self._box_sin
            )
            candidates.append((depth, self._box_index, points, normals))
        if self._sphere_index.size:
            depth, points, normals = sphere_contacts(c, radius, self._sphere_center, self._sphere_radius)
            candidates.append((depth, self._sphere_index, points, normals))
        for depth, objs, points, normals in candidates:
            collidable = np.array([self.objects[i].collidable for i in objs], dtype=bool)
            depth = np.where(collidable, depth, -np.inf)
            k = int(np.argmax(depth))
            if depth[k] > 0.0 and (best is None or depth[k] > best[0]):
                best = (float(depth[k]), int(objs[k]), points[k], normals[k])
        if best is None:
            return None
        depth, i, point, normal = best
        obj = self.objects[i]
        return Contact(obj.name, obj.segmentation_id, c.copy(), point, normal, depth)
