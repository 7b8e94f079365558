"""image_transport's topic parameters over a rule's params: found ones replace the rule's value, ones out of
the schema's bounds are refused by name and bound, and the bounds are the mapping schema's."""

from __future__ import annotations

import json

import pytest
from harness import ROOT

from airsim_mapper.convert.transport_params import (
    TOPIC_PARAMS,
    is_topic_parameter,
    overridden,
    parameter_name,
)

TOPIC = "/airsim_node/Drone1/front/scene_camera/image/compressed"
DEPTH_TOPIC = "/airsim_node/Drone1/front/depth_planar_camera/image/compressedDepth"


def test_a_set_parameter_replaces_the_rules_value_and_unset_ones_leave_it():
    ros = {f"{TOPIC}/jpeg_quality": 20}
    found = overridden("image_compressed", TOPIC, {"format": "jpeg", "jpeg_quality": 80}, ros.get)
    assert dict(found.params) == {"format": "jpeg", "jpeg_quality": 20} and found.refused == ()


def test_the_depth_transport_reads_its_own_names():
    ros = {f"{DEPTH_TOPIC}/depth_max": 50, f"{DEPTH_TOPIC}/png_level": 3, f"{DEPTH_TOPIC}/jpeg_quality": 5}
    found = overridden("image_compressed_depth", DEPTH_TOPIC, {"depth_max": 100.0}, ros.get)
    assert dict(found.params) == {"depth_max": 50, "png_level": 3}


@pytest.mark.parametrize(
    ("param", "value", "bound"),
    [
        ("jpeg_quality", 0, "an integer from 1 to 100"),
        ("jpeg_quality", 101, "an integer from 1 to 100"),
        ("jpeg_quality", 50.5, "an integer"),
        ("png_level", 10, "an integer from 1 to 9"),
        ("format", "webp", "one of jpeg, png"),
    ],
)
def test_a_value_out_of_bounds_is_refused_by_name_and_bound_and_the_rules_value_kept(param, value, bound):
    name = parameter_name(TOPIC, param)
    rule = {"format": "png", "jpeg_quality": 80, "png_level": 9}
    found = overridden("image_compressed", TOPIC, rule, {name: value}.get)
    assert dict(found.params) == rule
    assert found.refused == (
        f"parameter {name} = {value!r} ignored: it must be {bound}; keeping {rule[param]}",
    )


def test_depth_bounds_are_positive_numbers():
    ros = {f"{DEPTH_TOPIC}/depth_max": 0.0, f"{DEPTH_TOPIC}/depth_quantization": True}
    found = overridden("image_compressed_depth", DEPTH_TOPIC, {}, ros.get)
    assert dict(found.params) == {}
    assert [r.split(" ignored: it must be ")[1] for r in found.refused] == [
        "a number above 0; keeping the converter's default",
        "a number; keeping the converter's default",
    ]


def test_other_converters_read_no_parameters():
    asked: list[str] = []
    found = overridden("image", TOPIC, {"x": 1}, lambda name: asked.append(name))
    assert dict(found.params) == {"x": 1} and asked == []


def test_the_bounds_are_the_mapping_schemas():
    schema = json.loads((ROOT / "schemas" / "mapping.schema.json").read_text())
    stack, params = [schema], None
    while stack and params is None:  # the rule's `params` property, wherever the schema defines it
        node = stack.pop()
        if isinstance(node, dict):
            if isinstance(node.get("params"), dict) and "jpeg_quality" in node["params"].get(
                "properties", {}
            ):
                params = node["params"]["properties"]
            stack.extend(node.values())
        elif isinstance(node, list):
            stack.extend(node)
    assert params is not None
    for bounds in TOPIC_PARAMS.values():
        for name, bound in bounds.items():
            if bound.choices:
                continue
            given = params[name]
            assert (given["type"] == "integer") == bound.integer, name
            if bound.above:
                assert given["exclusiveMinimum"] == bound.low, name
            else:
                assert (given["minimum"], given["maximum"]) == (bound.low, bound.high), name


def test_topic_parameters_are_told_apart_from_others():
    assert is_topic_parameter(f"{TOPIC}/jpeg_quality")
    assert is_topic_parameter(f"{DEPTH_TOPIC}/depth_quantization")
    assert not is_topic_parameter(f"{DEPTH_TOPIC}/jpeg_quality")
    assert not is_topic_parameter("/airsim_node/mapping")
