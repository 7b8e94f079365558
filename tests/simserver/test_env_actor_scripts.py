"""Env actor config scripts (pure): read at scene load, imported under their names, followed on sim time."""

from __future__ import annotations

import copy
import json

import pytest

from airsim_mapper.simserver.scene.config import SceneSpecError, parse_scene
from airsim_mapper.simserver.scene.env_actors import EnvActors
from airsim_mapper.simserver.session import TrajectoryStore

SCRIPT = {
    "loop": False,
    "auto_start": True,
    "trajectory": {
        "name": "right_config",
        "time_sec": [1, 3],
        "pose_x": [3, 3],
        "pose_y": [0, 10],
        "pose_z": [-5, -5],
        "pose_roll": [0, 0],
        "pose_pitch": [0, 0],
        "pose_yaw": [0, 0],
        "velocity_linear_x": [0, 0],
        "velocity_linear_y": [5, 5],
        "velocity_linear_z": [0, 0],
    },
}


def scene(script) -> str:
    actor = {"type": "env_actor", "name": "Scripted", "origin": {"xyz": "0 0 -5"}, "env-actor-config": {}}
    if script is not None:
        actor["env-actor-config"]["script"] = script
    return json.dumps({"id": "S", "actors": [], "environment-actors": [actor]})


def actors(script) -> EnvActors:
    spec = parse_scene(scene(script))
    return EnvActors(spec.env_actors, spec.prefix, TrajectoryStore(), start_ns=0)


def test_the_script_is_imported_and_followed_from_the_scenes_start():
    env = actors(SCRIPT)
    assert env.trajectories.get("right_config")["pose_y"] == [0.0, 10.0]
    actor = env.actors["Scripted"]
    position, _, velocity = actor.state(2_000_000_000)  # trajectory time 2 s: halfway
    assert position.tolist() == pytest.approx([3.0, 5.0, -5.0]) and velocity[1] == pytest.approx(5.0)
    assert actor.state(9_000_000_000)[0][1] == pytest.approx(10.0)  # no loop: it stays at the end


def test_a_looping_script_starts_over():
    env = actors({**SCRIPT, "loop": True})
    assert env.actors["Scripted"].state(4_000_000_000)[0][1] == pytest.approx(5.0)  # 2 s into the next lap


def test_missing_arrays_other_than_time_and_position_default_to_zeros():
    script = copy.deepcopy(SCRIPT)
    for key in ("pose_roll", "pose_pitch", "pose_yaw", "velocity_linear_x", "velocity_linear_y"):
        del script["trajectory"][key]
    assert actors(script).trajectories.get("right_config")["vel_y_lin"] == [0.0, 0.0]


def test_an_actor_without_a_script_stays_at_its_origin():
    env = actors(None)
    assert env.actors["Scripted"].state(5_000_000_000)[0].tolist() == [0.0, 0.0, -5.0]
    assert env.trajectories.get("right_config") is None


@pytest.mark.parametrize(
    ("change", "problem"),
    [
        (lambda s: s.pop("trajectory"), "must have a 'trajectory' object"),
        (lambda s: s["trajectory"].pop("name"), "non-empty 'name'"),
        (lambda s: s["trajectory"].pop("pose_z"), "has no 'pose_z'"),
        (lambda s: s["trajectory"].update(pose_y=[0]), "'pose_y' must be a list of 2 numbers"),
        (lambda s: s["trajectory"].update(pose_x=[3, "a"]), "'pose_x' must be a list of 2 numbers"),
    ],
)
def test_a_malformed_script_is_refused_at_scene_load_naming_the_key(change, problem):
    script = copy.deepcopy(SCRIPT)
    change(script)
    with pytest.raises(SceneSpecError, match=problem) as err:
        parse_scene(scene(script))
    assert "environment actor 'Scripted'" in str(err.value)


def test_an_unknown_trajectory_is_refused_with_false_and_the_old_one_kept(caplog):
    env = actors(SCRIPT)
    offsets = dict.fromkeys(
        ("time_offset", "x_offset", "y_offset", "z_offset", "roll_offset", "pitch_offset", "yaw_offset"), 0.0
    )
    params = {"env_actor_name": "Scripted", "traj_name": "nope", **offsets, "to_loop": False}
    followed = env.actors["Scripted"].trajectory
    assert env.set_trajectory(params, 0) is False
    assert env.actors["Scripted"].trajectory is followed and "'nope' was not found" in caplog.text
