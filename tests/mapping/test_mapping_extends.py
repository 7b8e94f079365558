"""`extends:` and mapping-level `variables:`: merging onto a base, chains, and located errors in the right
file."""

from __future__ import annotations

from pathlib import Path

import pytest
import yaml

from airsim_mapper.cli.validate import main
from airsim_mapper.mapping.errors import MappingError
from airsim_mapper.mapping.loader import load_mapping, load_mapping_text

BASE = """version: 1
variables:
  robot_frame: <frame_prefix>base/<robot_name>
defaults: {queue_size: 2, limits: {max_linear_speed: 3.0}}
rules:
  - name: pose
    for_each: robot
    direction: sim_to_ros
    sim: /Sim/<scene_name>/robots/<robot_name>/actual_pose
    ros: /r/<robot_name>/pose
    type: geometry_msgs/PoseStamped
    converter: pose
    frame_id: <robot_frame>
    tf: {parent: map, child: <robot_frame>}
    latch: true
  - name: imu
    for_each: imu
    direction: sim_to_ros
    sim: /Sim/<scene_name>/robots/<robot_name>/sensors/<sensor_name>/imu_kinematics
    ros: /r/<robot_name>/imu
    type: sensor_msgs/Imu
    converter: imu
  - name: gps
    for_each: gps
    direction: sim_to_ros
    sim: /Sim/<scene_name>/robots/<robot_name>/sensors/<sensor_name>/gps
    ros: /r/<robot_name>/gps
    type: sensor_msgs/NavSatFix
    converter: gps
"""


def write(folder: Path, name: str, text: str) -> Path:
    path = folder / name
    path.write_text(text)
    return path


@pytest.fixture
def base(tmp_path: Path) -> Path:
    return write(tmp_path, "base.yaml", BASE)


def load_child(folder: Path, text: str, name: str = "child.yaml"):
    return load_mapping(write(folder, name, text))


def test_a_partial_rule_merges_into_the_base_rule_and_a_full_rule_replaces_it(base, tmp_path):
    mapping = load_child(
        tmp_path,
        """version: 1
extends: ./base.yaml
rules:
  - {name: pose, ros: /renamed/<robot_name>/pose, tf: {child: other/<robot_name>}}
  - name: imu
    for_each: imu
    direction: sim_to_ros
    sim: /Sim/<scene_name>/robots/<robot_name>/sensors/<sensor_name>/imu_kinematics
    ros: /r/<robot_name>/imu2
    type: sensor_msgs/Imu
    converter: imu
""",
    )
    pose, imu, gps = mapping.rules
    assert (pose.ros, pose.sim, pose.options.latch) == (
        "/renamed/<robot_name>/pose",
        "/Sim/<scene_name>/robots/<robot_name>/actual_pose",
        True,
    )
    assert (pose.tf.parent, pose.tf.child) == ("map", "other/<robot_name>")
    assert (imu.ros, imu.options.queue_size, gps.name) == ("/r/<robot_name>/imu2", 2, "gps")
    assert pose.line == 4  # the override's line: where the user edits it


def test_rules_are_dropped_by_remove_or_enabled_false_and_new_rules_are_appended(base, tmp_path):
    mapping = load_child(
        tmp_path,
        """version: 1
extends: base.yaml
remove: [imu]
rules:
  - {name: gps, enabled: false}
  - {name: baro, for_each: barometer, direction: sim_to_ros, converter: barometer,
     type: sensor_msgs/FluidPressure, ros: /r/<robot_name>/baro,
     sim: /Sim/<scene_name>/robots/<robot_name>/sensors/<sensor_name>/barometer}
""",
    )
    assert [(rule.name, rule.options.enabled) for rule in mapping.rules] == [
        ("pose", True),
        ("gps", False),
        ("baro", True),
    ]


def test_after_places_new_rules_after_a_base_rule_in_the_childs_order(base, tmp_path):
    new = "for_each: robot, direction: sim_to_ros, converter: pose, type: geometry_msgs/PoseStamped"
    sim = "sim: /Sim/<scene_name>/robots/<robot_name>/actual_pose"
    mapping = load_child(
        tmp_path,
        f"""version: 1
extends: base.yaml
rules:
  - {{name: p1, after: pose, ros: /p1/<robot_name>, {new}, {sim}}}
  - {{name: p2, after: pose, ros: /p2/<robot_name>, {new}, {sim}}}
""",
    )
    assert [rule.name for rule in mapping.rules] == ["pose", "p1", "p2", "imu", "gps"]


