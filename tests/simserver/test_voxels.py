"""createVoxelGrid's occupancy and layout (pure): read back with the 1.1.0 client's own index helpers."""

from __future__ import annotations

import math

import numpy as np
import pytest
from projectairsim.planners import AStarPlanner
from projectairsim.utils import get_voxel_grid_idx

from airsim_mapper.simserver.scene import voxels
from airsim_mapper.simserver.world.world import World
from airsim_mapper.simserver.world.world_file import load_world, world_from_dict


def grid(world: World, center=(0.0, 0.0, 0.0), size=20, res=1.0, ignore=()) -> list[bool]:
    params = {
        "position": {"translation": dict(zip("xyz", center)), "rotation": {"w": 0, "x": 0, "y": 0, "z": 0}},
        "x_size": size,
        "y_size": size,
        "z_size": size,
        "res": res,
        "actors_to_ignore": list(ignore),
    }
    return voxels.create_voxel_grid(world, params)


def one(shape: str, **keys) -> World:
    entry = {"name": "Thing", "shape": shape, "segmentation-id": 5, "color-bgr": [1, 2, 3], **keys}
    return world_from_dict({"objects": [entry]})


def occupied(world: World, ned, **kwargs) -> bool:
    """The cell holding NED point `ned`, found the way the client's planner finds it."""
    size, res = kwargs.get("size", 20), kwargs.get("res", 1.0)
    cells = grid(world, size=size, res=res)
    planner = AStarPlanner(cells, (0, 0, 0), (size, size, size), res)
    return bool(cells[planner.get_grid_idx((ned[0], ned[1], -ned[2]))])


def test_the_layout_is_the_real_servers_and_the_clients_helpers_read_it():
    world = one("box", center=[3, -2, -5], size=[1, 1, 1])
    cells = grid(world)
    # the layer the ground cuts (up 0: from -0.5 to 0.5), and one box cell
    assert len(cells) == 20**3 and sum(cells) == 20 * 20 + 1
    # cell (i, j, k) centred at (i - 10, j - 10, up k - 10) is element i + 20 * (k + 20 * j)
    i, j, k = 3 + 10, -2 + 10, 5 + 10
    assert cells[i + 20 * (k + 20 * j)] is True
    assert cells[get_voxel_grid_idx([3, -2, -5], [0, 0, 0], (20, 20, 20), 1)] is True
    assert cells[get_voxel_grid_idx([3, -2, -6], [0, 0, 0], (20, 20, 20), 1)] is False


def test_the_ground_is_a_surface_occupying_the_cells_it_cuts():
    world = World([])
    assert occupied(world, (0, 0, -1)) is False  # the cube spans z -1.5 .. -0.5
    assert occupied(world, (0, 0, 0)) is True  # -0.5 .. 0.5: the ground cuts it
    assert occupied(world, (4, 4, 5)) is False  # below the ground, as under the real server's floor
    at_half = grid(World([]), size=20, res=1.0, center=(0.0, 0.0, -0.5))  # cubes touch z = 0: all free
    assert sum(at_half) == 0


def test_a_cube_that_only_touches_a_face_is_free():
    world = one("box", center=[0, 0, -5], size=[3, 3, 3])  # x from -1.5 to 1.5
    assert occupied(world, (1, 0, -5)) is True
    assert occupied(world, (2, 0, -5)) is False  # spans 1.5 .. 2.5: touches the face
    assert occupied(world, (0, 0, -7)) is False and occupied(world, (0, 0, -6)) is True


def test_a_yawed_box_leaves_the_corners_of_its_bounding_box_free():
    world = one("box", center=[0, 0, -5], size=[8, 1, 1], **{"yaw-deg": 45})
    assert occupied(world, (2, 2, -5)) is True  # on the box's long axis
    assert occupied(world, (-2, -2, -5)) is True
    assert occupied(world, (2, -2, -5)) is False  # inside the world-aligned bounds, off the box
    assert occupied(world, (3, 0, -5)) is False


def test_a_sphere_leaves_the_cells_off_its_diagonal_free():
    world = one("sphere", center=[0, 0, -6], radius=2.0)
    assert occupied(world, (2, 0, -6)) is True  # the cube from 1.5 overlaps the sphere to 2
    assert occupied(world, (2, 2, -6)) is False  # nearest cube corner at 1.5*sqrt(2) = 2.12
    assert occupied(world, (0, 0, -9)) is False


def test_ignored_and_non_collidable_objects_are_left_out():
    world = one("box", center=[0, 0, -5], size=[1, 1, 1])
    base = sum(grid(World([])))
    assert sum(grid(world)) == base + 1
    assert sum(grid(world, ignore=["Thing", "NoSuchActor"])) == base
    pad = one("box", center=[0, 0, -5], size=[1, 1, 1], collidable=False)
    assert sum(grid(pad)) == base


def test_sizes_are_truncated_to_whole_metres_and_cells_counted_as_the_real_server_does():
    assert voxels.grid_shape(10.9, 7.0, 5.5, 2.0) == (5, 3, 2)
    assert voxels.grid_shape(44.0, 44.0, 44.0, 2.0) == (22, 22, 22)
    assert grid(World([]), size=1, res=2.0) == []  # fewer metres than the resolution: no cells
    with pytest.raises(voxels.VoxelGridError, match="'res' must be positive") as err:
        voxels.grid_shape(10, 10, 10, 0)
    assert err.value.code == 2.0
    with pytest.raises(voxels.VoxelGridError, match="must not be negative"):
        voxels.grid_shape(-10, 10, 10, 1)
    with pytest.raises(voxels.VoxelGridError, match="at most"):
        voxels.grid_shape(1000, 1000, 1000, 0.1)
    with pytest.raises(voxels.VoxelGridError, match="finite"):
        voxels.grid_shape(math.nan, 1, 1, 1)


def test_a_bad_pose_or_ignore_list_is_a_parameter_error():
    with pytest.raises(voxels.VoxelGridError, match="translation"):
        voxels.create_voxel_grid(World([]), {**_params(), "position": {"rotation": {}}})
    with pytest.raises(voxels.VoxelGridError, match="actors_to_ignore"):
        voxels.create_voxel_grid(World([]), {**_params(), "actors_to_ignore": "Drone1"})


def _params() -> dict:
    return {
        "position": {"translation": {"x": 0, "y": 0, "z": 0}},
        "x_size": 4,
        "y_size": 4,
        "z_size": 4,
        "res": 1,
        "actors_to_ignore": [],
    }


def test_the_planner_finds_a_way_around_the_default_worlds_block():
    world = load_world()
    cells = grid(world, center=(30.0, 0.0, -5.0), size=30, res=1.0)
    planner = AStarPlanner(cells, (30, 0, -5), (30, 30, 30), 1)
    path = planner.generate_plan((22, 0, -5), (38, 0, -5))  # through BlockNorth, 4 x 8 x 10 at (30, 0, -5)
    assert path and tuple(path[-1]) == (38, 0, -5)
    block = world.object_named("BlockNorth")
    for point in np.asarray(path, dtype=float):
        inside = np.abs(point - block.center) < block.size / 2.0 + 0.5
        assert not inside.all(), f"the path passes through the block at {point}"
