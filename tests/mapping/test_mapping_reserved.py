"""The names the node owns (/diagnostics, /rosout, /tf, /tf_static, /clock while the clock rule is on, its
private services and status topic) are refused as located errors, as is one name for two rules."""

from __future__ import annotations

import pytest
from harness import SIM_CONFIG
from scene_builders import pose_rule

from airsim_mapper.cli.validate import main
from airsim_mapper.common.resources import DEFAULT_MAPPING
from airsim_mapper.mapping.errors import MappingError
from airsim_mapper.mapping.expand import expand
from airsim_mapper.mapping.loader import load_mapping, load_mapping_text
from airsim_mapper.mapping.reserved import GLOBAL
from airsim_mapper.mapping.scene import read_scene

EXTENDING = "version: 1\nextends: default\n"


@pytest.fixture(scope="module")
def scene():
    return read_scene(SIM_CONFIG, "scene_basic_drone.jsonc")


@pytest.mark.parametrize("name", sorted(GLOBAL))
def test_a_rule_on_a_name_the_node_owns_is_a_located_error_at_its_ros_key(tmp_path, capsys, name):
    mapping = tmp_path / "mine.yaml"
    mapping.write_text(EXTENDING + "rules:\n" + pose_rule("mine", name))
    assert main([str(mapping)]) == 1
    (line,) = capsys.readouterr().err.splitlines()
    assert line.startswith(f"{mapping}:9:10: rule 'mine': ROS name '{name}' belongs to ")
    assert line.endswith("a rule cannot take it")


@pytest.mark.parametrize("service", ["reload_mapping", "get_loggers", "set_logger_level"])
@pytest.mark.parametrize("namespace", ["", "/sim2"])
def test_a_rule_on_the_nodes_private_services_is_refused_at_expansion(scene, service, namespace):
    text = "version: 1\nrules:\n" + pose_rule("mine", f"<namespace>/<node_name>/{service}")
    mapping = load_mapping_text(text, "mine.yaml")
    with pytest.raises(MappingError) as raised:
        expand(mapping, scene, "bridge", namespace)
    (problem,) = raised.value.problems
    assert (problem.file, problem.line, problem.column) == ("mine.yaml", 8, 10)  # at its ros value
    assert (
        f"'{namespace}/bridge/{service}' belongs to the node's private service ~{service}" in problem.message
    )


def test_the_status_topic_is_the_nodes_own(scene):
    mapping = load_mapping_text(
        "version: 1\nrules:\n" + pose_rule("mine", "/airsim_mapper/<node_name>/status")
    )
    with pytest.raises(MappingError, match="belongs to the node's status topic"):
        expand(mapping, scene, "bridge")
    # a node in a namespace has its full name in its status topic
    grouped = load_mapping_text(
        "version: 1\nrules:\n" + pose_rule("mine", "/airsim_mapper/sim1/bridge/status")
    )
    with pytest.raises(MappingError, match="belongs to the node's status topic"):
        expand(grouped, scene, "bridge", "/sim1")
    assert expand(grouped, scene, "bridge")  # free for a node in the root namespace


def test_clock_is_the_clock_rules_while_it_is_on_and_free_without_it(scene):
    taken = load_mapping_text(EXTENDING + "rules:\n" + pose_rule("mine", "/clock"), "mine.yaml")
    with pytest.raises(MappingError, match=r"'/clock' belongs to the clock rule's /clock"):
        expand(taken, scene, "projectairsim", "/sim2")  # the clock rule publishes /sim2/clock
    free = load_mapping_text(
        EXTENDING + "remove: [clock]\nrules:\n" + pose_rule("mine", "/clock"), "mine.yaml"
    )
    assert any(b.ros == "/clock" for b in expand(free, scene, "projectairsim", "/sim2"))


