"""Loading mappings: defaults, options, safe YAML with marks, and errors reported all at once."""

from __future__ import annotations

import pytest
from scene_builders import pose_rule

from airsim_mapper.mapping.errors import MappingError
from airsim_mapper.mapping.loader import DEFAULT_IMAGE_TYPES, load_mapping_text
from airsim_mapper.mapping.model import Limits
from airsim_mapper.mapping.yamlmarks import YamlLimits, load_marked

CMD_VEL = """
version: 1
defaults: {queue_size: 5, stamp: ros, convention: enu, limits: {max_linear_speed: 2.0}}
rules:
  - name: cmd_vel
    for_each: robot
    direction: ros_to_sim
    sim: /Sim/<scene_name>/robots/<robot_name>/MoveByVelocity
    ros: /airsim_node/<robot_name>/cmd_vel
    type: geometry_msgs/Twist
    converter: cmd_vel
    watchdog_s: 1.5
    limits: {max_yaw_rate: 0.5, on_violation: reject}
    params: {frame: world}
  - name: pose
    for_each: robot
    direction: sim_to_ros
    sim: /Sim/<scene_name>/robots/<robot_name>/actual_pose
    ros: <namespace>/airsim_node/<robot_name>/actual_pose
    type: geometry_msgs/PoseStamped
    converter: pose
    convention: ned
    queue_size: 1
    enabled: false
"""


def test_rules_take_the_defaults_they_do_not_set_and_keep_their_own():
    mapping = load_mapping_text(CMD_VEL, "m.yaml")
    cmd, pose = mapping.rules
    assert (cmd.options.queue_size, cmd.options.stamp, cmd.options.watchdog_s, cmd.convention) == (
        5,
        "ros",
        1.5,
        "enu",
    )
    assert cmd.options.limits == Limits(max_linear_speed=2.0, max_yaw_rate=0.5, on_violation="reject")
    assert dict(cmd.params) == {"frame": "world"}
    assert (cmd.line, cmd.ros_kind) == (5, "topic")
    assert (pose.options.queue_size, pose.options.enabled, pose.convention) == (1, False, "ned")
    assert dict(mapping.image_types) == DEFAULT_IMAGE_TYPES
    assert mapping.source == "m.yaml"


def test_a_service_type_makes_a_service_rule():
    text = """
version: 1
rules:
  - {name: sw, for_each: streaming_camera, direction: ros_to_sim, sim: /Sim/<scene_name>/SwitchStreamingView,
     ros: /airsim_streaming_camera/switch_view, type: std_srvs/Trigger, converter: switch_view}
"""
    assert load_mapping_text(text).rules[0].ros_kind == "service"


def test_a_custom_image_type_table_must_name_all_seven_types():
    text = "version: 1\nimage_types: {0: rgb, 1: depth}\nrules: []\n"
    with pytest.raises(MappingError, match=r"^t\.yaml:2:14: image_types: '2' is required"):
        load_mapping_text(text, "t.yaml")


def test_a_tf_only_rule_needs_tf():
    text = """version: 1
rules:
  - {name: t, for_each: robot, direction: sim_to_ros, sim: /Sim/<scene_name>/robots/<robot_name>/actual_pose,
     converter: pose}
"""
    with pytest.raises(
        MappingError, match=r"t\.yaml:3:5: rule 't': 'ros' is required \(only a sim_to_ros rule"
    ):
        load_mapping_text(text, "t.yaml")


def test_a_ros_side_needs_a_type():
    text = """version: 1
rules:
  - {name: t, for_each: node, direction: ros_to_sim, ros: /load, converter: load_scene}
"""
    with pytest.raises(MappingError, match=r"t\.yaml:3:59: rule 't': 'type' is required when 'ros' is set"):
        load_mapping_text(text, "t.yaml")


def test_rules_must_be_a_list_of_rules():
    with pytest.raises(MappingError, match=r"^t\.yaml:2:8: rules: expected array, got \{\}$"):
        load_mapping_text("version: 1\nrules: {}\n", "t.yaml")


def test_the_loader_reports_problems_from_every_rule_at_once():
    text = CMD_VEL.replace("converter: cmd_vel", "converter: cmd_vell").replace(
        "queue_size: 1\n", "queue_size: 0\n"
    )
    with pytest.raises(MappingError) as caught:
        load_mapping_text(text, "m.yaml")
    assert str(caught.value).splitlines() == [
        "m.yaml:11:16: rule 'cmd_vel': unknown converter 'cmd_vell' (did you mean 'cmd_vel'?)",
        "m.yaml:23:17: rules[1] 'pose'.queue_size: must be at least 1, got 0",
    ]


