"""QoS in the mapping: a rule's `qos` validated with located messages, each converter family's default,
explicit settings, a profile with overrides, and latched rules."""

from __future__ import annotations

import json

import pytest
from harness import ROOT, SIM_CONFIG
from hypothesis import given
from hypothesis import strategies as st

from airsim_mapper.convert.catalog import CONVERTERS, QOS_PROFILES
from airsim_mapper.mapping.errors import MappingError
from airsim_mapper.mapping.loader import load_mapping_text
from airsim_mapper.mapping.model import Qos
from airsim_mapper.mapping.pipeline import load_and_expand
from airsim_mapper.mapping.qos import PROFILES, node_topic_qos, qos_of
from airsim_mapper.mapping.schema import schema

BEST_EFFORT_5 = Qos("best_effort", "volatile", 5)
RELIABLE_10 = Qos("reliable", "volatile", 10)
LATCHED = Qos("reliable", "transient_local", 1)


def pose_mapping(qos: str = "", latch: bool = False) -> str:
    """A one-rule mapping whose rule ends with the line `qos` (when given)."""
    lines = [
        "version: 1",
        "rules:",
        "  - name: pose",
        "    for_each: robot",
        "    direction: sim_to_ros",
        "    converter: pose",
        "    sim: /Sim/<scene_name>/robots/<robot_name>/actual_pose",
        "    ros: /x/<robot_name>/pose",
        "    type: geometry_msgs/PoseStamped",
    ]
    if latch:
        lines.append("    latch: true")
    if qos:
        lines.append(f"    qos: {qos}")
    return "\n".join(lines) + "\n"


def rule_qos(qos: str, latch: bool = False) -> Qos | None:
    return load_mapping_text(pose_mapping(qos, latch), "m.yaml").rules[0].options.qos


def problems(text: str) -> list[str]:
    with pytest.raises(MappingError) as caught:
        load_mapping_text(text, "m.yaml")
    return [str(problem) for problem in caught.value.problems]


def test_the_profiles_have_rmws_settings():
    """rmw/qos_profiles.h: sensor_data keep-last 5 best-effort volatile; default and services keep-last 10
    reliable volatile; transient_local as tf2_ros's static broadcaster (reliable, depth 1)."""
    assert PROFILES == {
        "sensor_data": BEST_EFFORT_5,
        "default": RELIABLE_10,
        "transient_local": LATCHED,
        "services": RELIABLE_10,
    }
    assert tuple(PROFILES) == QOS_PROFILES
    assert str(BEST_EFFORT_5) == "best_effort/volatile/5"
    assert str(Qos("reliable", "volatile", 10, "keep_all")) == "reliable/volatile/all"


def test_every_catalogue_entry_names_a_profile():
    assert {info.qos for info in CONVERTERS.values()} <= set(QOS_PROFILES)


def test_the_schema_lists_the_catalogues_profiles():
    qos = schema()["$defs"]["qos"]
    assert qos["then"]["enum"] == list(QOS_PROFILES)
    assert qos["else"]["properties"]["profile"]["enum"] == list(QOS_PROFILES)


@pytest.mark.parametrize("name", QOS_PROFILES)
def test_a_rule_may_name_a_profile(name: str):
    assert rule_qos(name) == PROFILES[name]


def test_explicit_settings_start_from_the_default_profile():
    assert rule_qos("{reliability: best_effort, depth: 2}") == Qos("best_effort", "volatile", 2)
    assert rule_qos("{history: keep_all}") == Qos("reliable", "volatile", 10, "keep_all")


def test_a_profile_with_overrides_keeps_what_it_does_not_override():
    assert rule_qos("{profile: sensor_data, depth: 1}") == Qos("best_effort", "volatile", 1)
    assert rule_qos("{profile: transient_local, depth: 3}") == Qos("reliable", "transient_local", 3)


def test_the_mappings_defaults_give_every_rule_without_its_own_a_qos():
    text = pose_mapping().replace("rules:", "defaults:\n  qos: sensor_data\nrules:")
    assert load_mapping_text(text, "m.yaml").rules[0].options.qos == BEST_EFFORT_5


def test_a_misspelt_profile_is_located_at_its_value_with_a_did_you_mean():
    assert problems(pose_mapping("sensor_dta")) == [
        "m.yaml:10:10: rules[0] 'pose'.qos: \"sensor_dta\" is not allowed (did you mean 'sensor_data'?)"
    ]


