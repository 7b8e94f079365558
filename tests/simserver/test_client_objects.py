"""Scene objects through the real 1.1.0 client, as the client's example scripts call them: the voxel grid
its planners read, object listing and poses, glTF models spawned (by call and from a scene's
`spawn-objects`) that the cameras then see, and env actors that follow the trajectory in their config."""

from __future__ import annotations

import copy
import json
import math
import struct

import pytest
from projectairsim import Drone, EnvActor, World
from projectairsim.planners import AStarPlanner
from projectairsim.types import Pose
from projectairsim.utils import unpack_image

from simserver.clientkit import load_world, scene_config, settle, subscribe


def pose(x: float, y: float, z: float) -> Pose:
    rotation = {"w": 1.0, "x": 0.0, "y": 0.0, "z": 0.0}
    return Pose({"translation": {"x": x, "y": y, "z": z}, "rotation": rotation, "frame_id": "DEFAULT_ID"})


def tower_glb(height: float, half_width: float) -> bytes:
    """A binary glTF whose only mesh spans `height` metres up (glTF +Y) on a square footprint."""
    document = {
        "asset": {"version": "2.0"},
        "scenes": [{"nodes": [0]}],
        "nodes": [{"mesh": 0}],
        "meshes": [{"primitives": [{"attributes": {"POSITION": 0}}]}],
        "accessors": [
            {
                "count": 8,
                "type": "VEC3",
                "componentType": 5126,
                "min": [-half_width, 0.0, -half_width],
                "max": [half_width, height, half_width],
            }
        ],
    }
    text = json.dumps(document).encode()
    text += b" " * (-len(text) % 4)
    return struct.pack("<4sII", b"glTF", 2, 20 + len(text)) + struct.pack("<II", len(text), 0x4E4F534A) + text


def test_the_voxel_grid_is_read_by_the_clients_planner_around_a_block(client):
    world = load_world(client, "scene_basic_drone.jsonc")
    center = (30, 0, -5)
    grid = world.create_voxel_grid(pose(*center), 30, 30, 30, 1)
    assert len(grid) == 30**3
    planner = AStarPlanner(grid, center, (30, 30, 30), 1)
    assert planner.check_coordinate_validity((30, 0, -5), is_NED=True) is False  # inside BlockNorth
    assert planner.check_coordinate_validity((22, 0, -5), is_NED=True) is True
    path = planner.generate_plan((22, 0, -5), (38, 0, -5))
    assert tuple(path[-1]) == (38, 0, -5)
    assert all(not (28 <= x <= 32 and -4 <= y <= 4 and z >= -10) for x, y, z in path)
    ignoring = world.create_voxel_grid(pose(*center), 30, 30, 30, 1, actors_to_ignore=["BlockNorth"])
    assert sum(ignoring) < sum(grid)


def test_objects_are_listed_and_their_poses_read_and_set(client):
    world = load_world(client, "scene_basic_drone.jsonc")
    assert world.list_objects("Block.*") == ["BlockNorth", "BlockEast", "BlockSouthWest"]
    assert world.list_objects("Drone.*") == ["Drone1"]
    assert world.list_assets(".*") == ["Cube", "Sphere"] and world.list_assets(".*LandingPad.*") == []
    ball = world.get_object_pose("OrangeBall")
    assert (ball["translation"]["x"], ball["translation"]["y"], ball["translation"]["z"]) == (20, 20, -3)
    assert math.isnan(world.get_object_pose("NoSuchThing")["translation"]["x"])
    assert world.set_object_pose("OrangeBall", pose(5.0, -5.0, -2.0), True) is True
    moved = world.get_object_poses(["OrangeBall", "BlockNorth"])
    assert moved[0]["translation"]["x"] == 5.0 and moved[1]["translation"]["x"] == 30.0
    with pytest.raises(RuntimeError, match="No objects of name Ghost"):
        world.set_object_pose("Ghost", pose(0.0, 0.0, 0.0), True)


