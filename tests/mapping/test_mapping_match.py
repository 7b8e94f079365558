"""Per-rule `match:`: globs, lists as "any of", "!" as "none of", located errors, and the preview's report."""

from __future__ import annotations

import pytest
from scene_builders import camera, capture

from airsim_mapper.cli.validate import main
from airsim_mapper.mapping.errors import MappingError
from airsim_mapper.mapping.expand import expand, selected
from airsim_mapper.mapping.loader import load_mapping_text
from airsim_mapper.mapping.match import Selector, matches, pattern_problem
from airsim_mapper.mapping.scene import read_scene

IMAGES = """version: 1
rules:
  - name: image
    for_each: camera_capture
    direction: sim_to_ros
    sim: /Sim/<scene_name>/robots/<robot_name>/sensors/<camera_name>/<sim_image_type>
    ros: /<robot_name>/<camera_name>/<image_type>
    type: sensor_msgs/Image
    converter: image
"""


@pytest.fixture
def scene(write_scene):
    captures = [capture(0), capture(1), capture(2), capture(3)]
    robots = {
        "Scout1": [camera("FrontCam", captures), camera("Belly", captures), camera("Chase", captures)],
        "Scout2": [camera("FrontCam", captures)],
        "Tanker": [camera("FrontCam", captures)],
    }
    return read_scene(write_scene(robots), "scene.jsonc")


def topics(match: str, scene) -> list[str]:
    mapping = load_mapping_text(IMAGES + f"    match: {match}\n", "m.yaml")
    return [bridge.ros for bridge in expand(mapping, scene, "n")]


def test_a_glob_a_list_and_a_negation_select_elements_together(scene):
    got = topics('{robot_name: "Scout*", camera_name: [FrontCam, Belly], image_type: "!depth_*"}', scene)
    assert got == [
        "/Scout1/FrontCam/scene_camera",
        "/Scout1/FrontCam/segmentation_camera",
        "/Scout1/Belly/scene_camera",
        "/Scout1/Belly/segmentation_camera",
        "/Scout2/FrontCam/scene_camera",
        "/Scout2/FrontCam/segmentation_camera",
    ]


def test_a_list_of_negations_is_none_of_them_and_globs_are_case_sensitive(scene):
    assert topics('{camera_name: ["!Belly", "!Chase"], robot_name: "scout*"}', scene) == []
    got = topics('{camera_name: ["!Belly", "!Chase"], robot_name: "Tank?r", image_type: "[sd]*"}', scene)
    assert got == [
        "/Tanker/FrontCam/scene_camera",
        "/Tanker/FrontCam/depth_planar_camera",
        "/Tanker/FrontCam/depth_camera",
        "/Tanker/FrontCam/segmentation_camera",
    ]


def test_a_list_of_selections_keeps_what_any_of_them_keeps(scene):
    got = topics('[{camera_name: "!Chase"}, {image_type: "!depth_*"}]', scene)
    chase = [topic for topic in got if "/Chase/" in topic]
    assert chase == ["/Scout1/Chase/scene_camera", "/Scout1/Chase/segmentation_camera"]
    assert len(got) == 18  # 20 less the Chase camera's two depth images


def test_bad_entries_of_a_list_of_selections_are_located_errors():
    with pytest.raises(MappingError) as caught:
        load_mapping_text(IMAGES + '    match: [{camera_name: A}, {lidar_nme: "x["}]\n', "m.yaml")
    assert str(caught.value).splitlines() == [
        "m.yaml:10:32: rule 'image': match: <lidar_nme> is not a variable of for_each camera_capture "
        "(for_each camera_capture has: node_name, namespace, frame_prefix, scene_name, robot_name, "
        "camera_name, image_type, image_type_id, sim_image_type)"
    ]


def test_selector_and_matches_are_pure():
    assert Selector.of(["a*", "!ab*"]) == Selector(("a*",), ("ab*",))
    assert Selector.of(["a*", "!ab*"]).accepts("ax") and not Selector.of(["a*", "!ab*"]).accepts("abc")
    assert Selector.of(["!x"]).accepts("y")
    assert matches([{"robot_name": ("R*",)}], {"robot_name": "R1"})
    assert matches([], {"robot_name": "R1"})
    both = {"robot_name": ("R*",), "camera_name": ("C",)}
    assert not matches([both], {"robot_name": "R1", "camera_name": "D"})
    assert matches([both, {"camera_name": ("D",)}], {"robot_name": "R1", "camera_name": "D"})


@pytest.mark.parametrize(
    ("pattern", "why"),
    [
        ("", "an empty pattern"),
        ("!", "an empty pattern"),
        ("!!x", "a double '!'"),
        ("Cam[12", "an unclosed '[' at character 4"),
        ("[]", "an unclosed '['"),
        ("[!", "an unclosed '['"),
    ],
)
def test_bad_globs_are_named(pattern, why):
    assert pattern_problem(pattern).startswith(why)


@pytest.mark.parametrize("pattern", ["*", "Cam[12]", "[]]x", "[!a]*", "!depth_*", "a?b"])
def test_good_globs_pass(pattern):
    assert pattern_problem(pattern) is None


@pytest.mark.parametrize(
    ("match", "expected"),
    [
        (
            "{camera_nam: x}",
            "10:13: rule 'image': match: <camera_nam> is not a variable of for_each camera_capture "
            "(did you mean 'camera_name'?)",
        ),
        (
            "{lidar_name: x}",
            "10:13: rule 'image': match: <lidar_name> is not a variable of for_each camera_capture "
            "(for_each camera_capture has: node_name, namespace, frame_prefix",
        ),
        ("{camera_name: [a, 'Cam[1']}", "10:30: rule 'image': match.camera_name 'Cam[1': an unclosed '['"),
        ("{camera_name: ''}", "10:26: rule 'image': match.camera_name '': an empty pattern"),
        ("{camera_name: 3}", "10:26: rules[0] 'image'.match.camera_name: expected string or array, got 3"),
        ("{camera_name: []}", "10:26: rules[0] 'image'.match.camera_name: [] should be non-empty"),
        ("{}", "10:12: rules[0] 'image'.match: {} should be non-empty"),
    ],
)
def test_bad_match_entries_are_located_errors(match, expected):
    with pytest.raises(MappingError) as caught:
        load_mapping_text(IMAGES + f"    match: {match}\n", "m.yaml")
    lines = str(caught.value).splitlines()
    assert any(line.startswith(f"m.yaml:{expected}") for line in lines), lines


def test_selected_counts_what_each_match_keeps(scene):
    mapping = load_mapping_text(IMAGES + '    match: {robot_name: "Scout*"}\n')
    assert selected(mapping, scene, "n") == {"image": (16, 20)}


def test_the_preview_reports_the_selection_and_warns_about_a_rule_matching_nothing(
    scene, tmp_path, write_scene, capsys
):
    root = tmp_path / "sim_config"
    path = tmp_path / "m.yaml"
    path.write_text(IMAGES + '    match: {robot_name: "Nobody*"}\n')
    assert main([str(path), "--scene", "scene.jsonc", "--simconfigpath", str(root)]) == 0
    captured = capsys.readouterr()
    assert "match: rule 'image' (robot_name: Nobody*) selects 0 of 20 elements" in captured.out
    assert captured.err == f"{path}:3: warning: rule 'image': match selects nothing in scene TestScene\n"