def test_after_naming_no_rule_or_on_an_override_is_an_error(base, tmp_path):
    new = "for_each: robot, direction: sim_to_ros, converter: pose, type: geometry_msgs/PoseStamped, ros: /q"
    lines = errors(
        write(
            tmp_path,
            "after.yaml",
            f"version: 1\nextends: base.yaml\nrules:\n  - {{name: p1, after: posse, {new}}}\n"
            "  - {name: imu, after: pose}\n",
        )
    )
    file = tmp_path / "after.yaml"
    assert lines == [
        f"{file}:4:23: rule 'p1': after: no rule 'posse' to place it after (did you mean 'pose'?)",
        f"{file}:5:17: rule 'imu': after places a new rule; an override keeps the base rule's place",
    ]
    standalone = write(tmp_path, "alone.yaml", f"version: 1\nrules:\n  - {{name: p1, after: x, {new}}}\n")
    assert errors(standalone) == [
        f"{standalone}:3:16: after: only a rule of a mapping that extends another may say where it goes"
    ]


def test_defaults_image_types_and_variables_merge_entry_by_entry(base, tmp_path):
    mapping = load_child(
        tmp_path,
        """version: 1
extends: ./base.yaml
image_types: {0: rgb}
variables: {robot_frame: <robot_name>/base_link}
defaults: {stamp: ros, limits: {on_violation: reject}}
""",
    )
    pose = mapping.rules[0]
    assert (pose.frame_id, pose.tf.child) == ("<robot_name>/base_link", "<robot_name>/base_link")
    assert (pose.options.queue_size, pose.options.stamp) == (2, "ros")
    assert (pose.options.limits.max_linear_speed, pose.options.limits.on_violation) == (3.0, "reject")
    assert (mapping.image_types[0], mapping.image_types[1]) == ("rgb", "depth_planar_camera")


def test_chains_of_extends_resolve_each_path_relative_to_its_own_file(base, tmp_path):
    (tmp_path / "sub").mkdir()
    write(tmp_path / "sub", "middle.yaml", "version: 1\nextends: ../base.yaml\nremove: [gps]\n")
    mapping = load_child(
        tmp_path, "version: 1\nextends: sub/middle.yaml\nrules: [{name: imu, ros: /x/imu}]\n"
    )
    assert [(rule.name, rule.ros) for rule in mapping.rules] == [
        ("pose", "/r/<robot_name>/pose"),
        ("imu", "/x/imu"),
    ]


def test_a_shipped_mapping_can_be_extended_by_name(tmp_path):
    mapping = load_child(
        tmp_path, "version: 1\nextends: enu\nrules:\n  - {name: camera_image, rate_limit_hz: 5.0}\n"
    )
    image = next(rule for rule in mapping.rules if rule.name == "camera_image")
    assert (image.options.rate_limit_hz, image.convention) == (5.0, "enu")
    assert image.frame_id == "<frame_prefix><robot_name>/<camera_name>/<image_type>_optical"


def errors(path: Path) -> list[str]:
    with pytest.raises(MappingError) as caught:
        load_mapping(path)
    return str(caught.value).splitlines()


def test_a_cycle_is_located_at_the_extends_that_closes_it(tmp_path):
    write(tmp_path, "a.yaml", "version: 1\nextends: ./b.yaml\n")
    write(tmp_path, "b.yaml", "version: 1\nrules: []\nextends: ./a.yaml\n")
    [line] = errors(tmp_path / "a.yaml")
    assert line.startswith(f"{tmp_path / 'b.yaml'}:3:10: extends: cycle: {tmp_path / 'a.yaml'} -> ")
    assert line.endswith(f"{tmp_path / 'b.yaml'} -> {tmp_path / 'a.yaml'}")


def test_a_file_extending_itself_is_a_cycle(tmp_path):
    [line] = errors(write(tmp_path, "a.yaml", "version: 1\nextends: a.yaml\n"))
    assert line.startswith(f"{tmp_path / 'a.yaml'}:2:10: extends: cycle")