def test_python_tags_are_refused_and_never_executed(tmp_path):
    marker = tmp_path / "ran"
    text = f"version: 1\nrules: []\nx: !!python/object/apply:os.system ['touch {marker}']\n"
    with pytest.raises(MappingError, match=r"t\.yaml:3:4: invalid YAML value: the tag .*python/object/apply"):
        load_mapping_text(text, "t.yaml")
    with pytest.raises(
        MappingError,
        match=r"could not determine a constructor for the tag 'tag:yaml\.org,2002:python/object:",
    ):
        load_marked("a: !!python/object:collections.OrderedDict\n", "t.yaml")
    assert not marker.exists()


def test_marks_locate_keys_and_values():
    data, marks = load_marked("a:\n  - b: 1\n    c: [x, y]\n", "t.yaml")
    assert data == {"a": [{"b": 1, "c": ["x", "y"]}]}
    assert marks.key(("a", 0, "c")) == (3, 5)
    assert marks.value(("a", 0, "c", 1)) == (3, 12)
    assert marks.value(("a", 0, "missing")) == (2, 5)


def test_recursive_aliases_are_an_error_not_a_hang():
    with pytest.raises(MappingError, match=r"t\.yaml:1:\d+: recursive or too deeply nested YAML"):
        load_marked("a: &x [1, *x]\n", "t.yaml")


def test_a_position_box_is_read_and_an_inverted_one_is_a_located_error():
    boxed = CMD_VEL.replace(
        "limits: {max_yaw_rate: 0.5, on_violation: reject}",
        "limits: {position_box: {min: [-1, -2, -3], max: [1, 2, 0]}}",
    )
    box = load_mapping_text(boxed, "m.yaml").rules[0].options.limits.position_box
    assert (box.min, box.max) == ((-1, -2, -3), (1, 2, 0))
    inverted = boxed.replace("max: [1, 2, 0]", "max: [1, -5, -4]")
    with pytest.raises(MappingError) as err:
        load_mapping_text(inverted, "m.yaml")
    assert str(err.value) == ("m.yaml:13:28: rule 'cmd_vel': limits.position_box has min above max on y, z")


def test_yaml_limits_bound_values_and_file_size_and_are_configurable():
    text = "version: 1\nrules: []\nx: &x [1, 2, 3]\ny: [*x, *x]\n"
    assert load_marked(text, "m.yaml")[0]["y"] == [[1, 2, 3], [1, 2, 3]]
    with pytest.raises(MappingError, match=r"^m.yaml:3:4: the aliases of this anchor expand"):
        load_marked(text, "m.yaml", YamlLimits(max_alias_expansions=5))
    with pytest.raises(MappingError, match=r"^m.yaml:3:14: the YAML holds more than 6 values"):
        load_marked(text, "m.yaml", YamlLimits(max_values=6))
    with pytest.raises(MappingError, match=r"^m.yaml:1:1: the file is larger than 10 bytes"):
        load_marked(text, "m.yaml", YamlLimits(max_bytes=10))


def test_a_type_naming_an_installed_module_that_is_no_message_package_is_refused_without_importing_it(
    tmp_path, monkeypatch
):
    trap = tmp_path / "trap_pkg"
    (trap / "msg").mkdir(parents=True)
    ran = tmp_path / "ran"
    (trap / "__init__.py").write_text(f"open({str(ran)!r}, 'w').close()\n")
    (trap / "msg" / "__init__.py").write_text("Foo = object\n")
    (trap / "msg" / "_Foo.py").write_text("Foo = object\n")  # not generated by genpy
    monkeypatch.syspath_prepend(str(tmp_path))
    text = CMD_VEL.replace("type: geometry_msgs/PoseStamped", "type: trap_pkg/Foo")
    with pytest.raises(MappingError, match=r"'trap_pkg' is not a ROS message package"):
        load_mapping_text(text, "m.yaml")
    assert not ran.exists()


IMAGE_RULE = """
version: 1
rules:
  - name: camera_image
    for_each: camera_capture
    direction: sim_to_ros
    sim: /Sim/<scene_name>/robots/<robot_name>/sensors/<camera_name>/<sim_image_type>
    ros: /airsim_node/<robot_name>/<camera_name>/<image_type>
    type: sensor_msgs/Image
    converter: image
    params: {max_pixels: PIXELS}
"""


def test_an_image_rule_may_bound_its_pixels_and_a_bad_bound_is_a_located_error():
    rule = load_mapping_text(IMAGE_RULE.replace("PIXELS", "1000000"), "m.yaml").rules[0]
    assert rule.params["max_pixels"] == 1_000_000
    for bad in ("0", "-5", "1.5", "lots", "true"):
        with pytest.raises(MappingError) as err:
            load_mapping_text(IMAGE_RULE.replace("PIXELS", bad), "m.yaml")
        assert str(err.value).startswith(
            "m.yaml:11:26: rule 'camera_image': params.max_pixels must be a positive integer, got "
        ), bad
    with pytest.raises(MappingError) as err:
        load_mapping_text(CMD_VEL.replace("{frame: world}", "{frame: world, max_pixels: 5}"), "m.yaml")
    assert str(err.value) == (
        "m.yaml:14:28: rule 'cmd_vel': params.max_pixels applies only to the image converters"
    )


