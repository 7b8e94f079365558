"""validate-mapping: output formats and exit statuses."""

from __future__ import annotations

import json
import subprocess

import pytest
from harness import EXAMPLE_CONFIG, ROOT, SIM_CONFIG, VENV_BIN
from simconfigs import both_configs

from airsim_mapper.cli.validate import format_table, load_and_expand, main
from airsim_mapper.common.errors import ConfigError
from airsim_mapper.mapping.errors import MappingError
from airsim_mapper.mapping.scene import SceneConfigError

DEFAULT = ROOT / "mappings" / "default.yaml"
# bridges for scene_drone_sensors.jsonc: the project's sensor drone also has radar1 (detections, tracks, tf)
SENSORS_SCENE_BRIDGES = {SIM_CONFIG: 81, EXAMPLE_CONFIG: 78}


def test_a_valid_mapping_without_a_scene_exits_0_and_lists_its_rules(capsys):
    assert main([str(DEFAULT)]) == 0
    out = capsys.readouterr().out
    assert "/airsim_node/<robot_name>/<camera_name>/<image_type>/image" in out
    assert out.rstrip().endswith("valid, 45 rules")


@pytest.mark.live
@pytest.mark.parametrize("sim_config", both_configs(), indirect=True)
def test_the_console_script_prints_the_drone1_topic_table_for_the_sensors_scene(sim_config):
    result = subprocess.run(
        [
            str(VENV_BIN / "validate-mapping"),
            "mappings/default.yaml",
            "--scene",
            "scene_drone_sensors.jsonc",
            "--simconfigpath",
            str(sim_config),
        ],
        capture_output=True,
        text=True,
        cwd=ROOT,
        timeout=60,
    )
    assert result.returncode == 0, result.stderr
    lines = result.stdout.splitlines()
    assert lines[0].split() == ["DIRECTION", "SIMULATOR", "ROS", "TYPE", "FRAME"]
    # the count, and the scene file it was read from (then what each rule's match selects)
    scene = f"{sim_config}/scene_drone_sensors.jsonc"
    assert f"{SENSORS_SCENE_BRIDGES[sim_config]} bridges in {scene}" in lines
    pose = next(line for line in lines if " /airsim_node/Drone1/actual_pose " in line)
    assert pose.split() == [
        "sim_to_ros",
        "/Sim/SceneDroneSensors/robots/Drone1/actual_pose",
        "/airsim_node/Drone1/actual_pose",
        "geometry_msgs/PoseStamped",
        "map",
    ]


def test_json_format_prints_one_array_of_bridges_with_the_documented_keys(capsys):
    argv = [str(DEFAULT), "--scene", "scene_survey_drone.jsonc", "--simconfigpath", str(SIM_CONFIG)]
    assert main([*argv, "--format", "json", "--nodename", "bridge7"]) == 0
    rows = json.loads(capsys.readouterr().out)
    assert all(
        {"direction", "sim", "ros", "ros_type", "converter", "frame_id", "rule", "name", "tf"} <= set(r)
        for r in rows
    )
    load = rows[0]
    assert (load["name"], load["ros"], load["sim"], load["frame_id"], load["tf"]) == (
        "load_scene[bridge7]",
        "/ProjectAirSim/node/bridge7/load_scene",
        None,
        None,
        None,
    )
    lidar = next(row for row in rows if row["rule"] == "lidar_tf")
    assert (lidar["sim"], lidar["converter"], lidar["ros"]) == (
        "/Sim/SceneSurveyDrone/robots/Drone1/actual_pose",
        "sensor_pose",
        None,
    )
    assert lidar["tf"] == {
        "parent": "airsim_node/Drone1",
        "child": "airsim_node/Drone1/lidar1",
        "static": True,
    }
    assert {row["direction"] for row in rows} == {"sim_to_ros", "ros_to_sim"}


def test_usage_errors_exit_2(capsys):
    assert main([]) == 2
    assert main([str(DEFAULT), "--format", "yaml"]) == 2
    assert "usage: validate-mapping" in capsys.readouterr().err


def test_an_unreadable_mapping_file_exits_2_naming_the_file(tmp_path, capsys):
    missing = tmp_path / "nope.yaml"
    assert main([str(missing)]) == 2
    assert (
        capsys.readouterr().err.strip()
        == f"{missing}: cannot read the mapping file: No such file or directory"
    )


def test_a_mistyped_shipped_mapping_name_gets_a_did_you_mean(tmp_path, capsys, monkeypatch):
    monkeypatch.chdir(tmp_path)  # no file of that name here
    assert main(["enuu"]) == 2
    assert capsys.readouterr().err.strip() == (
        "enuu: cannot read the mapping file: No such file or directory (did you mean 'enu'?)"
    )
    assert main(["zzz"]) == 2
    assert (
        capsys.readouterr()
        .err.strip()
        .endswith("No such file or directory (shipped: default, enu; a file is written ./zzz.yaml)")
    )
    assert main(["./enuu"]) == 2  # written as a path: no guess
    assert capsys.readouterr().err.strip() == "enuu: cannot read the mapping file: No such file or directory"


