"""ROS 2's name rules: the examples rcl's and rmw's own tests pass and refuse, the expansion of private
names and substitutions, and the names ROS1 takes that ROS 2 refuses."""

from __future__ import annotations

import pytest
from harness import ROOT, SIM_CONFIG
from hypothesis import given
from hypothesis import strategies as st

from airsim_mapper.mapping.errors import MappingError
from airsim_mapper.mapping.loader import load_mapping_text
from airsim_mapper.mapping.names import ros_name_problem
from airsim_mapper.mapping.pipeline import load_and_expand
from airsim_mapper.mapping.ros2_names import (
    NAMESPACE_MAX_LENGTH,
    NODE_NAME_MAX_LENGTH,
    TOPIC_MAX_LENGTH,
    expand_name,
    full_topic_problem,
    namespace_problem,
    node_name_problem,
    ros2_name_problem,
    rule_problems,
    topic_problem,
)

# rcl's test_validate_topic_name.cpp: the names it passes (the design article's examples) ...
RCL_VALID = [
    "foo",
    "abc123",
    "_foo",
    "Foo",
    "BAR",
    "~",
    "foo/bar",
    "~/foo",
    "{foo}_bar",
    "foo/{ping}/bar",
    "foo/_bar",
    "foo_/bar",
    "foo_",
    "/foo",
    "/bar/baz",
    "/_private/thing",
    "/public_namespace/_private/thing",
    "{foo1}",
    "{foo_bar}",
    "{_bar}",
]
# ... and those it refuses, with the index of the character it names
RCL_INVALID = [
    ("123abc", 0, "starts with a digit"),
    ("123", 0, "starts with a digit"),
    (" ", 0, "not allowed"),
    ("foo bar", 3, "not allowed"),
    ("/~", 1, "'~' is allowed only"),
    ("~foo", 1, "'~' must be followed by '/'"),
    ("foo~", 3, "'~' is allowed only"),
    ("foo~/bar", 3, "'~' is allowed only"),
    ("foo/~bar", 4, "'~' is allowed only"),
    ("foo/~/bar", 4, "'~' is allowed only"),
    ("foo/", 3, "ends with '/'"),
    ("foo/123bar", 4, "starts with a digit"),
    ("foo/bar}/baz", 7, "without its '{'"),
    ("foo/{bar", 4, "without its '}'"),
    ("{$}", 1, "not allowed"),
    ("{{bar}_baz}", 1, "'{' inside"),
    ("foo/{bar/baz}", 8, "contains '/'"),
    ("{1foo}", 1, "starts with a digit"),
]
# rmw's test_validate_full_topic_name.cpp
RMW_VALID = ["/basename_only", "/with_one/namespace"]
RMW_INVALID = [
    ("not_absolute", "must start with '/'"),
    ("not/absolute", "must start with '/'"),
    ("/ends/with/", "ends with '/'"),
    ("/", "ends with '/'"),
    ("/~/unexpanded_tilde", "'~' is not allowed"),
    ("/unexpanded_sub/{node}", "'{' is not allowed"),
    ("/question?", "'?' is not allowed"),
    ("/with spaces", "' ' is not allowed"),
    ("/repeated//slashes", "contains '//'"),
    ("/9starts_with_number", "starts with a digit"),
    ("/starts/42with/number", "starts with a digit"),
]


@pytest.mark.parametrize("name", RCL_VALID)
def test_rcl_takes_what_its_tests_pass(name: str):
    assert topic_problem(name) is None


@pytest.mark.parametrize(("name", "index", "why"), RCL_INVALID)
def test_rcl_refuses_what_its_tests_refuse_at_the_same_character(name: str, index: int, why: str):
    found = topic_problem(name)
    assert found is not None and why in found
    assert f"at character {index + 1} of " in found


def test_an_empty_name_is_refused():
    assert topic_problem("") == full_topic_problem("") == node_name_problem("") == "it is empty"


@pytest.mark.parametrize("name", RMW_VALID)
def test_rmw_takes_a_full_name_its_tests_pass(name: str):
    assert full_topic_problem(name) is None


@pytest.mark.parametrize(("name", "why"), RMW_INVALID)
def test_rmw_refuses_a_full_name_its_tests_refuse(name: str, why: str):
    found = full_topic_problem(name)
    assert found is not None and why in found


def test_a_full_name_may_have_rmws_length_and_not_one_more():
    """rmw: 255 less 8 kept for the middleware's prefixes; a namespace two less."""
    name = "/" + "a" * (TOPIC_MAX_LENGTH - 1)
    assert TOPIC_MAX_LENGTH == 247 and full_topic_problem(name) is None
    assert "more than ROS 2's 247" in full_topic_problem(name + "a")
    namespace = "/" + "a" * (NAMESPACE_MAX_LENGTH - 1)
    assert namespace_problem(namespace) is None
    assert "more than ROS 2's 245" in namespace_problem(namespace + "a")


