"""The scene reader: the client's loader, kept inside the config directory, with errors naming the file."""

from __future__ import annotations

import json
import os

import pytest
from harness import EXAMPLE_CONFIG, SIM_CONFIG
from scene_builders import camera, capture
from simconfigs import both_configs

from airsim_mapper.mapping.scene import SceneConfigError, read_scene, scene_from_config

# two different drones, Drone1 the plain one with a disabled GPS: file, scene id, Drone2's origin
TWO_DRONE_SCENES = {
    SIM_CONFIG: (
        "scene_two_drones_mixed.jsonc",
        "SceneTwoDronesMixed",
        {"geo-point": "47.641468 -122.140125 126.0", "rpy": "0 0 0"},
    ),
    EXAMPLE_CONFIG: (
        "scene_two_drones_sensors.jsonc",
        "SceneTwoDrones",
        {"xyz": "0.0 2.0 -4.0", "rpy-deg": "0 0 0"},
    ),
}


@pytest.mark.parametrize("sim_config", both_configs(), indirect=True)
def test_reads_robots_sensors_and_capture_settings_as_the_simulator_receives_them(sim_config):
    scene_file, scene_id, drone2_origin = TWO_DRONE_SCENES[sim_config]
    scene = read_scene(sim_config, scene_file)
    assert scene.name == scene_id
    assert [robot.name for robot in scene.robots] == ["Drone1", "Drone2"]
    drone2 = scene.robots[1]
    assert [s.id for s in drone2.enabled_sensors("lidar")] == ["lidar1"]
    assert [s.id for s in drone2.enabled_sensors("distance_sensor")] == ["DistanceSensor"]
    assert [s.id for s in scene.robots[0].enabled_sensors("gps")] == []  # "enabled": false in the config
    down = next(s for s in drone2.sensors if s.id == "DownCamera")
    assert [c.image_type for c in down.captures if c.capture_enabled] == [0, 1, 2, 3, 4, 5, 6]
    assert "robot-config" not in drone2.actor
    assert drone2.actor["origin"] == drone2_origin
    # the merged config inlines the robot config, as the client sends it with /Sim/LoadScene
    assert scene.config["actors"][1]["robot-config"]["sensors"][0]["id"] == "Chase"
    assert [(c.robot_name, c.camera_name) for c in scene.streaming_cameras] == [
        ("Drone1", "Chase"),
        ("Drone2", "Chase"),
    ]


def test_merges_a_list_of_robot_configs_like_the_client(write_scene):
    root = write_scene({"R": [camera("Cam", [capture(0)])]})
    extra = {"sensors": [camera("Cam2", [capture(1)])]}
    (root / "extra.jsonc").write_text(json.dumps(extra))
    doc = json.loads((root / "scene.jsonc").read_text())
    doc["actors"][0]["robot-config"] = ["robot_R.jsonc", "extra.jsonc"]
    (root / "scene.jsonc").write_text(json.dumps(doc))
    scene = read_scene(root, "scene.jsonc")
    assert [s.id for s in scene.robots[0].sensors] == ["Cam", "Cam2"]


def test_refuses_a_scene_path_that_climbs_out_of_the_config_directory(write_scene):
    root = write_scene({"R": []})
    with pytest.raises(
        SceneConfigError, match=r"the scene file may not leave the config directory .* \('\.\.'\)"
    ):
        read_scene(root, "../sim_config/scene.jsonc")


def test_refuses_an_absolute_scene_path(write_scene):
    root = write_scene({"R": []})
    with pytest.raises(SceneConfigError, match="the scene file must be relative to the config directory"):
        read_scene(root, str(root / "scene.jsonc"))


def test_refuses_a_symlink_that_leads_out_of_the_config_directory(write_scene, tmp_path):
    root = write_scene({"R": []})
    outside = tmp_path / "outside.jsonc"
    outside.write_text((root / "scene.jsonc").read_text())
    os.symlink(outside, root / "link.jsonc")
    with pytest.raises(
        SceneConfigError, match=r"link\.jsonc: the scene file resolves outside the config directory"
    ):
        read_scene(root, "link.jsonc")


def test_refuses_a_robot_config_outside_the_config_directory(write_scene):
    root = write_scene({"R": []})
    doc = json.loads((root / "scene.jsonc").read_text())
    doc["actors"][0]["robot-config"] = "../robot.jsonc"
    (root / "scene.jsonc").write_text(json.dumps(doc))
    with pytest.raises(
        SceneConfigError, match="robot-config of actor 'R' may not leave the config directory"
    ):
        read_scene(root, "scene.jsonc")


def test_a_missing_robot_config_is_an_error_naming_the_file(write_scene):
    root = write_scene({"R": []})
    (root / "robot_R.jsonc").unlink()
    with pytest.raises(SceneConfigError) as caught:
        read_scene(root, "scene.jsonc")
    assert str(caught.value) == f"{root / 'robot_R.jsonc'}: robot config of actor 'R' not found"
    assert not caught.value.unreadable


def test_invalid_json_in_a_robot_config_is_an_error_naming_the_file(write_scene):
    root = write_scene({"R": []})
    (root / "robot_R.jsonc").write_text('{"physics-type": "non-physics",, }')
    with pytest.raises(SceneConfigError) as caught:
        read_scene(root, "scene.jsonc")
    assert str(caught.value).startswith(
        f"{root / 'robot_R.jsonc'}: invalid JSON in the robot config of actor 'R': Unexpected token"
    )


