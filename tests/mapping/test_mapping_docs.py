"""The examples of docs/mapping-language.md validate and do what the text says, on the sensors scene."""

from __future__ import annotations

import re

import pytest
from harness import ROOT, SIM_CONFIG

from airsim_mapper.mapping.expand import expand
from airsim_mapper.mapping.loader import load_mapping, load_mapping_text
from airsim_mapper.mapping.scene import read_scene

DOC = (ROOT / "docs" / "mapping-language.md").read_text()
EXAMPLES = dict(re.findall(r"<!-- example: (\w+) -->\n```yaml\n(.*?)```", DOC, re.S))
ROBOT = "/airsim_node/Drone1"


def bridges(name: str) -> dict:
    mapping = load_mapping_text(EXAMPLES[name], f"docs/mapping-language.md#{name}")
    scene = read_scene(SIM_CONFIG, "scene_drone_sensors.jsonc")
    return {bridge.name: bridge for bridge in expand(mapping, scene, "projectairsim")}


def default_bridges() -> dict:
    scene = read_scene(SIM_CONFIG, "scene_drone_sensors.jsonc")
    return {bridge.name: bridge for bridge in expand(load_mapping("default"), scene, "projectairsim")}


def test_the_document_has_its_examples():
    assert set(EXAMPLES) == {"frames", "select", "rename", "one_camera", "no_chase_depth", "readme", "qos"}


def test_qos_makes_images_reliable_keeps_one_cloud_and_fifty_imu_samples():
    got = bridges("qos")
    assert str(got["camera_image[Drone1/Chase/scene_camera]"].qos) == "reliable/volatile/10"
    assert str(got["lidar[Drone1/lidar1]"].qos) == "best_effort/volatile/1"
    assert str(got["imu[Drone1/IMU1]"].qos) == "reliable/volatile/50"
    assert str(got["camera_info[Drone1/Chase/scene_camera]"].qos) == "best_effort/volatile/5"


@pytest.mark.parametrize("name", sorted(EXAMPLES))
def test_every_example_validates_and_expands(name):
    assert bridges(name)


def test_rename_renames_one_topic_and_slows_the_images():
    got = bridges("rename")
    assert got["actual_pose[Drone1]"].ros == "/drones/Drone1/pose"
    images = [b for b in got.values() if b.rule == "camera_image"]
    assert images and all(b.options.rate_limit_hz == 5.0 for b in images)
    assert set(got) == set(default_bridges())


def test_one_camera_slows_only_the_chase_camera():
    got = bridges("one_camera")
    assert got["chase_image[Drone1/Chase/scene_camera]"].options.rate_limit_hz == 5.0
    assert "camera_image[Drone1/Chase/scene_camera]" not in got
    assert got["camera_image[Drone1/DownCamera/scene_camera]"].options.rate_limit_hz is None
    assert {b.ros for b in got.values()} == {b.ros for b in default_bridges().values()}


def test_no_chase_depth_drops_only_the_chase_cameras_depth_images():
    got = {b.ros for b in bridges("no_chase_depth").values()}
    expected = {b.ros for b in default_bridges().values()} - {
        f"{ROBOT}/Chase/{kind}/image" for kind in ("depth_camera", "depth_planar_camera", "depth_vis_camera")
    }
    assert got == expected


def test_frames_renames_the_robot_frames():
    got = bridges("frames")
    assert got["actual_pose[Drone1]"].tf.child == "Drone1/base_link"
    assert got["lidar[Drone1/lidar1]"].frame_id == "Drone1/lidar1"


def test_select_keeps_the_selected_elements():
    got = bridges("select")
    images = {b.name for b in got.values() if b.rule == "camera_image"}
    assert images and all("Drone1/DownCamera/" in name for name in images)
    infos = {b.name for b in got.values() if b.rule == "camera_info"}
    assert infos and not any("depth_" in name or "Chase" in name for name in infos)
    assert not any(b.rule == "lidar" for b in got.values())


def test_the_readme_example_does_all_three():
    got = bridges("readme")
    assert got["actual_pose[Drone1]"].ros == "/drones/Drone1/pose"
    images = [b for b in got.values() if b.rule == "camera_image"]
    assert len(images) == 8 and all(b.options.rate_limit_hz == 5.0 for b in images)
    assert not any(b.rule == "lidar" for b in got.values())  # the sensors scene has no Scout*


def test_the_readme_shows_the_readme_example_as_tested_here():
    readme = (ROOT / "README.md").read_text()
    assert f"```yaml\n{EXAMPLES['readme']}```" in readme