def test_an_image_rule_may_bound_its_converted_bytes_and_a_bad_bound_is_a_located_error():
    text = IMAGE_RULE.replace("max_pixels: PIXELS", "max_bytes: BYTES")
    rule = load_mapping_text(text.replace("BYTES", "4000000"), "m.yaml").rules[0]
    assert rule.params["max_bytes"] == 4_000_000
    with pytest.raises(MappingError) as err:
        load_mapping_text(text.replace("BYTES", "-1"), "m.yaml")
    assert str(err.value).startswith("m.yaml:11:25: rule 'camera_image': params.max_bytes must be a positive")


def test_a_fifo_given_as_mapping_is_refused_at_once(tmp_path):
    import os

    from airsim_mapper.mapping.loader import load_mapping

    fifo = tmp_path / "mapping.yaml"
    os.mkfifo(fifo)
    with pytest.raises(MappingError) as err:
        load_mapping(fifo)
    assert str(err.value) == f"{fifo}: the mapping file is a FIFO (named pipe), not a regular file"
    assert not err.value.unreadable


MERGED = """
version: 1
rules:
  - &pose
    name: pose
    for_each: robot
    direction: sim_to_ros
    sim: /Sim/<scene_name>/robots/<robot_name>/actual_pose
    ros: /a/<robot_name>/pose
    type: geometry_msgs/PoseStamped
    converter: pose
    lazy: true
  - <<: *pose
    name: pose_b
    ros: /b/<robot_name>/pose
    lazy: false
  - <<: [{queue_size: 5, lazy: false}, *pose]
    name: pose_c
    ros: /c/<robot_name>/pose
"""


def test_yaml_merge_keys_bring_in_an_anchor_and_the_rules_own_keys_win():
    first, second, third = load_mapping_text(MERGED, "m.yaml").rules
    assert (second.name, second.ros, second.converter, second.options.lazy) == (
        "pose_b",
        "/b/<robot_name>/pose",
        "pose",
        False,
    )
    assert first.options.lazy is True  # the anchor itself is unchanged
    # of a list of merged mappings the earlier wins, as in PyYAML
    assert (third.options.queue_size, third.options.lazy, third.sim) == (5, False, first.sim)


def test_a_key_repeated_beside_a_merge_key_is_still_a_duplicate():
    with pytest.raises(MappingError) as err:
        load_mapping_text(MERGED + "    name: pose_d\n", "m.yaml")
    assert str(err.value) == "m.yaml:20:5: duplicate key 'name'"


def test_first_message_is_fresh_by_default_and_a_rule_may_keep_the_cached_one():
    text = CMD_VEL.replace("    enabled: false\n", "    first_message: cached\n")
    cmd, pose = load_mapping_text(text, "m.yaml").rules
    assert (cmd.options.first_message, pose.options.first_message) == ("fresh", "cached")
    with pytest.raises(MappingError, match="first_message"):
        load_mapping_text(text.replace("first_message: cached", "first_message: stale"), "m.yaml")


def _problems(*rules: tuple[str, str]) -> list[str]:
    """The problems (without their places) of pose rules on one ROS name, each (name, extra lines)."""
    listed = "".join(pose_rule(name, "/x/<robot_name>/pose") + extra for name, extra in rules)
    text = "version: 1\nrules:\n" + listed
    with pytest.raises(MappingError) as caught:
        load_mapping_text(text, "m.yaml")
    return [problem.split(": ", 1)[1] for problem in str(caught.value).splitlines()]


def test_a_rule_the_schema_refuses_still_counts_in_the_duplicate_checks_when_it_would_publish():
    problems = _problems(("pose", "    queue_size: 0\n"), ("pose", ""))
    assert any("duplicate rule name 'pose'" in p for p in problems)
    assert any("ROS name '/x/<robot_name>/pose' is also used by rule 'pose'" in p for p in problems)


@pytest.mark.parametrize(
    "mistake",
    ['    enabled: "false"\n', "    enabeld: false\n", "    match: {robot_name: 5}\n"],
    ids=["bad_enabled", "misspelt_key", "bad_match"],
)
def test_a_refused_rule_that_may_not_publish_its_ros_claims_no_duplicate_ros_name(mistake):
    problems = _problems(("first", mistake), ("second", ""))
    assert len(problems) == 1 and "rules[0] 'first'" in problems[0]  # the schema's own, alone
    assert any("duplicate rule name" in p for p in _problems(("same", mistake), ("same", "")))