def test_a_missing_scene_file_exits_2_and_an_invalid_scene_exits_1(tmp_path, capsys):
    def missing(scene: str) -> str:
        assert main([str(DEFAULT), "--scene", scene, "--simconfigpath", str(SIM_CONFIG)]) == 2
        return capsys.readouterr().err.strip()

    assert missing("absent.jsonc").endswith(
        "absent.jsonc: cannot read the scene file: No such file or directory"
    )
    # the folder written into the name, or a name off by a letter: the one meant is named
    inside = f"--simconfigpath {SIM_CONFIG.resolve()}"
    assert missing("sim_config/scene_drone_sensors.jsonc").endswith(
        f"(scene files are named inside {inside}: 'scene_drone_sensors.jsonc')"
    )
    assert missing("scene_drone_sensor.jsonc").endswith(
        "No such file or directory (did you mean 'scene_drone_sensors.jsonc'?)"
    )
    (tmp_path / "bad.jsonc").write_text('{"id": 5}')
    assert main([str(DEFAULT), "--scene", "bad.jsonc", "--simconfigpath", str(tmp_path)]) == 1
    assert "does not match the scene schema: id: 5 is not of type 'string'" in capsys.readouterr().err


def test_load_and_expand_returns_the_mapping_scene_and_bridges():
    mapping, scene, bridges = load_and_expand(DEFAULT, "scene_basic_drone.jsonc", SIM_CONFIG, "n1", "")
    assert (len(mapping.rules), scene.name, bridges[0].name) == (45, "SceneBasicDrone", "load_scene[n1]")
    table = format_table(bridges)
    assert len(table.splitlines()) == len(bridges) + 1


def test_load_and_expand_raises_config_errors_whose_text_is_the_full_report(tmp_path):
    broken = tmp_path / "m.yaml"
    broken.write_text("version: 1\nrules: 3\n")
    with pytest.raises(ConfigError, match="rules: expected array, got 3") as caught:
        load_and_expand(broken, "scene_basic_drone.jsonc", SIM_CONFIG, "n1")
    assert isinstance(caught.value, MappingError)
    assert str(caught.value) == f"{broken}:2:8: rules: expected array, got 3"
    assert issubclass(SceneConfigError, ConfigError)


def test_a_directory_given_as_mapping_exits_1_naming_it(tmp_path, capsys):
    assert main([str(tmp_path)]) == 1
    assert (
        capsys.readouterr().err.strip() == f"{tmp_path}: the mapping file is a directory, not a regular file"
    )


EXTENDING = """\
version: 1
extends: default
rules:
  - name: imu
    queue_size: -3
  - name: extra
    for_each: robot
    direction: sim_to_ros
    converter: pose
    sim: /Sim/<scene_name>/robots/<robot_name>/actual_pose
    ros: /extra/<robot_name>
    type: geometry_msgs/PoseStamped
    colour: red
"""


def test_json_format_reports_each_problem_on_stdout_with_its_place_and_key(tmp_path, capsys):
    mapping = tmp_path / "mine.yaml"
    mapping.write_text(EXTENDING)
    assert main([str(mapping), "--format", "json"]) == 1
    captured = capsys.readouterr()
    assert captured.err == ""
    problems = json.loads(captured.out)["problems"]
    assert problems == [
        {
            "file": str(mapping),
            "line": 5,
            "column": 17,
            "key": "rules[0].queue_size",
            "message": "rules[0] 'imu'.queue_size: must be at least 1, got -3",
        },
        {
            "file": str(mapping),
            "line": 13,
            "column": 5,
            "key": "rules[1].colour",
            "message": "unknown key 'colour' in rules[1] 'extra'",
        },
    ]
    # the same problems, the same exit status, as text on stderr
    assert main([str(mapping)]) == 1
    err = capsys.readouterr().err.splitlines()
    assert err == [f"{mapping}:5:17: {problems[0]['message']}", f"{mapping}:13:5: {problems[1]['message']}"]


def test_json_format_reports_an_unreadable_mapping_on_stdout_with_exit_status_2(tmp_path, capsys):
    assert main([str(tmp_path / "absent.yaml"), "--format", "json"]) == 2
    (problem,) = json.loads(capsys.readouterr().out)["problems"]
    assert problem["file"] == str(tmp_path / "absent.yaml") and "cannot read" in problem["message"]


def test_a_base_rules_problem_is_labelled_with_its_index_in_the_base(tmp_path, capsys):
    (tmp_path / "base.yaml").write_text(EXTENDING.replace("  - name: imu\n    queue_size: -3\n", ""))
    (tmp_path / "child.yaml").write_text(
        "version: 1\nextends: base.yaml\nrules:\n  - name: imu\n    queue_size: 2\n"
    )
    assert main([str(tmp_path / "child.yaml"), "--format", "json"]) == 1
    (problem,) = json.loads(capsys.readouterr().out)["problems"]
    assert problem["file"] == str(tmp_path / "base.yaml")
    assert problem["key"] == "rules[0].colour" and "in rules[0] 'extra'" in problem["message"]
