"""airsim-mapper topics: the expanded interface as Markdown, and the committed docs generated from it."""

from __future__ import annotations

import subprocess

import pytest
from harness import ROOT, VENV_BIN

from airsim_mapper.cli.main import main

DOCS = {
    "docs/interface.md": "mappings/default.yaml",
    "docs/interface-enu.md": "mappings/enu.yaml",
}


def topics(capsys, mapping: str, scene: str = "scene_drone_sensors.jsonc") -> tuple[int, str, str]:
    status = main(
        [
            "topics",
            "--mapping",
            str(ROOT / mapping),
            "--scene",
            scene,
            "--simconfigpath",
            str(ROOT / "sim_config"),
        ]
    )
    captured = capsys.readouterr()
    return status, captured.out, captured.err


@pytest.mark.parametrize(("doc", "mapping"), sorted(DOCS.items()))
def test_committed_interface_docs_equal_the_commands_output(doc: str, mapping: str, monkeypatch, capsys):
    monkeypatch.chdir(ROOT)  # the command as documented, run from the repository root
    assert main(["topics", "--mapping", mapping, "--scene", "scene_drone_sensors.jsonc"]) == 0
    committed = (ROOT / doc).read_text(encoding="utf-8")
    assert committed == capsys.readouterr().out, (
        f"{doc} is out of date: regenerate it with "
        f"`airsim-mapper topics --mapping {mapping} --scene scene_drone_sensors.jsonc > {doc}`"
    )


@pytest.mark.live
def test_the_console_script_runs_the_topics_command():
    result = subprocess.run(
        [str(VENV_BIN / "airsim-mapper"), "topics", "--help"], capture_output=True, text=True, timeout=60
    )
    assert result.returncode == 0, result.stderr
    assert result.stdout.startswith("usage: airsim-mapper topics [-h] --mapping MAPPING --scene SCENE")


def test_topics_prints_one_markdown_row_per_bridge_with_ros_type_direction_sim_frame_qos_and_rule(capsys):
    status, out, _ = topics(capsys, "mappings/enu.yaml")
    assert status == 0
    lines = out.splitlines()
    assert lines[0].startswith("# ROS interface of ")
    header = lines.index("| ROS name | type | direction | simulator | frame | QoS (ROS 2) | bridge |")
    assert lines[header + 1] == "|---|---|---|---|---|---|---|"
    rows = lines[header + 2 :]
    assert "81 bridges: 46 topics, 16 services, 19 tf-only." in out
    assert len(rows) == 81
    assert (
        "| `/airsim_node/Drone1/actual_pose` | `geometry_msgs/PoseStamped` | sim → ROS | "
        "`/Sim/SceneDroneSensors/robots/Drone1/actual_pose` | `map`; tf `map` → `Drone1/base_link` | "
        "`reliable/transient_local/1` | `actual_pose[Drone1]` |"
    ) in rows
    assert (
        "| `/airsim_node/pause` (service) | `std_srvs/SetBool` | ROS → sim | "
        "`/Sim/SceneDroneSensors/Pause` | - | `reliable/volatile/10` | `pause[SceneDroneSensors]` |"
    ) in rows
    assert (
        "| tf_static `Drone1/base_link` → `Drone1/Chase/scene_camera_optical` | - | sim → ROS | "
        "`/Sim/SceneDroneSensors/robots/Drone1/actual_pose` | - | `reliable/transient_local/1` | "
        "`camera_optical_tf[Drone1/Chase/scene_camera]` |"
    ) in rows
    assert "| (node: streaming_image) |" in next(r for r in rows if "image_raw" in r)


def test_topics_with_an_invalid_mapping_exits_1_with_the_problems(tmp_path, capsys):
    broken = tmp_path / "m.yaml"
    broken.write_text("version: 1\nrules: 3\n")
    status, out, err = topics(capsys, str(broken))
    assert (status, out) == (1, "")
    assert "rules: expected array, got 3" in err


def test_topics_with_an_unreadable_mapping_exits_2(tmp_path, capsys):
    missing = tmp_path / "nope.yaml"
    status, _, err = topics(capsys, str(missing))
    assert status == 2
    assert err.strip() == f"{missing}: cannot read the mapping file: No such file or directory"


def test_topics_without_a_command_or_its_arguments_is_a_usage_error(capsys):
    assert main([]) == 2
    assert main(["topics", "--mapping", "mappings/default.yaml"]) == 2
    assert "the following arguments are required: --scene" in capsys.readouterr().err
