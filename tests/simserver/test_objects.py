"""Scene objects (pure): glTF bounds, listing, poses, spawning and the world the sensors then see."""

from __future__ import annotations

import json
import math
import struct

import numpy as np
import pytest

from airsim_mapper.common.geometry import quat_from_rpy
from airsim_mapper.simserver.scene.objects import LiveWorld, SceneObjects
from airsim_mapper.simserver.wire.services import ServiceError
from airsim_mapper.simserver.world import gltf
from airsim_mapper.simserver.world.world_file import load_world


def box_gltf(minimum, maximum, node: dict | None = None, color=(1.0, 0.0, 0.0, 1.0)) -> dict:
    """A glTF document with one mesh whose POSITION accessor spans minimum..maximum."""
    return {
        "asset": {"version": "2.0"},
        "scene": 0,
        "scenes": [{"nodes": [0]}],
        "nodes": [{"children": [1], "translation": [0, 0, 0]}, {"mesh": 0, **(node or {})}],
        "meshes": [{"primitives": [{"attributes": {"POSITION": 0}, "material": 0}]}],
        "materials": [{"pbrMetallicRoughness": {"baseColorFactor": list(color)}}],
        "accessors": [{"count": 8, "type": "VEC3", "componentType": 5126, "min": minimum, "max": maximum}],
    }


def glb(document: dict) -> bytes:
    text = json.dumps(document).encode()
    text += b" " * (-len(text) % 4)
    return struct.pack("<4sII", b"glTF", 2, 20 + len(text)) + struct.pack("<II", len(text), 0x4E4F534A) + text


def test_gltf_y_up_becomes_ned_up_and_node_transforms_apply():
    bounds = gltf.model_bounds(json.dumps(box_gltf([-1, 0, -2], [1, 3, 2])).encode())
    # glTF (x, y, z) is NED (x, z, -y): 3 m tall is 3 m up
    assert bounds.minimum.tolist() == [-1, -2, -3] and bounds.maximum.tolist() == [1, 2, 0]
    assert bounds.color_bgr == (0, 0, 255)
    moved = box_gltf([-1, -1, -1], [1, 1, 1], {"translation": [10, 0, 0], "scale": [2, 1, 1]})
    bounds = gltf.model_bounds(glb(moved))
    assert bounds.minimum.tolist() == [8, -1, -1] and bounds.maximum.tolist() == [12, 1, 1]
    quarter = [0, math.sin(math.pi / 4), 0, math.cos(math.pi / 4)]
    turned = box_gltf([0, 0, 0], [2, 1, 1], {"rotation": quarter})
    bounds = gltf.model_bounds(json.dumps(turned).encode())  # 90 deg about glTF up: x becomes -z
    assert np.allclose(bounds.minimum, [0, -2, -1]) and np.allclose(bounds.maximum, [1, 0, 0])


@pytest.mark.parametrize(
    ("data", "problem"),
    [
        (b"\x00\x01binary", "not glTF JSON"),
        (json.dumps({"asset": {"version": "1.0"}}).encode(), "glTF 2.0"),
        (json.dumps({"asset": {"version": "2.0"}, "nodes": []}).encode(), "no mesh"),
        (b"glTF\x02\x00\x00\x00", "shorter than its header"),
    ],
)
def test_bytes_that_are_not_a_gltf_model_are_named_as_such(data, problem):
    with pytest.raises(gltf.GltfError, match=problem):
        gltf.model_bounds(data)


def test_an_accessor_without_bounds_is_refused():
    document = box_gltf([0, 0, 0], [1, 1, 1])
    del document["accessors"][0]["min"]
    with pytest.raises(gltf.GltfError, match="no min and max"):
        gltf.model_bounds(json.dumps(document).encode())


@pytest.fixture
def scene():
    world = LiveWorld(load_world())
    actors = {"Drone1": (np.array([0.0, 0.0, -4.0]), np.array([1.0, 0.0, 0.0, 0.0]))}
    return world, SceneObjects(world, lambda: dict(actors))


def pose(x, y, z, yaw=0.0) -> dict:
    q = quat_from_rpy(0.0, 0.0, yaw)
    return {"translation": {"x": x, "y": y, "z": z}, "rotation": dict(zip("wxyz", q.tolist()))}


def test_objects_are_listed_by_full_regex_match_with_robots_and_env_actors(scene):
    _, objects = scene
    assert objects.list_objects({"name": "Block.*"}) == ["BlockNorth", "BlockEast", "BlockSouthWest"]
    assert objects.list_objects({"name": "Block"}) == []  # a full match, as std::regex_match
    assert "Drone1" in objects.list_objects({"name": ".*"})
    assert objects.list_assets({"name": ".*"}) == ["Cube", "Sphere"]
    with pytest.raises(ServiceError, match="Invalid regex"):
        objects.list_objects({"name": "("})