def test_two_rules_with_one_name_and_different_types_are_a_located_error(tmp_path, capsys):
    mapping = tmp_path / "mine.yaml"
    twist = pose_rule("mine", "<namespace>/airsim_node/<robot_name>/actual_pose", "geometry_msgs/Twist")
    twist = twist.replace("converter: pose", "converter: cmd_vel").replace("sim_to_ros", "ros_to_sim")
    mapping.write_text(
        EXTENDING + "rules:\n" + twist.replace("actual_pose\n", "MoveByVelocityBodyFrame\n", 1)
    )
    assert main([str(mapping), "--scene", "scene_basic_drone.jsonc", "--simconfigpath", str(SIM_CONFIG)]) == 1
    (line,) = capsys.readouterr().err.splitlines()
    assert line.startswith(
        f"{mapping}:9:10: rule 'mine': ROS name '<namespace>/airsim_node/<robot_name>/actual_pose'"
    )
    assert line.endswith(f"is also used by rule 'actual_pose' ({DEFAULT_MAPPING}:40)")


def test_the_shipped_mappings_take_no_name_the_node_owns(scene):
    for name in ("default", "enu"):
        for namespace in ("", "/sim2"):
            assert expand(load_mapping(name), scene, "projectairsim", namespace)


@pytest.mark.parametrize("node_namespace", ["", "/fleet"])
def test_a_relative_name_collides_with_the_absolute_one_it_resolves_to(scene, node_namespace):
    """`x` is `/x` for a node at the root and `/fleet/x` for one in /fleet: the same topic as the absolute
    name another rule gives it (its spelling with the literal name is refused when the mapping loads)."""
    relative = pose_rule("mine", "airsim_node/<robot_name>/actual_pose")
    mapping = load_mapping_text(EXTENDING + "rules:\n" + relative, "mine.yaml")
    with pytest.raises(MappingError) as raised:
        expand(mapping, scene, "bridge", node_namespace, node_namespace)
    (problem,) = raised.value.problems
    assert (problem.file, problem.line, problem.column) == ("mine.yaml", 9, 10)  # at its ros value
    assert problem.message.startswith(
        f"bridge mine[Drone1]: ROS name 'airsim_node/Drone1/actual_pose' (that is, "
        f"'{node_namespace}/airsim_node/Drone1/actual_pose') is also used by actual_pose[Drone1] "
    )
    assert problem.message.endswith("default.yaml:40)")  # the other rule is in the base file
    # in another namespace it is another topic
    assert expand(mapping, scene, "bridge", node_namespace, "/elsewhere")


@pytest.mark.parametrize("node_namespace", ["", "/fleet"])
def test_a_private_name_on_the_nodes_own_service_is_refused(scene, node_namespace):
    mapping = load_mapping_text("version: 1\nrules:\n" + pose_rule("mine", "~reload_mapping"), "mine.yaml")
    with pytest.raises(MappingError) as raised:
        expand(mapping, scene, "bridge", "", node_namespace)
    (problem,) = raised.value.problems
    owned = f"'{node_namespace}/bridge/reload_mapping' belongs to the node's private service ~reload_mapping"
    assert owned in problem.message
    assert expand(load_mapping_text("version: 1\nrules:\n" + pose_rule("mine", "~pose")), scene, "bridge")


def test_private_names_resolve_with_the_ros_nodes_own_name_where_the_mappings_node_name_differs(scene):
    """A wrapper given node_name="bridge" in the ROS node /fleet/mission: `~x` is /fleet/mission/x, and
    rospy's own ~get_loggers is /fleet/mission/get_loggers, whatever <node_name> says."""
    from fakes import EngineRig

    private = pose_rule("mine", "~<robot_name>/pose")
    absolute = pose_rule("other", "/fleet/mission/<robot_name>/pose")
    both = load_mapping_text("version: 1\nrules:\n" + private + absolute, "mine.yaml")
    with pytest.raises(MappingError, match="'/fleet/mission/Drone1/pose' is also used by mine"):
        expand(both, scene, "bridge", "", "/fleet", "mission")
    assert expand(both, scene, "bridge", "", "/fleet")  # as the node "bridge": /fleet/bridge/Drone1/pose
    rospys = load_mapping_text("version: 1\nrules:\n" + pose_rule("mine", "/fleet/mission/get_loggers"))
    with pytest.raises(MappingError, match="belongs to the node's private service ~get_loggers"):
        expand(rospys, scene, "bridge", "", "/fleet", "mission")
    rig = EngineRig(mapping=both, ros_name="/fleet/mission")  # the engine resolves as its ROS node
    try:
        assert rig.engine.node_name == "node"
        with pytest.raises(MappingError, match="is also used"):
            rig.engine.specs_for(scene)
    finally:
        rig.engine.shutdown(timeout=2.0)
