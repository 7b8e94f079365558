"""Property tests: whatever the input, the loaders return a value or raise their own error type."""

from __future__ import annotations

import json
from pathlib import Path

import yaml
from harness import ROOT
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from airsim_mapper.mapping.errors import MappingError
from airsim_mapper.mapping.loader import load_mapping_text
from airsim_mapper.mapping.model import MappingDoc
from airsim_mapper.mapping.scene import Scene, SceneConfigError, read_scene

WORDS = [
    "version",
    "rules",
    "defaults",
    "image_types",
    "name",
    "for_each",
    "direction",
    "sim",
    "ros",
    "type",
    "converter",
    "frame_id",
    "tf",
    "parent",
    "child",
    "queue_size",
    "latch",
    "lazy",
    "limits",
    "params",
    "robot",
    "camera_capture",
    "sim_to_ros",
    "ros_to_sim",
    "pose",
    "image",
    "sensor_msgs/Image",
    "0",
    "6",
    "/airsim_node/<robot_name>/x",
    "<image_type>",
    "enabled",
    "watchdog_s",
    "stamp",
    "qos",
    "sensor_data",
    "depth",
]
scalars = (
    st.none()
    | st.booleans()
    | st.integers(-3, 10)
    | st.floats(allow_nan=False)
    | st.sampled_from(WORDS)
    | st.text(max_size=8)
)
json_values = st.recursive(
    scalars,
    lambda inner: (
        st.lists(inner, max_size=4)
        | st.dictionaries(st.sampled_from(WORDS) | st.text(max_size=6), inner, max_size=5)
    ),
    max_leaves=25,
)
DEFAULT_DATA = yaml.safe_load((ROOT / "mappings" / "default.yaml").read_text())


def check_mapping(text: str) -> None:
    try:
        result = load_mapping_text(text, "p.yaml")
    except MappingError as err:
        assert all(line.startswith("p.yaml:") for line in str(err).splitlines())
    else:
        assert isinstance(result, MappingDoc)


@settings(max_examples=150, deadline=None)
@given(st.text(alphabet=st.characters(codec="utf-8"), max_size=200))
def test_random_text_gives_a_mapping_or_a_mapping_error(text):
    check_mapping(text)


@settings(max_examples=150, deadline=None)
@given(json_values)
def test_random_yaml_documents_give_a_mapping_or_a_mapping_error(value):
    check_mapping(yaml.safe_dump(value))


@settings(max_examples=60, deadline=None)
@given(st.integers(0, len(DEFAULT_DATA["rules"]) - 1), st.sampled_from(WORDS[4:20]), json_values)
def test_a_default_mapping_with_one_value_replaced_gives_a_mapping_or_a_mapping_error(index, key, value):
    data = json.loads(json.dumps(DEFAULT_DATA))
    data["rules"][index][key] = value
    check_mapping(yaml.safe_dump(data))


SCENE_WORDS = [
    "id",
    "actors",
    "type",
    "robot",
    "name",
    "origin",
    "xyz",
    "rpy-deg",
    "robot-config",
    "robot.jsonc",
    "sensors",
    "physics-type",
    "non-physics",
    "enabled",
    "camera",
    "capture-settings",
    "0 0 0",
]
scene_values = st.recursive(
    st.none() | st.booleans() | st.integers(-2, 3) | st.sampled_from(SCENE_WORDS),
    lambda inner: (
        st.lists(inner, max_size=3) | st.dictionaries(st.sampled_from(SCENE_WORDS), inner, max_size=5)
    ),
    max_leaves=20,
)
robot_like = st.fixed_dictionaries(
    {"physics-type": st.sampled_from(["non-physics", "bogus"])},
    optional={
        "sensors": st.lists(
            st.dictionaries(st.sampled_from(SCENE_WORDS), scene_values, max_size=4), max_size=2
        )
    },
)
scene_like = st.fixed_dictionaries(
    {
        "id": st.sampled_from(["S", "Drone 1"]) | scene_values,
        "actors": st.lists(
            st.fixed_dictionaries(
                {
                    "type": st.just("robot"),
                    "name": st.sampled_from(["R", "R2"]),
                    "origin": st.just({"xyz": "0 0 0", "rpy-deg": "0 0 0"}),
                    "robot-config": st.sampled_from(["robot.jsonc", "missing.jsonc", "../x.jsonc"]),
                },
            ),
            max_size=2,
        ),
    }
)


@settings(max_examples=40, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(scene_like | scene_values, robot_like | scene_values, st.booleans())
def test_random_scene_and_robot_json_give_a_scene_or_a_scene_error(tmp_path: Path, scene, robot, garble):
    (tmp_path / "scene.jsonc").write_text(json.dumps(scene)[:-3] if garble else json.dumps(scene))
    (tmp_path / "robot.jsonc").write_text(json.dumps(robot))
    try:
        result = read_scene(tmp_path, "scene.jsonc")
    except SceneConfigError as err:
        assert str(err)
    else:
        assert isinstance(result, Scene)