def test_poses_are_read_and_set_and_the_sensors_see_the_move(scene):
    world, objects = scene
    ball = objects.get_pose({"object_name": "OrangeBall"})
    assert ball["translation"] == {"x": 20.0, "y": 20.0, "z": -3.0} and ball["rotation"]["w"] == 1.0
    assert objects.get_pose({"object_name": "Drone1"})["translation"]["z"] == -4.0
    missing = objects.get_pose({"object_name": "Nothing"})["translation"]
    assert all(math.isnan(v) for v in missing.values())  # the real server's reply for an unknown name
    down = np.array([[0.0, 0.0, 1.0]])
    assert world.raycast(np.array([0.0, 40.0, -20.0]), down, 100.0).distance[0] == pytest.approx(20.0)
    assert objects.set_pose({"object_name": "OrangeBall", "pose": pose(0, 40, -3), "teleport": True}) is True
    assert world.raycast(np.array([0.0, 40.0, -20.0]), down, 100.0).distance[0] == pytest.approx(16.0)
    assert objects.get_poses({"object_names": ["OrangeBall"]})[0]["translation"]["y"] == 40.0
    with pytest.raises(ServiceError, match="No objects of name Ghost"):
        objects.set_pose({"object_name": "Ghost", "pose": pose(0, 0, 0), "teleport": True})
    with pytest.raises(ServiceError, match="Unable to move object Drone1"):
        objects.set_pose({"object_name": "Drone1", "pose": pose(0, 0, 0), "teleport": True})


def test_a_turned_box_keeps_its_size_and_takes_the_yaw(scene):
    world, objects = scene
    turned = pose(0, 0, -7.5, yaw=math.pi / 2)
    objects.set_pose({"object_name": "PillarWest", "pose": turned, "teleport": False})
    pillar = world.object_named("PillarWest")
    assert pillar.yaw == pytest.approx(math.pi / 2) and pillar.size.tolist() == [2, 2, 15]


def test_a_gltf_model_spawns_as_its_bounds_under_a_unique_name(scene):
    world, objects = scene
    data = json.dumps(box_gltf([-1, 0, -1], [1, 4, 1])).encode()  # 2 x 2 footprint, 4 m tall
    params = {
        "object_name": "Tower",
        "file_format": "gltf",
        "byte_array": data,
        "is_binary": False,
        "pose": pose(0, 40, 0),
        "scale": [1.0, 1.0, 2.0],  # Unreal's z: twice as tall
        "enable_physics": False,
    }
    assert objects.spawn_from_file(params) == "Tower"
    assert objects.spawn_from_file(params) == "Tower1"
    tower = world.object_named("Tower")
    assert tower.center.tolist() == [0, 40, -4] and tower.size.tolist() == [2, 2, 8]
    assert tower.color_bgr == (0, 0, 255) and tower.segmentation_id not in (1, 10, 11, 20, 21, 22, 23)
    hit = world.raycast(np.array([0.0, 40.0, -20.0]), np.array([[0.0, 0.0, 1.0]]), 100.0)
    assert hit.distance[0] == pytest.approx(12.0)
    assert world.collide_sphere(np.array([0.0, 40.0, -4.0]), 0.5).object_name in ("Tower", "Tower1")
    assert objects.get_pose({"object_name": "Tower"})["translation"] == {"x": 0.0, "y": 40.0, "z": 0.0}
    assert objects.destroy({"object_name": "Tower1"}) is True
    assert objects.destroy({"object_name": "Tower1"}) is False
    assert objects.destroy_spawned({}) is True
    assert world.object_named("Tower") is None and world.object_named("OrangeBall") is not None


def test_bytes_that_are_not_gltf_spawn_nothing_and_return_the_name(scene, caplog):
    world, objects = scene
    params = {
        "object_name": "Junk",
        "file_format": "gltf",
        "byte_array": b"not a model",
        "is_binary": True,
        "pose": pose(0, 0, 0),
        "scale": [1, 1, 1],
        "enable_physics": False,
    }
    assert objects.spawn_from_file(params) == "Junk"
    assert world.object_named("Junk") is None and "nothing spawned" in caplog.text


def test_asset_spawns_and_their_errors(scene):
    world, objects = scene
    spawn = {"object_name": "Cube", "pose": pose(5, 5, -1), "scale": [2, 2, 2], "enable_physics": True}
    assert objects.spawn_asset({**spawn, "asset_path": "Cube"}) == "Cube"
    assert world.object_named("Cube").size.tolist() == [2, 2, 2]
    with pytest.raises(ServiceError, match="no objects with name Chair found in the Registry"):
        objects.spawn_asset({**spawn, "asset_path": "Chair"})
    with pytest.raises(ServiceError, match="3 positive numbers") as err:
        objects.spawn_asset({**spawn, "asset_path": "Sphere", "scale": [1, 0, 1]})
    assert err.value.code == 2.0


def test_a_new_scene_starts_from_the_world_file(scene):
    world, objects = scene
    objects.set_pose({"object_name": "OrangeBall", "pose": pose(0, 0, -3), "teleport": True})
    assert world.current is not world.base
    SceneObjects(world, dict)
    assert world.current is world.base and world.object_named("OrangeBall").center.tolist() == [20, 20, -3]


def test_spawns_at_a_geo_point_are_placed_from_the_home_point(scene):
    world, objects = scene
    lat, lon, alt = objects.home
    params = {
        "object_name": "Marker",
        "asset_path": "Sphere",
        "latitude": lat + 1e-4,
        "longitude": lon,
        "altitude": alt + 5.0,
        "rotation": [1.0, 0.0, 0.0, 0.0],
        "scale": [2.0, 2.0, 2.0],
        "enable_physics": False,
    }
    assert objects.spawn_asset_at_geo(params) == "Marker"
    marker = world.object_named("Marker")
    assert marker.shape == "sphere" and marker.radius == pytest.approx(1.0)
    assert marker.center == pytest.approx([11.13, 0.0, -5.0], abs=0.01)
    with pytest.raises(ServiceError, match="rotation"):
        objects.spawn_asset_at_geo({**params, "rotation": [1.0, 0.0]})
