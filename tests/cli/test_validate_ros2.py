"""validate-mapping --ros 2: names ROS 2 refuses are located problems; --ros 1 (the default) as before."""

from __future__ import annotations

import json
from pathlib import Path

import pytest
from harness import ROOT, SIM_CONFIG

from airsim_mapper.cli.validate import main

RULE = """version: 1
rules:
  - name: pose
    for_each: robot
    direction: sim_to_ros
    converter: pose
    sim: /Sim/<scene_name>/robots/<robot_name>/actual_pose
    ros: {ros}
    type: geometry_msgs/PoseStamped
"""
SCENE = ["--scene", "scene_drone_sensors.jsonc", "--simconfigpath", str(SIM_CONFIG)]


def mapping_with(tmp_path: Path, ros: str) -> str:
    path = tmp_path / "m.yaml"
    path.write_text(RULE.format(ros=ros))
    return str(path)


@pytest.mark.parametrize("scene", [[], SCENE], ids=["rules", "bridges"])
def test_ros1_takes_what_ros2_refuses_and_ros2_says_where(tmp_path, capsys, scene: list[str]):
    mapping = mapping_with(tmp_path, "/x/<robot_name>/0pose")
    assert main([mapping, *scene]) == 0
    assert main([mapping, *scene, "--ros", "1"]) == 0
    capsys.readouterr()
    assert main([mapping, *scene, "--ros", "2"]) == 1
    (line,) = capsys.readouterr().err.splitlines()
    assert line.startswith(f"{mapping}:8:10: ")
    assert "ROS 2" in line and "a token starts with a digit" in line


def test_a_private_name_without_a_slash_is_refused_by_ros2(tmp_path, capsys):
    mapping = mapping_with(tmp_path, "~pose")
    assert main([mapping, "--ros", "2", "--format", "json"]) == 1
    (problem,) = json.loads(capsys.readouterr().out)["problems"]
    assert (problem["file"], problem["line"], problem["column"]) == (mapping, 8, 10)
    assert "'~' must be followed by '/'" in problem["message"]
    assert main([mapping_with(tmp_path, "~/pose"), "--ros", "2"]) == 0


@pytest.mark.parametrize("name", ["default.yaml", "enu.yaml"])
def test_the_shipped_mappings_are_valid_for_ros2(capsys, name: str):
    assert main([str(ROOT / "mappings" / name), "--ros", "2"]) == 0
    assert main([str(ROOT / "mappings" / name), "--ros", "2", *SCENE]) == 0


def test_an_unknown_ros_is_a_usage_error(capsys):
    assert main([str(ROOT / "mappings" / "default.yaml"), "--ros", "3"]) == 2
    assert "--ros: invalid choice: 3" in capsys.readouterr().err
