"""Expansion of rules over a scene: names, variables, sources, disabled things, collisions."""

from __future__ import annotations

import pytest
from scene_builders import camera, capture

from airsim_mapper.mapping.errors import MappingError
from airsim_mapper.mapping.expand import expand
from airsim_mapper.mapping.loader import load_mapping, load_mapping_text
from airsim_mapper.mapping.scene import read_scene

HEADER = "version: 1\nrules:\n"


def rule(name: str, for_each: str, ros: str | None, **extra: str) -> str:
    """A sim_to_ros pose rule in flow style (the pose converter fits any domain for these tests)."""
    fields = {
        "name": name,
        "for_each": for_each,
        "direction": "sim_to_ros",
        "sim": "/sim/<node_name>/x",
        "type": "geometry_msgs/PoseStamped",
        "converter": "pose",
        **({"ros": ros} if ros else {}),
        **extra,
    }
    return "  - {" + ", ".join(f"{k}: {v}" for k, v in fields.items()) + "}\n"


LIDAR = {"id": "lid", "type": "lidar", "enabled": True, "parent-link": "Frame"}


@pytest.fixture
def scene(write_scene):
    root = write_scene(
        {
            "R1": [
                camera("Front", [capture(0, streaming=True), capture(1, enabled=False), capture(6)]),
                camera("Off", [capture(0)], enabled=False),
                LIDAR,
                {**LIDAR, "id": "lid_off", "enabled": False},
            ],
            "R2": [camera("Back", [capture(0, streaming=True)])],
        },
        scene_id="S",
    )
    return read_scene(root, "scene.jsonc")


def test_bridges_are_named_per_scene_element_in_rule_then_scene_order(scene):
    text = HEADER + "".join(
        rule(f"r_{d}", d, f"/{d}/<robot_name>" if d not in ("node", "scene", "streaming_camera") else f"/{d}")
        for d in ("node", "scene", "robot", "camera", "camera_capture", "lidar", "streaming_camera")
    )
    text = text.replace("/camera/<robot_name>", "/camera/<robot_name>/<camera_name>")
    text = text.replace("/camera_capture/<robot_name>", "/cc/<robot_name>/<camera_name>/<image_type>")
    names = [b.name for b in expand(load_mapping_text(text), scene, "nodeA")]
    assert names == [
        "r_node[nodeA]",
        "r_scene[S]",
        "r_robot[R1]",
        "r_robot[R2]",
        "r_camera[R1/Front]",
        "r_camera[R2/Back]",
        "r_camera_capture[R1/Front/scene_camera]",
        "r_camera_capture[R1/Front/surface_normals]",
        "r_camera_capture[R2/Back/scene_camera]",
        "r_lidar[R1/lid]",
        "r_streaming_camera[S]",
    ]


def test_camera_capture_bridges_carry_the_capture_setting_and_the_camera_mount(scene):
    mapping = load_mapping_text(
        HEADER + rule("img", "camera_capture", "/<robot_name>/<camera_name>/<image_type>")
    )
    bridge = expand(mapping, scene, "n")[1]
    assert dict(bridge.variables) == {
        "node_name": "n",
        "namespace": "",
        "frame_prefix": "",
        "scene_name": "S",
        "robot_name": "R1",
        "camera_name": "Front",
        "image_type": "surface_normals",
        "image_type_id": "6",
        "sim_image_type": "surface_normals_camera",
    }
    assert bridge.source["width"] == 320
    assert bridge.source["image-type"] == 6
    assert bridge.source["camera_origin"] == {"xyz": "0.3 0 0", "rpy-deg": "0 0 0"}


def test_robot_bridges_carry_the_actor_without_its_robot_config_and_sensors_their_config(scene):
    text = (
        HEADER
        + rule("r", "robot", "/<robot_name>")
        + rule("l", "lidar", "/<robot_name>/<lidar_name>/<sensor_name>")
    )
    robot, _, lidar = expand(load_mapping_text(text), scene, "n")
    assert dict(robot.source) == {
        "type": "robot",
        "name": "R1",
        "origin": {"xyz": "0 0 -4", "rpy-deg": "0 0 0"},
    }
    assert lidar.ros == "/R1/lid/lid"
    assert lidar.source["id"] == "lid"


def test_the_streaming_camera_domain_expands_once_and_lists_every_streaming_camera(scene):
    text = HEADER + rule("s", "streaming_camera", "/stream", frame_id="<robot_name>/<camera_name>")
    (bridge,) = expand(load_mapping_text(text), scene, "n")
    assert bridge.frame_id == "R1/Front"
    assert bridge.source["cameras"] == [
        {
            "robot_name": "R1",
            "camera_name": "Front",
            "sim": "/Sim/S/robots/R1/sensors/Front/scene_camera",
            "frame_id": "R1/Front",
        },
        {
            "robot_name": "R2",
            "camera_name": "Back",
            "sim": "/Sim/S/robots/R2/sensors/Back/scene_camera",
            "frame_id": "R2/Back",  # the frame switch_view moves the stream to
        },
    ]