def test_a_missing_base_and_an_unknown_shipped_name_are_located_errors(tmp_path):
    [missing] = errors(write(tmp_path, "a.yaml", "version: 1\nextends: ./nowhere.yaml\n"))
    assert missing.startswith(
        f"{tmp_path / 'a.yaml'}:2:10: extends: cannot read the base mapping './nowhere.yaml'"
    )
    assert missing.endswith("No such file or directory")
    [unknown] = errors(write(tmp_path, "b.yaml", "version: 1\nextends: defualt\n"))
    assert (
        unknown
        == f"{tmp_path / 'b.yaml'}:2:10: extends: no shipped mapping 'defualt' (did you mean 'default'?)"
    )


def test_overriding_or_removing_a_rule_the_base_lacks_is_an_error_with_a_did_you_mean(base, tmp_path):
    lines = errors(
        write(
            tmp_path,
            "c.yaml",
            "version: 1\nextends: base.yaml\nremove: [gpss]\nrules:\n  - {name: posee, ros: /p}\n",
        )
    )
    assert lines == [
        f"{tmp_path / 'c.yaml'}:3:10: remove: the base 'base.yaml' has no rule 'gpss' (did you mean 'gps'?)",
        f"{tmp_path / 'c.yaml'}:5:12: rule 'posee' overrides a rule that is not in the base 'base.yaml' "
        "(did you mean 'pose'?); a new rule needs for_each, direction, converter",
    ]
    new_rule = "  - {name: odom, for_each: robot, converter: odometry, ros: /o}\n"
    (line,) = errors(write(tmp_path, "d.yaml", f"version: 1\nextends: base.yaml\nrules:\n{new_rule}"))
    assert line.endswith("a new rule needs for_each, direction, converter (it has no direction)")


def test_problems_of_the_merged_mapping_point_at_the_file_that_holds_the_bad_value(base, tmp_path):
    lines = errors(
        write(
            tmp_path,
            "d.yaml",
            "version: 1\nextends: base.yaml\nrules:\n"
            "  - {name: pose, converter: imuu}\n  - {name: imu, qeue_size: 3}\n",
        )
    )
    child = tmp_path / "d.yaml"
    assert f"{child}:4:29: rule 'pose': unknown converter 'imuu' (did you mean 'imu'?)" in lines
    assert any(line.startswith(f"{child}:5:17: unknown key 'qeue_size'") for line in lines)


def test_an_error_inside_the_base_is_reported_in_the_base(tmp_path):
    write(tmp_path, "base.yaml", BASE.replace("converter: gps", "converter: gpss"))
    lines = errors(write(tmp_path, "e.yaml", "version: 1\nextends: base.yaml\n"))
    assert lines == [
        f"{tmp_path / 'base.yaml'}:29:16: rule 'gps': unknown converter 'gpss' (did you mean 'gps'?)"
    ]


def test_remove_without_extends_and_wrong_types_of_the_merge_keys_are_errors(tmp_path):
    assert errors(write(tmp_path, "f.yaml", "version: 1\nremove: [x]\nrules: []\n")) == [
        f"{tmp_path / 'f.yaml'}:2:1: remove: only a mapping that extends another may remove rules"
    ]
    lines = errors(write(tmp_path, "g.yaml", "version: 1\nextends: default\nremove: pose\nrules: {}\n"))
    assert lines == [
        f"{tmp_path / 'g.yaml'}:3:9: remove: expected a list of rule names",
        f"{tmp_path / 'g.yaml'}:4:8: rules: expected array",
    ]


def test_a_base_whose_rules_or_defaults_have_the_wrong_shape_is_an_error_in_the_base(tmp_path):
    base = write(tmp_path, "base.yaml", "version: 1\ndefaults: [1]\nrules: {a: 1}\n")
    assert errors(write(tmp_path, "i.yaml", "version: 1\nextends: base.yaml\n")) == [
        f"{base}:3:8: rules: expected array",
        f"{base}:2:11: defaults: expected object",
    ]


