"""The world: loading the world file, ray casting against ground / boxes / spheres, sphere collisions."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

from airsim_mapper.simserver.world import world as world_module
from airsim_mapper.simserver.world.world import GROUND_INDEX, MISS_INDEX, World, WorldObject
from airsim_mapper.simserver.world.world_file import (
    DEFAULT_WORLD_PATH,
    WorldError,
    load_world,
    world_from_dict,
)


@pytest.fixture(scope="module")
def world() -> World:
    return load_world()


def index_of(world: World, name: str) -> int:
    return [o.name for o in world.objects].index(name)


def box(name, center, size, yaw_deg=0.0, seg=50) -> WorldObject:
    return WorldObject(
        name, "box", np.array(center, float), np.array(size, float), math.radians(yaw_deg), seg, (1, 2, 3)
    )


def sphere(name, center, radius, seg=60) -> WorldObject:
    return WorldObject(name, "sphere", np.array(center, float), np.full(3, 2.0 * radius), 0.0, seg, (4, 5, 6))


def reference_distance(world: World, origin: np.ndarray, direction: np.ndarray) -> float:
    """Scalar, obviously-correct intersection of one ray (for checking the vectorised caster)."""
    best = -origin[2] / direction[2] if direction[2] > 1e-6 and origin[2] < 0 else math.inf
    for obj in world.objects:
        if obj.shape == "sphere":
            rel = origin - obj.center
            b = direction @ rel
            disc = b * b - (rel @ rel - (obj.size[0] / 2) ** 2)
            t = -b - math.sqrt(disc) if disc >= 0 else math.inf
        else:
            c, s = math.cos(obj.yaw), math.sin(obj.yaw)
            to_local = np.array([[c, s, 0], [-s, c, 0], [0, 0, 1]])
            o, d = to_local @ (origin - obj.center), to_local @ direction
            near, far = -math.inf, math.inf
            for a in range(3):
                h = obj.size[a] / 2
                if abs(d[a]) < 1e-12:
                    if abs(o[a]) > h:
                        near, far = math.inf, -math.inf
                    continue
                t1, t2 = (-h - o[a]) / d[a], (h - o[a]) / d[a]
                near, far = max(near, min(t1, t2)), min(far, max(t1, t2))
            t = near if near <= far else math.inf
        if 1e-4 < t < best:
            best = t
    return best


def test_default_world_has_ground_pad_ball_and_boxes_with_distinct_segmentation_ids(world):
    names = [o.name for o in world.objects]
    assert {"LandingPad", "OrangeBall"} <= set(names)
    assert sum(o.shape == "box" for o in world.objects) >= 4
    ids = [o.segmentation_id for o in world.objects] + [world.ground_segmentation_id]
    assert len(set(ids)) == len(ids)
    assert world.object_named("OrangeBall").shape == "sphere"
    assert world.object_named("OrangeBall").color_bgr == (0, 140, 255)
    pad = world.object_named("LandingPad")
    assert np.allclose(pad.center[:2], 0.0) and pad.center[2] + pad.size[2] / 2 == pytest.approx(0.0)


def test_loading_without_a_path_reads_the_shipped_default_world_file(world):
    explicit = load_world(DEFAULT_WORLD_PATH)
    assert [o.name for o in explicit.objects] == [o.name for o in world.objects]
    assert world.source == str(DEFAULT_WORLD_PATH)


def test_object_named_returns_none_for_an_unknown_name(world):
    assert world.object_named("NoSuchThing") is None


def test_a_ray_straight_down_hits_the_ground_plane_at_the_height(world):
    hits = world.raycast(np.array([-40.0, 40.0, -7.5]), np.array([[0.0, 0.0, 1.0]]), 100.0)
    assert hits.distance[0] == pytest.approx(7.5)
    assert hits.object_index[0] == GROUND_INDEX
    assert hits.segmentation_id[0] == world.ground_segmentation_id
    assert np.allclose(hits.normal[0], [0.0, 0.0, -1.0])


def test_a_ray_hits_the_near_face_of_a_box_with_its_outward_normal(world):
    hits = world.raycast(np.array([20.0, 0.0, -5.0]), np.array([[1.0, 0.0, 0.0]]), 100.0)
    assert hits.distance[0] == pytest.approx(8.0)  # BlockNorth spans x 28..32
    assert hits.object_index[0] == index_of(world, "BlockNorth")
    assert hits.segmentation_id[0] == 20
    assert np.allclose(hits.normal[0], [-1.0, 0.0, 0.0])


def test_a_yawed_box_is_hit_on_its_rotated_face(world):
    block = world.object_named("BlockEast")  # 6 m cube yawed 30 degrees
    axis = np.array([math.cos(block.yaw), math.sin(block.yaw), 0.0])
    origin = block.center - 10.0 * axis
    hits = world.raycast(origin, axis[None, :], 100.0)
    assert hits.distance[0] == pytest.approx(7.0, abs=1e-4)
    assert np.allclose(hits.normal[0], -axis, atol=1e-6)


def test_a_ray_towards_the_ball_centre_stops_one_radius_short(world):
    ball = world.object_named("OrangeBall")
    origin = np.array([0.0, 0.0, -3.0])
    to_centre = ball.center - origin
    hits = world.raycast(origin, to_centre[None, :], 100.0)
    assert hits.distance[0] == pytest.approx(np.linalg.norm(to_centre) - 1.0, abs=1e-4)
    assert hits.segmentation_id[0] == ball.segmentation_id
    assert np.allclose(hits.normal[0], -to_centre / np.linalg.norm(to_centre), atol=1e-5)


def test_rays_into_the_sky_miss_with_infinite_distance_and_id_zero(world):
    hits = world.raycast(np.zeros(3) - [0, 0, 1.0], np.array([[0.0, 0.0, -1.0], [1.0, 1.0, -1.0]]), 1e4)
    assert np.isinf(hits.distance).all()
    assert (hits.object_index == MISS_INDEX).all()
    assert (hits.segmentation_id == 0).all()
    assert not hits.hit.any()


def test_hits_beyond_max_range_count_as_misses(world):
    hits = world.raycast(np.array([20.0, 0.0, -5.0]), np.array([[1.0, 0.0, 0.0]]), 7.9)
    assert np.isinf(hits.distance[0]) and hits.object_index[0] == MISS_INDEX


def test_a_ray_starting_inside_an_object_does_not_see_that_object(world):
    ball = world.object_named("OrangeBall")
    hits = world.raycast(ball.center, np.array([[0.0, 0.0, 1.0]]), 100.0)
    assert hits.object_index[0] == GROUND_INDEX
    assert hits.distance[0] == pytest.approx(3.0)


def test_the_nearest_of_several_objects_along_a_ray_wins():
    world = World([box("Far", [20, 0, -2], [2, 2, 2], seg=5), sphere("Near", [10, 0, -2], 1.0, seg=6)])
    hits = world.raycast(np.array([0.0, 0.0, -2.0]), np.array([[1.0, 0.0, 0.0]]), 100.0)
    assert hits.distance[0] == pytest.approx(9.0)
    assert hits.segmentation_id[0] == 6


def test_vectorised_ray_casting_matches_a_scalar_reference_over_many_random_rays(world):
    rng = np.random.default_rng(7)
    count = 20000  # more than one internal block
    origins = rng.uniform([-30, -30, -12], [35, 35, -0.5], size=(count, 3))
    directions = rng.normal(size=(count, 3))
    directions /= np.linalg.norm(directions, axis=1, keepdims=True)
    hits = world.raycast(origins, directions, 1e4)
    sample = rng.choice(count, 300, replace=False)
    expected = np.array([reference_distance(world, origins[i], directions[i]) for i in sample])
    got = hits.distance[sample].astype(float)
    assert np.array_equal(np.isinf(got), np.isinf(expected))
    finite = np.isfinite(expected)
    assert np.allclose(got[finite], expected[finite], rtol=1e-4, atol=1e-3)
    assert (hits.object_index >= 0).sum() > 100  # the sample is not only ground and sky


def test_a_shared_origin_gives_the_same_hits_as_repeating_it_per_ray(world):
    rng = np.random.default_rng(3)
    directions = rng.normal(size=(500, 3))
    origin = np.array([18.0, 12.0, -3.5])
    shared = world.raycast(origin, directions, 1e3)
    repeated = world.raycast(np.tile(origin, (500, 1)), directions, 1e3)
    assert np.array_equal(shared.object_index, repeated.object_index)
    assert np.allclose(shared.distance, repeated.distance, equal_nan=True)
    assert np.allclose(shared.normal, repeated.normal, atol=1e-5)


def test_surface_below_matches_a_straight_down_ray_cast_everywhere():
    scene = World(
        [
            box("Yawed", [3.0, -2.0, -2.0], [4.0, 2.0, 4.0], yaw_deg=30.0),
            box("Tower", [3.0, -2.0, -8.0], [1.0, 1.0, 2.0]),  # above Yawed: the first surface wins
            sphere("Ball", [-4.0, 3.0, -3.0], 2.0),
        ]
    )
    rng = np.random.default_rng(11)
    points = rng.uniform([-8, -6, -12], [8, 6, 1], size=(3000, 3))  # some inside objects, some underground
    hits = scene.raycast(points, np.tile([0.0, 0.0, 1.0], (len(points), 1)), 1000.0)
    for point, distance in zip(points, hits.distance.astype(float)):
        got = scene.surface_below(point, 1000.0)
        if math.isinf(distance):
            assert got is None, point
        else:
            assert got == pytest.approx(point[2] + distance, abs=1e-3), point
    kinds = set(hits.object_index.tolist())
    assert {GROUND_INDEX, MISS_INDEX, 0, 1, 2} <= kinds  # every case was met
    assert scene.surface_below([3.0, -2.0, -20.0], 5.0) is None  # the tower's top is 11 m down


def test_range_along_matches_a_one_ray_cast_in_every_direction():
    scene = World(
        [
            box("Yawed", [3.0, -2.0, -2.0], [4.0, 2.0, 4.0], yaw_deg=30.0),
            box("Tower", [3.0, -2.0, -8.0], [1.0, 1.0, 2.0]),
            sphere("Ball", [-4.0, 3.0, -3.0], 2.0),
        ]
    )
    rng = np.random.default_rng(12)
    points = rng.uniform([-8, -6, -12], [8, 6, 1], size=(3000, 3))  # some inside objects, some underground
    directions = rng.normal(size=(3000, 3))
    directions[:300] = [0.0, 0.0, 1.0]  # straight down, and axis-parallel rays, the slab test's edge case
    directions[300:600] = [1.0, 0.0, 0.0]
    hits = scene.raycast(points, directions, 30.0)
    for point, direction, distance in zip(points, directions, hits.distance.astype(float)):
        got = scene.range_along(point, direction, 30.0)
        if math.isinf(distance):
            assert got is None, (point, direction)
        else:
            assert got == pytest.approx(distance, abs=1e-3), (point, direction)
    kinds = set(hits.object_index.tolist())
    assert {GROUND_INDEX, MISS_INDEX, 0, 1, 2} <= kinds  # every case was met
    assert scene.range_along([0.0, 0.0, -5.0], [0.0, 0.0, 0.0], 30.0) is None
    assert scene.range_along([0.0, 0.0, -5.0], [0.0, 0.0, -1.0], math.inf) is None  # up, into the sky


def test_collision_checks_far_from_every_object_skip_the_exact_test(world, monkeypatch):
    calls = []
    monkeypatch.setattr(world_module, "box_contacts", lambda *a: calls.append(a))
    assert world.collide_sphere(np.array([-50.0, -50.0, -10.0]), 0.5) is None
    assert calls == []


def test_raycast_rejects_a_mismatched_number_of_origins(world):
    with pytest.raises(ValueError, match="raycast: 2 origins for 3 directions"):
        world.raycast(np.zeros((2, 3)), np.ones((3, 3)), 10.0)


def test_a_sphere_touching_the_ball_reports_a_contact_with_depth_normal_and_impact_point(world):
    contact = world.collide_sphere(np.array([20.0, 20.0, -4.3]), 0.5)  # ball centre (20, 20, -3), r 1
    assert contact is not None
    assert contact.object_name == "OrangeBall" and contact.segmentation_id == 11
    assert contact.penetration_depth == pytest.approx(0.2)
    assert np.allclose(contact.normal, [0.0, 0.0, -1.0])
    assert np.allclose(contact.impact_point, [20.0, 20.0, -4.0])
    assert np.allclose(contact.position, [20.0, 20.0, -4.3])


def test_a_sphere_near_a_box_face_is_pushed_out_along_the_face_normal(world):
    contact = world.collide_sphere(np.array([27.8, 1.0, -5.0]), 0.5)  # BlockNorth face at x = 28
    assert contact.object_name == "BlockNorth"
    assert contact.penetration_depth == pytest.approx(0.3)
    assert np.allclose(contact.normal, [-1.0, 0.0, 0.0])
    assert np.allclose(contact.impact_point, [28.0, 1.0, -5.0])


def test_a_sphere_centred_inside_a_box_leaves_through_the_nearest_face(world):
    contact = world.collide_sphere(np.array([28.5, 0.0, -5.0]), 0.4)
    assert contact.object_name == "BlockNorth"
    assert contact.penetration_depth == pytest.approx(0.9)
    assert np.allclose(contact.normal, [-1.0, 0.0, 0.0])


def test_no_contact_in_free_space_and_none_with_the_non_collidable_landing_pad(world):
    assert world.collide_sphere(np.array([0.0, 0.0, -10.0]), 0.5) is None
    assert world.collide_sphere(np.array([0.0, 0.0, -0.1]), 0.4) is None  # resting on the pad
    assert world.object_named("LandingPad").collidable is False


def write(tmp_path, data, name="world.json"):
    path = tmp_path / name
    path.write_text(json.dumps(data) if name.endswith(".json") else data)
    return path


def minimal_object(**overrides):
    entry = {"name": "A", "shape": "box", "center": [0, 0, -1], "size": [1, 1, 1], "segmentation-id": 5}
    entry["color-bgr"] = [1, 2, 3]
    entry.update(overrides)
    return entry


def test_a_yaml_world_file_is_accepted(tmp_path):
    text = "objects:\n  - {name: Ball, shape: sphere, center: [5, 0, -2], radius: 0.5, segmentation-id: 9,\n"
    text += "     color-bgr: [0, 0, 255]}\n"
    world = load_world(write(tmp_path, text, "w.yaml"))
    assert world.object_named("Ball").size.tolist() == [1.0, 1.0, 1.0]


@pytest.mark.parametrize(
    ("data", "key", "problem"),
    [
        ([], "<top level>", "must be a mapping"),
        ({"version": 2}, "version", "must be 1"),
        ({"colour": 1}, "<top level>.colour", "unknown key"),
        ({"objects": {}}, "objects", "must be a list"),
        ({"objects": [minimal_object(shape="cone")]}, "objects[0].shape", "must be one of box, sphere"),
        ({"objects": [minimal_object(size=[1, 0, 1])]}, "objects[0].size", "3 positive numbers"),
        ({"objects": [minimal_object(size=[1, 1])]}, "objects[0].size", "list of 3 numbers"),
        ({"objects": [minimal_object(center=[0, "x", 0])]}, "objects[0].center[1]", "finite number"),
        ({"objects": [minimal_object(shape="sphere")]}, "objects[0].radius", "required for a sphere"),
        ({"objects": [minimal_object(shape="sphere", radius=-1)]}, "objects[0].radius", "must be positive"),
        ({"objects": [{"name": "A"}]}, "objects[0].shape", "is required"),
        ({"objects": [minimal_object(**{"color-bgr": [0, 0, 300]})]}, "objects[0].color-bgr", "0-255"),
        ({"objects": [minimal_object(**{"segmentation-id": 0})]}, "objects[0].segmentation-id", "1-255"),
        ({"objects": [minimal_object(**{"segmentation-id": 1})]}, "objects[0].segmentation-id", "ground's"),
        ({"objects": [minimal_object(collidable="yes")]}, "objects[0].collidable", "true or false"),
        (
            {"objects": [minimal_object(), minimal_object(**{"segmentation-id": 6})]},
            "objects[1].name",
            "duplicate",
        ),
        ({"objects": [minimal_object(spin=1)]}, "objects[0].spin", "unknown key"),
        ({"ground": {"segmentation-id": 300}}, "ground.segmentation-id", "1-255"),
        ({"sky": []}, "sky", "must be a mapping"),
    ],
)
def test_world_file_errors_name_the_file_and_the_key(tmp_path, data, key, problem):
    path = write(tmp_path, data)
    with pytest.raises(WorldError, match=r"world file .*world\.json: key") as caught:
        load_world(path)
    assert caught.value.key == key
    assert str(path) in str(caught.value)
    assert problem in caught.value.problem


def test_a_missing_world_file_is_reported_with_its_path(tmp_path):
    with pytest.raises(WorldError, match=r"world file .*nope\.json: key '<file>': cannot be read"):
        load_world(tmp_path / "nope.json")


def test_a_world_file_that_is_not_json_is_reported_with_its_path(tmp_path):
    path = tmp_path / "bad.json"
    path.write_text("{not json")
    with pytest.raises(WorldError, match=r"bad\.json: key '<file>': is not valid json"):
        load_world(path)


def test_world_from_dict_builds_an_empty_world_with_only_the_ground():
    world = world_from_dict({})
    assert world.objects == ()
    hits = world.raycast(np.array([0.0, 0.0, -2.0]), np.array([[0.0, 0.0, 1.0], [1.0, 0.0, 0.0]]), 10.0)
    assert hits.distance[0] == pytest.approx(2.0) and np.isinf(hits.distance[1])