def test_each_bad_setting_is_located_at_its_key_or_value():
    found = problems(pose_mapping("{profile: defualt, depth: 0, reliabilty: reliable, durability: x}"))
    assert found == [
        "m.yaml:10:20: rules[0] 'pose'.qos.profile: \"defualt\" is not allowed (did you mean 'default'?)",
        "m.yaml:10:36: rules[0] 'pose'.qos.depth: must be at least 1, got 0",
        "m.yaml:10:39: unknown key 'reliabilty' in rules[0] 'pose'.qos (did you mean 'reliability'?)",
        "m.yaml:10:73: rules[0] 'pose'.qos.durability: \"x\" is not allowed "
        "(one of: volatile, transient_local)",
    ]


@pytest.mark.parametrize(("value", "message"), [("5", "got 5"), ("[reliable]", 'got ["reliable"]')])
def test_a_qos_neither_a_name_nor_settings_is_one_problem(value: str, message: str):
    assert problems(pose_mapping(value)) == [
        f"m.yaml:10:10: rules[0] 'pose'.qos: expected string or object, {message}"
    ]


def test_an_empty_settings_mapping_is_refused():
    assert problems(pose_mapping("{}")) == ["m.yaml:10:10: rules[0] 'pose'.qos: {} should be non-empty"]


FAMILIES = {  # a converter of each family, with the QoS its bridges get on ROS 2
    "image": BEST_EFFORT_5,
    "camera_info": BEST_EFFORT_5,
    "image_compressed": BEST_EFFORT_5,
    "pointcloud": BEST_EFFORT_5,
    "radar_scan": BEST_EFFORT_5,
    "imu": BEST_EFFORT_5,
    "gps": BEST_EFFORT_5,
    "clock": BEST_EFFORT_5,
    "odometry": RELIABLE_10,
    "camera_pose": RELIABLE_10,
    "cmd_vel": RELIABLE_10,
    "desired_pose": RELIABLE_10,
    "load_scene": RELIABLE_10,
    "set_bool": RELIABLE_10,
    "trigger": RELIABLE_10,
}


@pytest.fixture(scope="module")
def default_bridges():
    _, _, bridges = load_and_expand(
        ROOT / "mappings/default.yaml", "scene_drone_sensors.jsonc", SIM_CONFIG, "n"
    )
    return bridges


@pytest.mark.parametrize(("converter", "expected"), sorted(FAMILIES.items()))
def test_each_family_gets_the_qos_a_ros2_user_expects(default_bridges, converter: str, expected: Qos):
    found = {b.qos for b in default_bridges if b.converter == converter and not b.options.latch}
    assert found == {expected}, converter


def test_a_latched_rule_without_its_own_qos_is_transient_local(default_bridges):
    latched = [b for b in default_bridges if b.options.latch]
    assert latched and {b.qos for b in latched} == {LATCHED}
    assert rule_qos("", latch=True) is None  # the rule says nothing: expansion decides
    assert rule_qos("sensor_data", latch=True) == BEST_EFFORT_5  # what a rule says wins


def test_the_nodes_own_topics_without_a_rule_are_transient_local_when_latched_else_default():
    assert node_topic_qos(latch=True) == LATCHED  # the status topic
    assert node_topic_qos(latch=False) == RELIABLE_10  # /diagnostics


def test_the_service_converters_default_to_the_services_profile():
    services = [info for info in CONVERTERS.values() if all("_srvs/" in t for t in info.ros_types)]
    assert services and {info.qos for info in services} == {"services"}


def test_a_rules_qos_reaches_its_bridges_and_their_json_rows(write_scene, capsys):
    from airsim_mapper.cli.validate import main

    root = write_scene({"Drone1": []})
    mapping = root / "m.yaml"
    mapping.write_text(pose_mapping("{profile: sensor_data, depth: 2}"))
    assert (
        main([str(mapping), "--scene", "scene.jsonc", "--simconfigpath", str(root), "--format", "json"]) == 0
    )
    (row,) = json.loads(capsys.readouterr().out)
    assert row["qos"] == {
        "reliability": "best_effort",
        "durability": "volatile",
        "depth": 2,
        "history": "keep_last",
    }


SETTINGS = st.fixed_dictionaries(
    {},
    optional={
        "profile": st.sampled_from(QOS_PROFILES),
        "reliability": st.sampled_from(["reliable", "best_effort"]),
        "durability": st.sampled_from(["volatile", "transient_local"]),
        "depth": st.integers(1, 1000),
        "history": st.sampled_from(["keep_last", "keep_all"]),
    },
).filter(bool)


@given(SETTINGS)
def test_any_valid_settings_load_as_their_profile_with_each_override_applied(settings: dict):
    loaded = rule_qos(json.dumps(settings))
    assert loaded == qos_of(settings)
    base = PROFILES[settings.get("profile", "default")]
    for key in ("reliability", "durability", "depth", "history"):
        assert getattr(loaded, key) == settings.get(key, getattr(base, key))