def test_no_streaming_bridge_without_a_streaming_camera(write_scene):
    scene = read_scene(write_scene({"R": [camera("C", [capture(0)])]}), "scene.jsonc")
    assert expand(load_mapping_text(HEADER + rule("s", "streaming_camera", "/stream")), scene, "n") == ()


def test_disabled_rules_and_disabled_sensors_produce_nothing(scene):
    text = (
        HEADER
        + rule("a", "lidar", "/<robot_name>/<lidar_name>", enabled="false")
        + rule("b", "lidar", "/b/<lidar_name>")
    )
    assert [b.ros for b in expand(load_mapping_text(text), scene, "n")] == ["/b/lid"]


def test_the_namespace_variable_prefixes_names(scene):
    mapping = load_mapping_text(HEADER + rule("r", "robot", "<namespace>/airsim_node/<robot_name>/pose"))
    assert [b.ros for b in expand(mapping, scene, "n")] == ["/airsim_node/R1/pose", "/airsim_node/R2/pose"]
    assert [b.ros for b in expand(mapping, scene, "n", "/sim2")] == [
        "/sim2/airsim_node/R1/pose",
        "/sim2/airsim_node/R2/pose",
    ]


def test_two_rules_that_collide_only_after_expansion_are_an_error(scene):
    text = HEADER + rule("a", "robot", "/x/<robot_name>") + rule("b", "node", "/x/R2")
    with pytest.raises(MappingError) as caught:
        expand(load_mapping_text(text, "m.yaml"), scene, "n")
    assert (
        str(caught.value)
        == "m.yaml:4:134: bridge b[n]: ROS name '/x/R2' is also used by a[R2] (rule at line 3)"
    )


def test_a_scene_name_that_makes_an_illegal_ros_name_is_an_error(write_scene):
    scene = read_scene(write_scene({"Drone-1": []}), "scene.jsonc")
    mapping = load_mapping_text(HEADER + rule("r", "robot", "/airsim_node/<robot_name>/pose"), "m.yaml")
    with pytest.raises(
        MappingError,
        match=r"m\.yaml:3:135: bridge r\[Drone-1\]: ROS name '/airsim_node/Drone-1/pose' is not valid",
    ):
        expand(mapping, scene, "n")


def test_expansion_is_deterministic(scene):
    text = HEADER + rule("c", "camera_capture", "/<robot_name>/<camera_name>/<image_type>")
    mapping = load_mapping_text(text)
    assert expand(mapping, scene, "n") == expand(mapping, scene, "n")


def test_a_namespace_prefixes_every_topic_and_frame_of_the_default_mapping():
    from harness import ROOT

    from airsim_mapper.mapping.expand import expand, namespace_variables
    from airsim_mapper.mapping.loader import load_mapping
    from airsim_mapper.mapping.scene import read_scene

    assert namespace_variables("") == {"namespace": "", "frame_prefix": ""}
    assert namespace_variables("/sim2/") == {"namespace": "/sim2", "frame_prefix": "sim2/"}
    scene = read_scene(ROOT / "sim_config", "scene_two_drones.jsonc")
    bridges = expand(load_mapping(ROOT / "mappings" / "default.yaml"), scene, "n", "sim2")
    assert all(b.ros.startswith("/sim2/") for b in bridges if b.ros)
    frames = [f for b in bridges for f in (b.frame_id, *((b.tf.parent, b.tf.child) if b.tf else ())) if f]
    assert frames and all(f.startswith("sim2/") for f in frames)


def test_template_strings_in_params_are_rendered_per_element_and_other_values_are_kept():
    from harness import ROOT

    from airsim_mapper.mapping.loader import load_mapping

    scene = read_scene(ROOT / "sim_config", "scene_two_drones.jsonc")
    bridges = expand(load_mapping("default"), scene, "n", "sim2")
    odom = {b.variables["robot_name"]: b.params for b in bridges if b.converter == "odometry"}
    assert odom == {
        "Drone1": {"child_frame_id": "sim2/airsim_node/Drone1"},
        "Drone2": {"child_frame_id": "sim2/airsim_node/Drone2"},
    }
    takeoff = next(b for b in bridges if b.params.get("method") == "Takeoff")
    assert takeoff.params == {"method": "Takeoff", "args": {"timeout_sec": 20}}


def test_without_a_scene_only_the_node_rules_expand():
    from airsim_mapper.common.resources import DEFAULT_MAPPING

    mapping = load_mapping(DEFAULT_MAPPING)
    bridges = expand(mapping, None, "bridge", "sim1")
    assert [(b.name, b.ros) for b in bridges] == [
        ("load_scene[bridge]", "/sim1/ProjectAirSim/node/bridge/load_scene")
    ]
