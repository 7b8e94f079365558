"""The image_transport rules: their params checked with located errors, and an image type the transport
cannot carry (JPEG of a depth image) refused when the mapping is expanded, before anything runs."""

from __future__ import annotations

import pytest
from harness import ROOT

from airsim_mapper.mapping.errors import MappingError
from airsim_mapper.mapping.expand import expand
from airsim_mapper.mapping.loader import load_mapping, load_mapping_text
from airsim_mapper.mapping.scene import read_scene

RULE = """\
version: 1
rules:
  - name: compressed
    for_each: camera_capture
    direction: sim_to_ros
    sim: /Sim/<scene_name>/robots/<robot_name>/sensors/<camera_name>/<sim_image_type>
    ros: /airsim_node/<robot_name>/<camera_name>/<image_type>/image/compressed
    type: sensor_msgs/CompressedImage
    converter: CONVERTER
    params: PARAMS
"""


def mapping(converter: str = "image_compressed", params: str = "{}"):
    return load_mapping_text(RULE.replace("CONVERTER", converter).replace("PARAMS", params), "m.yaml")


def problem(converter: str, params: str) -> str:
    with pytest.raises(MappingError) as err:
        mapping(converter, params)
    return str(err.value)


def test_good_params_load():
    rule = mapping(params="{format: png, png_level: 3}").rules[0]
    assert dict(rule.params) == {"format": "png", "png_level": 3}
    rule = mapping("image_compressed_depth", "{depth_max: 50, depth_quantization: 80.5}").rules[0]
    assert rule.params["depth_max"] == 50


@pytest.mark.parametrize("quality", ["0", "101", "80.5", "true", "high"])
def test_a_jpeg_quality_out_of_range_is_a_located_error(quality):
    text = problem("image_compressed", f"{{jpeg_quality: {quality}}}")
    assert text.startswith("m.yaml:10:"), text
    assert "jpeg_quality" in text


@pytest.mark.parametrize(("key", "value"), [("png_level", "0"), ("png_level", "10"), ("depth_max", "0")])
def test_png_level_and_depth_bounds_are_located_errors(key, value):
    text = problem("image_compressed_depth", f"{{{key}: {value}}}")
    assert text.startswith("m.yaml:10:") and key in text, text


def test_an_unknown_format_is_a_located_error_with_a_did_you_mean():
    text = problem("image_compressed", "{format: jpg}")
    assert text == (
        "m.yaml:10:22: rule 'compressed': params.format must be one of jpeg, png, got 'jpg' "
        "(did you mean 'jpeg'?)"
    )


@pytest.mark.parametrize(
    ("converter", "params", "takers"),
    [
        ("image_compressed_depth", "{jpeg_quality: 80}", "image_compressed"),
        ("image_compressed", "{depth_max: 20}", "image_compressed_depth"),
        ("image", "{png_level: 3}", "image_compressed and image_compressed_depth"),
    ],
)
def test_a_transport_param_on_a_converter_that_does_not_take_it_is_a_located_error(converter, params, takers):
    text = problem(converter, params).splitlines()[-1]
    assert text.startswith("m.yaml:10:") and text.endswith(f"applies only to {takers}"), text


def test_jpeg_of_a_depth_image_is_refused_when_the_mapping_is_expanded():
    scene = read_scene(ROOT / "sim_config", "scene_drone_sensors.jsonc")
    with pytest.raises(MappingError) as err:
        expand(mapping(), scene, "n")
    lines = str(err.value).splitlines()
    assert len(lines) == 2  # depth_planar_camera and depth_camera, nothing else
    assert lines[0] == (
        "m.yaml:3:1: bridge compressed[Drone1/DownCamera/depth_planar_camera]: converter 'image_compressed' "
        "cannot encode image type 1 (depth_planar_camera, a float depth image): use image_compressed_depth, "
        "or a match on image_type_id that leaves it out"
    )
    with pytest.raises(MappingError) as err:
        expand(mapping("image_compressed_depth"), scene, "n")
    assert "converter 'image_compressed_depth' cannot encode image type 0 (scene_camera" in str(err.value)


def test_the_default_mapping_has_the_sibling_topics_of_every_image():
    scene = read_scene(ROOT / "sim_config", "scene_drone_sensors.jsonc")
    bridges = expand(load_mapping(ROOT / "mappings" / "default.yaml"), scene, "n")
    images = {b.ros for b in bridges if b.rule == "camera_image"}
    compressed = {b.ros for b in bridges if b.rule == "camera_image_compressed"}
    depth = {b.ros for b in bridges if b.rule == "camera_image_compressed_depth"}
    assert {
        f"{ros}/compressed" for ros in images if "depth_camera" not in ros and "depth_planar" not in ros
    } == (compressed)
    assert depth == {
        "/airsim_node/Drone1/DownCamera/depth_planar_camera/image/compressedDepth",
        "/airsim_node/Drone1/DownCamera/depth_camera/image/compressedDepth",
    }
    assert all(b.options.lazy for b in bridges if b.ros in compressed | depth)
