"""`createVoxelGrid`: which cells of a box of the world are occupied, in the real server's layout.

The real server (Unreal plugin, `WorldSimApi::createVoxelGrid`) truncates the three sizes to whole metres,
makes `int(size / res)` cells along each axis, and tests cell (i, j, k) as a cube of edge `res` centred at
`position + ((i - nx // 2) * res, (j - ny // 2) * res, (k - nz // 2) * res)` in Unreal's axes (north,
east, up), so k counts upwards. Cell (i, j, k) is element `i + nx * (k + nz * j)` of the flat list of
booleans it returns; the client's `AStarPlanner.get_grid_idx` and `utils.get_voxel_grid_idx` read it so.
The rotation of `position` is not used.

A cell is occupied when its cube overlaps a collidable object (its interior, not just a face) or straddles
the ground plane. The ground is a surface, as in every other sense of this server: the cells below it are
free, as under the real server's floor mesh. The client relies on that: `generate_intercept_trajectory`
centres its grid at the negated (up) height, below the ground, and plans in the grid as if it were at
the right height. Robots and env actors are not in the grid; objects named in `actors_to_ignore` are
left out. Everything is vectorised over the cells near each object.
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Mapping
from typing import Any

import numpy as np

from airsim_mapper.simserver.wire import messages
from airsim_mapper.simserver.wire.services import ServiceError
from airsim_mapper.simserver.world.world import World

MAX_CELLS = 64_000_000  # a list of that many booleans is already 64 MB on the wire
_TOUCH = 1e-9  # cubes that only touch a surface are free


class VoxelGridError(ServiceError):
    """A createVoxelGrid request the server cannot answer (a parameter error, code 2)."""

    def __init__(self, message: str) -> None:
        super().__init__(message, code=2.0)


def grid_shape(x_size: Any, y_size: Any, z_size: Any, res: Any) -> tuple[int, int, int]:
    """Cells along north, east and up: the real server's `int(int(size) / res)` for each size (a size below
    the resolution gives no cells, and the grid is empty, as from the real server)."""
    values = {"x_size": x_size, "y_size": y_size, "z_size": z_size, "res": res}
    for key, value in values.items():
        if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
            raise VoxelGridError(f"Parameter '{key}' must be a finite number, got {value!r}")
    if res <= 0:
        raise VoxelGridError(f"Parameter 'res' must be positive, got {res!r}")
    if min(x_size, y_size, z_size) < 0:
        raise VoxelGridError(f"the sizes must not be negative, got {x_size}, {y_size}, {z_size}")
    shape = tuple(int(int(size) / res) for size in (x_size, y_size, z_size))
    if math.prod(shape) > MAX_CELLS:
        raise VoxelGridError(f"the grid would have {math.prod(shape)} cells (at most {MAX_CELLS})")
    return shape  # type: ignore[return-value]


def cell_centres(center: np.ndarray, shape: tuple[int, int, int], res: float) -> tuple[np.ndarray, ...]:
    """World NED north (nx,), east (ny,) and down (nz,) coordinates of the cell centres along each axis."""
    nx, ny, nz = shape
    north = center[0] + (np.arange(nx) - nx // 2) * res
    east = center[1] + (np.arange(ny) - ny // 2) * res
    down = center[2] - (np.arange(nz) - nz // 2) * res
    return north, east, down


def occupancy(
    world: World, center: np.ndarray, shape: tuple[int, int, int], res: float, ignore: Iterable[str] = ()
) -> np.ndarray:
    """The flat boolean grid, element `i + nx * (k + nz * j)` for cell (i north, j east, k up)."""
    if min(shape) == 0:
        return np.zeros(0, dtype=bool)
    north, east, down = cell_centres(np.asarray(center, dtype=float), shape, res)
    half = res / 2.0
    occupied = np.zeros((shape[1], shape[2], shape[0]), dtype=bool)  # [j, k, i]: C order is the real layout
    occupied[:, np.abs(down) < half - _TOUCH, :] = True  # the cubes the ground plane z = 0 cuts
    skip = set(ignore)
    for obj in world.objects:
        if not obj.collidable or obj.name in skip:
            continue
        reach = obj.radius + half
        i = _span(north, obj.center[0], reach)
        j = _span(east, obj.center[1], reach)
        k = _span(down, obj.center[2], reach)
        if i.start >= i.stop or j.start >= j.stop or k.start >= k.stop:
            continue
        dx = north[i][None, None, :] - obj.center[0]
        dy = east[j][:, None, None] - obj.center[1]
        dz = down[k][None, :, None] - obj.center[2]
        if obj.shape == "sphere":
            gap = [np.maximum(np.abs(d) - half, 0.0) for d in (dx, dy, dz)]
            hit = gap[0] ** 2 + gap[1] ** 2 + gap[2] ** 2 < (obj.size[0] / 2.0) ** 2 - _TOUCH
        else:
            hit = _box_overlap(obj.size / 2.0, obj.yaw, dx, dy, dz, half)
        occupied[j, k, i] |= hit
    return occupied.ravel()


def _span(axis: np.ndarray, centre: float, reach: float) -> slice:
    """The index range of cells along one axis whose centres lie within `reach` of `centre`."""
    inside = np.flatnonzero(np.abs(axis - centre) < reach)
    return slice(int(inside[0]), int(inside[-1]) + 1) if inside.size else slice(0, 0)


def _box_overlap(half_size: np.ndarray, yaw: float, dx, dy, dz, half: float) -> np.ndarray:
    """Whether axis-aligned cubes (half edge `half`, centres offset dx, dy, dz from the box centre) overlap a
    box yawed about the down axis: the separating-axis test on the world and the box's horizontal axes."""
    cos, sin = abs(math.cos(yaw)), abs(math.sin(yaw))
    c, s = math.cos(yaw), math.sin(yaw)
    hx, hy, hz = (float(v) for v in half_size)
    overlap = np.abs(dz) < hz + half - _TOUCH
    overlap = overlap & (np.abs(dx) < cos * hx + sin * hy + half - _TOUCH)
    overlap = overlap & (np.abs(dy) < sin * hx + cos * hy + half - _TOUCH)
    cube_on_box_axes = half * (cos + sin)
    overlap = overlap & (np.abs(c * dx + s * dy) < hx + cube_on_box_axes - _TOUCH)
    return overlap & (np.abs(c * dy - s * dx) < hy + cube_on_box_axes - _TOUCH)


def create_voxel_grid(world: World, params: Mapping[str, Any]) -> list[bool]:
    """The `createVoxelGrid` service method."""
    position = params["position"]
    if not isinstance(position, Mapping):
        raise VoxelGridError(f"Parameter 'position' must be a pose, got {position!r}")
    try:
        center = messages.parse_vector3(position.get("translation"), "position translation")
    except messages.MessageError as exc:
        raise VoxelGridError(str(exc)) from exc
    shape = grid_shape(params["x_size"], params["y_size"], params["z_size"], params["res"])
    ignore = params["actors_to_ignore"]
    if not isinstance(ignore, list) or not all(isinstance(name, str) for name in ignore):
        raise VoxelGridError(f"Parameter 'actors_to_ignore' must be a list of names, got {ignore!r}")
    return occupancy(world, center, shape, float(params["res"]), ignore).tolist()


VOXEL_GRID_PARAMS = ("position", "x_size", "y_size", "z_size", "res", "actors_to_ignore")