def test_invalid_json_in_the_scene_is_an_error_naming_the_scene_file(write_scene):
    root = write_scene({"R": []})
    (root / "scene.jsonc").write_text('{"id": "x" // comments are fine, a missing brace is not\n')
    with pytest.raises(SceneConfigError, match=r"scene\.jsonc: invalid JSON in the scene file"):
        read_scene(root, "scene.jsonc")


def test_a_robot_config_that_breaks_the_client_schema_is_an_error_naming_the_file(write_scene):
    root = write_scene({"R": []})
    (root / "robot_R.jsonc").write_text('{"links": []}')
    with pytest.raises(SceneConfigError) as caught:
        read_scene(root, "scene.jsonc")
    assert str(caught.value) == (
        f"{root / 'robot_R.jsonc'}: does not match the robot schema: "
        "top level: 'physics-type' is a required property"
    )


def test_a_scene_that_breaks_the_client_schema_is_an_error_naming_the_scene(write_scene):
    root = write_scene({"R": []})
    doc = json.loads((root / "scene.jsonc").read_text())
    del doc["actors"][0]["origin"]
    (root / "scene.jsonc").write_text(json.dumps(doc))
    with pytest.raises(SceneConfigError) as caught:
        read_scene(root, "scene.jsonc")
    assert str(caught.value) == (
        f"{root / 'scene.jsonc'}: does not match the scene schema: actors/0: 'origin' is a required property"
    )


def test_a_missing_config_directory_is_an_unreadable_error(tmp_path):
    with pytest.raises(SceneConfigError, match="the config directory does not exist") as caught:
        read_scene(tmp_path / "nowhere", "scene.jsonc")
    assert caught.value.unreadable


def test_reading_a_scene_leaves_no_client_log_file_behind(write_scene, monkeypatch, tmp_path):
    root = write_scene({"R": []})
    monkeypatch.chdir(tmp_path)
    read_scene(root, "scene.jsonc")
    assert not (tmp_path / "projectairsim_client.log").exists()


def test_a_scene_can_be_built_from_a_merged_config_like_world_get_configuration():
    merged = read_scene(SIM_CONFIG, "scene_survey_drone.jsonc").config
    scene = scene_from_config(merged, "scene_survey_drone.jsonc", SIM_CONFIG)
    assert (scene.name, [r.name for r in scene.robots]) == ("SceneSurveyDrone", ["Drone1"])
    assert [s.id for s in scene.robots[0].enabled_sensors("lidar")] == ["lidar1"]


def test_a_merged_config_without_an_id_or_with_paths_not_inlined_is_a_scene_error():
    with pytest.raises(SceneConfigError, match=r"^s\.jsonc: the scene configuration has no string 'id'$"):
        scene_from_config({"actors": []}, "s.jsonc", SIM_CONFIG)
    actor = {"type": "robot", "name": "R", "robot-config": "robot.jsonc"}
    with pytest.raises(SceneConfigError, match="actor 'R': robot-config is not inlined"):
        scene_from_config({"id": "S", "actors": [actor]}, "s.jsonc", SIM_CONFIG)


def test_a_fifo_scene_or_robot_config_is_refused_at_once_naming_the_file(tmp_path):
    import os
    import shutil
    import time

    from harness import SIM_CONFIG

    from airsim_mapper.mapping.scene import SceneConfigError, read_scene

    root = tmp_path / "configs"
    shutil.copytree(SIM_CONFIG, root)
    os.mkfifo(root / "fifo.jsonc")
    os.mkfifo(root / "robot_fifo.jsonc")
    scene = (root / "scene_drone_sensors.jsonc").read_text()
    (root / "fifo_robot.jsonc").write_text(scene.replace("robot_quadrotor_sensors.jsonc", "robot_fifo.jsonc"))
    start = time.monotonic()
    with pytest.raises(SceneConfigError) as caught:
        read_scene(root, "fifo.jsonc")
    assert (
        str(caught.value)
        == f"{root / 'fifo.jsonc'}: the scene file is a FIFO (named pipe), not a regular file"
    )
    with pytest.raises(SceneConfigError) as caught:
        read_scene(root, "fifo_robot.jsonc")
    assert str(caught.value) == (
        f"{root / 'robot_fifo.jsonc'}: the robot config of actor 'Drone1' is a FIFO (named pipe), "
        "not a regular file"
    )
    assert time.monotonic() - start < 5


def test_scenes_read_at_once_from_many_threads_share_the_clients_patches_under_one_lock():
    import threading

    import projectairsim.utils as client_utils

    original = client_utils.get_schema
    results: list = []

    def read() -> None:
        for _ in range(2):
            results.append(read_scene(SIM_CONFIG, "scene_basic_drone.jsonc").name)

    threads = [threading.Thread(target=read) for _ in range(6)]
    for thread in threads:
        thread.start()
    for thread in threads:
        thread.join(timeout=120)
    assert results == ["SceneBasicDrone"] * 12
    assert client_utils.get_schema is original and "open" not in vars(client_utils)