def test_a_rule_overridden_twice_in_one_file_is_an_error(base, tmp_path):
    lines = errors(
        write(tmp_path, "h.yaml", "version: 1\nextends: base.yaml\nrules: [{name: imu}, {name: imu}]\n")
    )
    assert lines == [
        f"{tmp_path / 'h.yaml'}:3:29: rule 'imu' appears twice in this mapping (first at line 3)"
    ]


# --- variables -------------------------------------------------------------------------------------------
def variables_mapping(variables: str, frame: str = "<robot_frame>", domain: str = "robot") -> str:
    return f"""version: 1
variables: {variables}
rules:
  - name: pose
    for_each: {domain}
    direction: sim_to_ros
    sim: /Sim/<scene_name>/robots/<robot_name>/actual_pose
    ros: /r/pose_<scene_name>
    type: geometry_msgs/PoseStamped
    converter: pose
    frame_id: {frame}
"""


def test_variables_may_use_domain_and_other_mapping_variables():
    text = variables_mapping("{root: <frame_prefix>robots, robot_frame: <root>/<robot_name>}")
    assert load_mapping_text(text).rules[0].frame_id == "<frame_prefix>robots/<robot_name>"


@pytest.mark.parametrize(
    ("variables", "expected"),
    [
        ("{robot_name: x}", "2:13: variables: 'robot_name' is a domain variable"),
        (
            "{robot_frame: <robot_nam>}",
            "2:26: variables: robot_frame uses <robot_nam>, neither a domain nor a "
            "mapping variable (did you mean 'robot_name'?)",
        ),
        ("{robot_frame: a<b}", "2:26: variables: robot_frame 'a<b': stray '<'"),
        (
            "{robot_frame: <a>, a: <robot_frame>}",
            "2:26: variables: robot_frame refers to itself (robot_frame -> a -> robot_frame)",
        ),
        ("{Robot: x}", '2:12: variables: "Robot" does not match'),
        ("{robot_frame: 3}", "2:26: variables.robot_frame: expected string, got 3"),
    ],
)
def test_bad_variables_are_located_errors(variables, expected):
    with pytest.raises(MappingError) as caught:
        load_mapping_text(variables_mapping(variables), "v.yaml")
    assert any(line.startswith(f"v.yaml:{expected}") for line in str(caught.value).splitlines()), str(
        caught.value
    )


def test_a_variable_using_a_domain_variable_the_rule_lacks_is_an_error_at_the_use():
    text = variables_mapping("{cam: <camera_name>}", frame="<cam>")
    with pytest.raises(
        MappingError, match=r"v\.yaml:11:15: rule 'pose': unknown template variable <camera_name>"
    ):
        load_mapping_text(text, "v.yaml")


def test_a_misspelt_mapping_variable_gets_a_did_you_mean():
    text = variables_mapping("{robot_frame: x}", frame="<robot_fram>")
    with pytest.raises(
        MappingError, match=r"v\.yaml:11:15: .*<robot_fram>.*\(did you mean 'robot_frame'\?\)"
    ):
        load_mapping_text(text, "v.yaml")


# --- validate-mapping --resolved -------------------------------------------------------------------------
@pytest.mark.parametrize("name", ["default", "enu"])
def test_resolved_prints_a_standalone_mapping_that_loads_to_the_same_rules(name, tmp_path, capsys):
    assert main([name, "--resolved"]) == 0
    out = capsys.readouterr().out
    document = yaml.safe_load(out)
    assert "extends" not in document and "remove" not in document
    resolved = load_mapping(write(tmp_path, "resolved.yaml", out))
    original = load_mapping(name)
    assert [(r.name, r.sim, r.ros, r.frame_id, r.tf, r.options, r.convention) for r in resolved.rules] == [
        (r.name, r.sim, r.ros, r.frame_id, r.tf, r.options, r.convention) for r in original.rules
    ]


def test_resolved_of_an_invalid_mapping_exits_1_with_the_errors(tmp_path, capsys):
    path = write(tmp_path, "bad.yaml", "version: 1\nextends: defualt\n")
    assert main([str(path), "--resolved"]) == 1
    captured = capsys.readouterr()
    assert captured.out == ""
    assert captured.err.startswith(f"{path}:2:10: extends: no shipped mapping 'defualt'")
