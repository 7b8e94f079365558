"""The difference between two mappings' bridges (what live reload applies), and validate-mapping OLD NEW."""

from __future__ import annotations

import dataclasses

from harness import SIM_CONFIG

from airsim_mapper.cli.validate import main
from airsim_mapper.mapping.diff import bridge_diff, format_diff
from airsim_mapper.mapping.pipeline import load_and_expand

SCENE = ("scene_drone_sensors.jsonc", SIM_CONFIG, "projectairsim")


def test_bridges_are_added_removed_changed_or_kept_by_name_and_whole_spec():
    _, _, bridges = load_and_expand("default", *SCENE)
    first, second, third, *rest = bridges
    edited = [dataclasses.replace(second, ros="/renamed"), third, *rest]
    extra = dataclasses.replace(first, name="extra[x]")
    diff = bridge_diff(bridges, [*edited, extra])
    assert (diff.added, diff.removed, diff.changed) == (("extra[x]",), (first.name,), (second.name,))
    assert diff.kept == tuple(b.name for b in [third, *rest])
    assert not diff.empty and bridge_diff(bridges, bridges).empty
    text = format_diff(diff, bridges, [*edited, extra])
    assert f"~ {second.name}  ros: {second.ros} -> /renamed" in text.splitlines()
    assert text.splitlines()[-1] == f"1 added, 1 removed, 1 changed, {len(rest) + 1} unchanged"


def test_a_qos_change_is_told_as_the_bridges_qos(tmp_path, capsys):
    new = tmp_path / "new.yaml"
    new.write_text("version: 1\nextends: default\nrules:\n  - {name: imu, qos: {depth: 20}}\n")
    scene = ["--scene", "scene_drone_sensors.jsonc", "--simconfigpath", str(SIM_CONFIG)]
    assert main(["default", str(new), *scene]) == 0
    lines = capsys.readouterr().out.splitlines()
    imu = [line for line in lines if line.startswith("~ imu[")]
    assert imu and all(line.endswith("qos: best_effort/volatile/5 -> reliable/volatile/20") for line in imu)


def test_validate_mapping_old_new_prints_the_difference_over_a_scene(tmp_path, capsys):
    new = tmp_path / "new.yaml"
    new.write_text(
        "version: 1\nextends: default\nremove: [clock]\nrules:\n"
        "  - {name: camera_image, match: {camera_name: '!Chase'}}\n  - {name: imu, rate_limit_hz: 5.0}\n"
    )
    scene = ["--scene", "scene_drone_sensors.jsonc", "--simconfigpath", str(SIM_CONFIG)]
    assert main(["default", str(new), *scene]) == 0
    lines = capsys.readouterr().out.splitlines()
    assert "- camera_image[Drone1/Chase/scene_camera]  /airsim_node/Drone1/Chase/scene_camera/image" in lines
    assert "- clock[SceneDroneSensors]  /clock" in lines
    assert "~ imu[Drone1/IMU1]  rate_limit_hz: None -> 5.0" in lines
    assert lines[-1] == "0 added, 2 removed, 1 changed, 78 unchanged"


def test_validate_mapping_old_new_needs_a_scene_and_reports_an_invalid_new_mapping(tmp_path, capsys):
    assert main(["default", "enu"]) == 2
    assert "needs --scene" in capsys.readouterr().err
    bad = tmp_path / "bad.yaml"
    bad.write_text("version: 1\nextends: default\nrules:\n  - {name: imu, converter: imuu}\n")
    assert (
        main(["default", str(bad), "--scene", "scene_basic_drone.jsonc", "--simconfigpath", str(SIM_CONFIG)])
        == 1
    )
    assert capsys.readouterr().err.startswith(f"{bad}:4:28: rule 'imu': unknown converter 'imuu'")
