"""The real 1.1.0 client loads every scene (the project's, and Project AirSim's examples where present) and
sees the documented topics, services and clock."""

from __future__ import annotations

import time

import pytest
from projectairsim import Drone, World
from simconfigs import both_configs, scenes_of

from simserver.clientkit import load_world, scene_config
from simserver.expected_topics import EXAMPLE_EXPECTED, EXPECTED, PROJECT_EXPECTED, ROBOTS


@pytest.mark.parametrize(
    ("sim_config", "scene_file"), scenes_of(PROJECT_EXPECTED, EXAMPLE_EXPECTED), indirect=["sim_config"]
)
def test_world_and_drone_load_each_scene_with_the_documented_topic_catalogue(client, sim_config, scene_file):
    scene_id, expected = EXPECTED[sim_config][scene_file]
    world = load_world(client, scene_file, sim_config)
    assert world.parent_topic == f"/Sim/{scene_id}"
    assert set(client.topics) == expected | {"/$topics"}
    assert client.topics["/$topics"].message_type == "topic-list"
    assert world.list_actors() == ROBOTS[sim_config][scene_file]
    for name in ROBOTS[sim_config][scene_file]:
        drone = Drone(client, world, name)
        actor = next(a for a in world.sim_config["actors"] if a["name"] == name)
        enabled = {s["id"] for s in actor["robot-config"].get("sensors", []) if s["enabled"]}
        leaves = {topic for sensor_id in enabled for topic in drone.sensors[sensor_id].values()}
        # The client also expects `disparity_normalized_camera_info`; the real server never registers it.
        quirk = {topic for topic in leaves if topic.endswith("/disparity_normalized_camera_info")}
        assert leaves - quirk <= set(client.topics)
        assert not quirk & set(client.topics)
        assert drone.robot_info["actual_pose"] in client.topics


@pytest.mark.parametrize("sim_config", both_configs(), indirect=True)
def test_the_client_world_constructor_loads_the_basic_drone_scene_file(client, sim_config):
    world = World(client, "scene_basic_drone.jsonc", sim_config_path=str(sim_config))
    assert world.parent_topic == "/Sim/SceneBasicDrone"
    assert set(client.topics) == EXPECTED[sim_config]["scene_basic_drone.jsonc"][1] | {"/$topics"}
    assert Drone(client, world, "Drone1").get_ground_truth_pose()["translation"]["z"] == -4.0


def test_a_world_without_a_scene_name_imports_its_null_trajectory_on_the_default_scene(client):
    world = World(client)
    assert world.parent_topic == "/Sim/SceneBasicDrone"
    assert world.sim_config is None


def test_the_steppable_clock_starts_at_zero_and_can_be_paused_stepped_and_resumed(client):
    world = load_world(client, "scene_basic_drone.jsonc")
    assert world.get_sim_clock_type() == "steppable"
    assert 0 < world.get_sim_time() < 10_000_000_000
    paused_at = int(world.pause().rsplit(" ", 1)[1])
    assert world.is_paused()
    time.sleep(0.05)
    assert world.get_sim_time() == paused_at
    assert world.continue_for_sim_time(30_000_000) == paused_at + 30_000_000
    assert world.continue_for_n_steps(2) == paused_at + 36_000_000
    assert world.continue_for_single_step() == paused_at + 39_000_000
    assert world.continue_until_sim_time(paused_at + 50_000_000) == paused_at + 50_000_000
    assert world.is_paused()
    assert world.resume() == f"Sim time resumed from t = {paused_at + 50_000_000}"
    time.sleep(0.05)
    assert world.get_sim_time() > paused_at + 50_000_000 and not world.is_paused()


def test_a_paused_sim_holds_motion_until_it_continues(client):
    import asyncio

    world = load_world(client, "scene_basic_drone.jsonc")
    drone = Drone(client, world, "Drone1")
    world.pause()

    async def move():
        task = await drone.move_by_velocity_async(10.0, 0.0, 0.0, 0.1)
        await asyncio.sleep(0.2)
        before = drone.get_ground_truth_pose()["translation"]["x"]
        world.continue_for_sim_time(200_000_000)
        return before, await task

    before, finished = asyncio.run(move())
    assert before == 0.0 and finished is True
    assert drone.get_ground_truth_pose()["translation"]["x"] == pytest.approx(1.0, abs=0.06)


def test_real_time_scenes_report_unix_time_and_refuse_to_pause(client):
    scene = scene_config("scene_basic_drone.jsonc")
    scene["clock"] = {"type": "real-time"}
    scene["id"] = "RealTimeScene"
    world = World(client)
    world.load_scene(scene)
    assert world.get_sim_clock_type() == "real-time"
    assert abs(world.get_sim_time() - time.time_ns()) < 2_000_000_000
    with pytest.raises(
        RuntimeError, match=r"ERROR code: 1\.0, message: This clock type doesn't support SimPause\."
    ):
        world.pause()


def test_scene_level_services_answer_like_the_real_server(client):
    world = load_world(client, "scene_basic_drone.jsonc")
    assert client.request({"method": f"{world.parent_topic}/SwitchStreamingView", "params": {}}) is True
    params = {
        "traj_name": "t1",
        "time": [0.0, 1.0],
        **{k: [0.0, 0.0] for k in ("pose_x", "pose_y", "pose_z", "pose_roll", "pose_pitch", "pose_yaw")},
        **{k: [0.0, 0.0] for k in ("vel_x_lin", "vel_y_lin", "vel_z_lin")},
    }
    method = f"{world.parent_topic}/ImportNEDTrajectory"
    assert client.request({"method": method, "params": params}) is True
    assert client.request({"method": method, "params": params}) is False
    client.set_interactive_feature("viewport_camera", True)
    assert (
        client.request(
            {"method": "/Sim/SetInteractiveFeature", "params": {"feature_id": "x", "enable": True}}
        )
        is False
    )
    assert client.get_build_commit_hash() == "airsim-mapper-simserver"