def test_a_spawned_gltf_model_is_seen_by_the_camera_and_in_the_voxel_grid(client):
    world = load_world(client, "scene_drone_sensors.jsonc")
    drone = Drone(client, world, "Drone1")
    drone.set_pose(pose(0.0, 60.0, -20.0), True)  # over open ground
    world.pause()  # lock-step: every image due in a step is rendered before the step replies
    inbox = subscribe(client, drone.sensors["DownCamera"]["depth_planar_camera"])
    settle(client, drone.robot_info["actual_pose"])

    def centre_depth() -> float:
        inbox.messages.clear()
        world.continue_for_sim_time(200_000_000, wait_until_complete=True)
        image = inbox.wait_for(timeout=30.0)[-1]
        return float(unpack_image(image)[image["height"] // 2, image["width"] // 2])

    before = centre_depth()
    name = world.spawn_object_from_file(
        "Tower", "gltf", tower_glb(12.0, 15.0), True, pose(0, 60, 0), [1, 1, 1], False
    )
    assert name == "Tower" and world.list_objects("Tower.*") == ["Tower"]
    after = centre_depth()
    assert after < before - 5.0, (
        f"the camera did not see the spawned model ({before:.1f} m, then {after:.1f} m)"
    )
    grid = world.create_voxel_grid(pose(0, 60, -6), 10, 10, 10, 1)
    assert all(grid[: 10 * 10 * 10 // 2])  # the lower half of the cells lies inside the 12 m tower
    assert world.destroy_object("Tower") is True
    assert centre_depth() == pytest.approx(before, rel=0.01)


def test_a_scenes_spawn_objects_load_with_the_scene(client, tmp_path):
    model = tmp_path / "pad.glb"
    model.write_bytes(tower_glb(0.2, 2.0))
    config = copy.deepcopy(scene_config("scene_basic_drone.jsonc"))
    config["spawn-objects"] = {
        "from-file": [
            {
                "name": "Beacon",
                "file-format": "gltf",
                "is-binary": True,
                "asset-path": str(model),
                "origin": {"xyz": "3 4 0", "rpy-deg": "0 0 90"},
                "scale": "1 1 1",
                "physics-enabled": False,
            }
        ]
    }
    world = World(client)
    world.load_scene(config, delay_after_load_sec=0)
    assert world.list_objects("Beacon") == ["Beacon"]
    pad = world.get_object_pose("Beacon")
    assert (pad["translation"]["x"], pad["translation"]["y"]) == (3, 4)
    assert 2 * math.atan2(pad["rotation"]["z"], pad["rotation"]["w"]) == pytest.approx(math.pi / 2)


def test_env_actors_follow_the_trajectory_of_their_config(client):
    config = copy.deepcopy(scene_config("scene_basic_drone.jsonc"))
    script = {
        "loop": True,
        "auto_start": True,
        "trajectory": {
            "name": "right_config",
            "time_sec": [0, 2, 4],
            "pose_x": [3, 3, 3],
            "pose_y": [0, 10, 20],
            "pose_z": [-5, -5, -5],
            "pose_roll": [0, 0, 0],
            "pose_pitch": [0, 0, 0],
            "pose_yaw": [0, 0, 0],
            "velocity_linear_x": [0, 0, 0],
            "velocity_linear_y": [5, 5, 5],
            "velocity_linear_z": [0, 0, 0],
        },
    }
    config["environment-actors"] = [
        {
            "type": "env_actor",
            "name": "Scripted",
            "origin": {"xyz": "0 0 -5"},
            "env-actor-config": {"script": script},
        },
        {"type": "env_actor", "name": "Follower", "origin": {"xyz": "0 0 -6"}, "env-actor-config": {}},
    ]
    world = World(client)
    world.load_scene(config, delay_after_load_sec=0)
    scripted = EnvActor(client, world, "Scripted")
    inbox = subscribe(client, scripted.actor_info["actual_kinematics"])
    moving = inbox.wait_for(where=lambda m: m["kinematics"]["pose"]["position"]["y"] > 1.0)[-1]
    assert moving["kinematics"]["pose"]["position"]["x"] == pytest.approx(3.0)
    assert moving["kinematics"]["twist"]["linear"]["y"] == pytest.approx(5.0)
    follower = EnvActor(client, world, "Follower")
    assert client.request(_set_trajectory(world, "Follower", "right_config")) is True
    assert client.request(_set_trajectory(world, "Follower", "never_imported")) is False
    follower_inbox = subscribe(client, follower.actor_info["actual_kinematics"])
    follower_inbox.wait_for(where=lambda m: m["kinematics"]["pose"]["position"]["y"] > 1.0)


def _set_trajectory(world: World, actor: str, trajectory: str) -> dict:
    offsets = dict.fromkeys(("time_offset", "x_offset", "y_offset", "z_offset"), 0.0)
    offsets.update(dict.fromkeys(("roll_offset", "pitch_offset", "yaw_offset"), 0.0))
    params = {"env_actor_name": actor, "traj_name": trajectory, **offsets, "to_loop": True}
    return {"method": f"{world.parent_topic}/SetEnvActorTrajectory", "params": params, "version": 1.0}