@pytest.mark.parametrize(
    ("name", "why"),
    [
        ("my_node", None),
        ("_node", None),
        ("node9", None),
        ("9node", "starts with a digit"),
        ("my-node", "'-' is not allowed"),
        ("ns/node", "'/' is not allowed"),
        ("a" * NODE_NAME_MAX_LENGTH, None),
        ("a" * (NODE_NAME_MAX_LENGTH + 1), "more than ROS 2's 255"),
    ],
)
def test_node_names(name: str, why: str | None):
    found = node_name_problem(name)
    assert found is None if why is None else why in found


@pytest.mark.parametrize(
    ("namespace", "why"),
    [("/", None), ("/sim1", None), ("/a/b", None), ("sim1", "must start with '/'"), ("/a/", "ends with '/'")],
)
def test_namespaces(namespace: str, why: str | None):
    found = namespace_problem(namespace)
    assert found is None if why is None else why in found


@pytest.mark.parametrize(
    ("name", "namespace", "full"),
    [
        ("foo", "", "/foo"),
        ("foo", "/ns", "/ns/foo"),
        ("/foo", "/ns", "/foo"),
        ("~", "/ns", "/ns/node"),
        ("~/foo", "", "/node/foo"),
        ("~/foo", "/ns", "/ns/node/foo"),
        ("{node}/foo", "/ns", "/ns/node/foo"),
        ("/{ns}/foo", "", "///foo"),
        ("{namespace}/foo", "/ns", "/ns/foo"),
    ],
)
def test_names_expand_as_rcl_expands_them(name: str, namespace: str, full: str):
    assert expand_name(name, "node", namespace) == full


def test_a_name_is_refused_when_its_expansion_is():
    assert ros2_name_problem("/{ns}/foo", "node") == (
        "its full name '///foo' is refused: it contains '//' (at character 2 of '///foo')"
    )
    assert ros2_name_problem("~/foo", "node", "/sim1") is None


def test_a_substitution_rcl_does_not_know_is_refused():
    assert ros2_name_problem("/{robot}/pose", "node") == (
        "{robot} is not a substitution ROS 2 knows (node, ns, namespace)"
    )
    assert topic_problem("/{robot}/pose") is None  # as written, any word in braces is well formed


@pytest.mark.parametrize("name", ["/cam/0image", "~foo", "/a/b/9", "x/" + "a" * TOPIC_MAX_LENGTH])
def test_ros1_takes_names_that_ros2_refuses(name: str):
    assert ros_name_problem(name) is None
    assert ros2_name_problem(name, "node") is not None


TOKEN = st.from_regex(r"[A-Za-z_][A-Za-z0-9_]{0,8}", fullmatch=True)


@given(st.lists(TOKEN, min_size=1, max_size=6), st.booleans())
def test_any_name_of_word_tokens_is_taken_as_written_and_expanded(tokens: list[str], absolute: bool):
    name = ("/" if absolute else "") + "/".join(tokens)
    assert topic_problem(name) is None
    assert ros2_name_problem(name, "node", "/ns") is None


@given(st.lists(TOKEN, min_size=1, max_size=4), st.integers(0, 3), st.sampled_from("0123456789"))
def test_a_token_starting_with_a_digit_is_refused_wherever_it_is(tokens: list[str], at: int, digit: str):
    at = min(at, len(tokens) - 1)
    tokens[at] = digit + tokens[at]
    assert "starts with a digit" in topic_problem("/" + "/".join(tokens))


def rule_text(ros: str) -> str:
    return (
        "version: 1\nrules:\n  - name: pose\n    for_each: robot\n    direction: sim_to_ros\n"
        "    converter: pose\n    sim: /Sim/<scene_name>/robots/<robot_name>/actual_pose\n"
        f"    ros: {ros}\n    type: geometry_msgs/PoseStamped\n"
    )


def test_a_rules_name_ros2_refuses_is_located_at_its_ros_value():
    mapping = load_mapping_text(rule_text("/x/<robot_name>/0pose"), "m.yaml")  # ROS1 takes it
    (problem,) = rule_problems(mapping)
    assert (problem.file, problem.line, problem.column) == ("m.yaml", 8, 10)
    assert problem.message.startswith("rule 'pose': ros '/x/<robot_name>/0pose' is refused by ROS 2: ")


def test_the_shipped_mappings_keep_to_ros2s_rules():
    for name in ("default.yaml", "enu.yaml"):
        _, _, bridges = load_and_expand(
            ROOT / "mappings" / name, "scene_drone_sensors.jsonc", SIM_CONFIG, "airsim_node", ros=2
        )
        assert bridges


def test_expansion_for_ros2_refuses_a_name_that_a_scene_makes_illegal(write_scene, tmp_path):
    root = write_scene({"9Drone": []})
    (tmp_path / "m.yaml").write_text(rule_text("/x/<robot_name>/pose"))
    load_and_expand(tmp_path / "m.yaml", "scene.jsonc", root, "n")  # ROS1 takes /x/9Drone/pose
    with pytest.raises(MappingError) as caught:
        load_and_expand(tmp_path / "m.yaml", "scene.jsonc", root, "n", ros=2)
    (problem,) = caught.value.problems
    assert (problem.line, problem.column) == (8, 10)
    assert "bridge pose[9Drone]: ROS name '/x/9Drone/pose' is not valid: ROS 2 refuses it: " in str(problem)
