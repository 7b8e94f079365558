"""Expand mapping rules over a scene into concrete bridges: pure, deterministic, free of ROS imports.

Without a scene (`scene=None`) only the node-domain rules expand: the bridges a node runs before any scene
is loaded (load_scene). Order: rules in file order; within a rule, scene elements in scene order (robots,
then their sensors, then capture settings). Domains:
- node: once, named `<rule>[<node_name>]`; scene: once, `<rule>[<scene_name>]`;
- robot: per robot, `<rule>[<robot>]`, source = the actor entry (name, origin, ...) without its robot-config;
- first_robot: once per scene with a robot, for the first robot, `<rule>[<scene_name>]`, source as robot;
- camera: per enabled camera, `<rule>[<robot>/<camera>]`, source = the camera's sensor config;
- camera_capture: per capture-enabled setting of an enabled camera, `<rule>[<robot>/<camera>/<image_type>]`,
  source = the capture setting plus the camera mount under "camera_origin";
- streaming_camera: once per scene when a capture-enabled image-type 0 setting has "streaming-enabled": true,
  `<rule>[<scene_name>]`; robot_name/camera_name are the first streaming camera's, and source["cameras"] lists
  every streaming camera as {"robot_name", "camera_name", "sim": its scene_camera topic path, "frame_id": the
  rule's frame_id for that camera (with a frame_id)};
- lidar, radar, imu, gps, barometer, magnetometer, distance_sensor, battery, airspeed: per enabled sensor of
  that type, `<rule>[<robot>/<sensor>]`, source = the sensor config.
"""

from __future__ import annotations

import copy
from collections.abc import Iterator, Mapping
from types import MappingProxyType
from typing import Any

from airsim_mapper.common.image_types import FLOAT_IMAGE_TYPES, SIM_IMAGE_LEAVES
from airsim_mapper.convert import catalog
from airsim_mapper.mapping import template
from airsim_mapper.mapping.errors import MappingError, Problem
from airsim_mapper.mapping.match import matches
from airsim_mapper.mapping.model import BridgeSpec, MappingDoc, Rule, TfSpec
from airsim_mapper.mapping.names import resolve_name, ros_name_problem
from airsim_mapper.mapping.origins import place_text
from airsim_mapper.mapping.qos import bridge_qos
from airsim_mapper.mapping.reserved import clock_rule_on, node_names, taken_problem
from airsim_mapper.mapping.ros2_names import ros2_name_problem
from airsim_mapper.mapping.scene import Scene

Element = tuple[str, dict[str, str], dict[str, Any]]  # (name key, variables, source)


def _robot_elements(scene: Scene, base: dict[str, str]) -> Iterator[Element]:
    for robot in scene.robots:
        yield robot.name, {**base, "robot_name": robot.name}, copy.deepcopy(dict(robot.actor))


def _sensor_elements(scene: Scene, base: dict[str, str], kind: str) -> Iterator[Element]:
    for robot in scene.robots:
        for sensor in robot.enabled_sensors(kind):
            variables = {**base, "robot_name": robot.name, "sensor_name": sensor.id}
            if kind in ("camera", "lidar", "radar"):
                variables[f"{kind}_name"] = sensor.id
                if kind == "camera":
                    del variables["sensor_name"]
            source = copy.deepcopy(dict(sensor.config))
            if kind == "camera":  # the mount, under the same key as for camera_capture elements
                source["camera_origin"] = copy.deepcopy(sensor.config.get("origin"))
            yield f"{robot.name}/{sensor.id}", variables, source


def _capture_elements(
    scene: Scene, base: dict[str, str], image_types: Mapping[int, str]
) -> Iterator[Element]:
    for robot in scene.robots:
        for camera in robot.enabled_sensors("camera"):
            for capture in camera.captures:
                if not capture.capture_enabled or capture.image_type not in SIM_IMAGE_LEAVES:
                    continue
                name = image_types.get(capture.image_type, SIM_IMAGE_LEAVES[capture.image_type])
                variables = {
                    **base,
                    "robot_name": robot.name,
                    "camera_name": camera.id,
                    "image_type": name,
                    "image_type_id": str(capture.image_type),
                    "sim_image_type": SIM_IMAGE_LEAVES[capture.image_type],
                }
                source = copy.deepcopy(dict(capture.settings))
                source["camera_origin"] = copy.deepcopy(camera.config.get("origin"))
                yield f"{robot.name}/{camera.id}/{name}", variables, source


def _streaming_elements(scene: Scene, base: dict[str, str]) -> Iterator[Element]:
    cameras = scene.streaming_cameras
    if not cameras:
        return
    leaf = SIM_IMAGE_LEAVES[0]
    listed = [
        {
            "robot_name": cam.robot_name,
            "camera_name": cam.camera_name,
            "sim": f"/Sim/{scene.name}/robots/{cam.robot_name}/sensors/{cam.camera_name}/{leaf}",
        }
        for cam in cameras
    ]
    first = cameras[0]
    yield (
        scene.name,
        {**base, "robot_name": first.robot_name, "camera_name": first.camera_name},
        {"cameras": listed},
    )


def elements(
    rule: Rule, mapping: MappingDoc, scene: Scene | None, node_name: str, namespace: str
) -> Iterator[Element]:
    """The scene elements `rule` expands over, each with its name key, variables and source (none for a
    scene-domain rule when there is no scene)."""
    base = {"node_name": node_name, **namespace_variables(namespace)}
    if rule.domain == "node":
        yield node_name, base, {}
        return
    if scene is None:
        return
    base["scene_name"] = scene.name
    if rule.domain == "scene":
        robots = [robot.name for robot in scene.robots]
        yield scene.name, base, {"scene_name": scene.name, "file": scene.file, "robots": robots}
    elif rule.domain == "robot":
        yield from _robot_elements(scene, base)
    elif rule.domain == "first_robot":
        for _, variables, source in list(_robot_elements(scene, base))[:1]:
            yield scene.name, variables, source
    elif rule.domain == "camera_capture":
        yield from _capture_elements(scene, base, mapping.image_types)
    elif rule.domain == "streaming_camera":
        yield from _streaming_elements(scene, base)
    else:
        yield from _sensor_elements(scene, base, rule.domain)


def _bridge(rule: Rule, key: str, variables: dict[str, str], source: dict[str, Any]) -> BridgeSpec:
    def fill(text: str | None) -> str | None:
        return None if text is None else template.render(text, variables)

    info = catalog.find(rule.converter)
    return BridgeSpec(
        name=f"{rule.name}[{key}]",
        rule=rule.name,
        direction=rule.direction,
        converter=rule.converter,
        sim=fill(rule.sim),
        sim_kind=info.sim_kind if info else "topic",
        ros=fill(rule.ros),
        ros_type=rule.ros_type,
        frame_id=fill(rule.frame_id),
        tf=TfSpec(fill(rule.tf.parent), fill(rule.tf.child), rule.tf.static) if rule.tf else None,
        convention=rule.convention,
        options=rule.options,
        params=MappingProxyType(template.render_all(rule.params, variables)),
        variables=MappingProxyType(dict(variables)),
        source=MappingProxyType(source),
        ros_kind=rule.ros_kind,
        qos=bridge_qos(rule.options, rule.converter),
    )


def _image_kind_problem(bridge: BridgeSpec) -> str | None:
    """Why an image-encoding converter cannot take the bridge's image type (JPEG of a depth image), if so."""
    info = catalog.find(bridge.converter)
    type_id = bridge.variables.get("image_type_id")
    if info is None or info.image_kind is None or type_id is None:
        return None
    is_float = int(type_id) in FLOAT_IMAGE_TYPES
    if is_float == (info.image_kind == catalog.FLOAT):
        return None
    kind = "a float depth image" if is_float else "an 8-bit colour image"
    other = [c.name for c in catalog.CONVERTERS.values() if c.image_kind not in (None, info.image_kind)]
    return (
        f"bridge {bridge.name}: converter '{info.name}' cannot encode image type {type_id} "
        f"({bridge.variables.get('image_type')}, {kind}): use {' or '.join(other)}, or a match on "
        "image_type_id that leaves it out"
    )


def namespace_variables(namespace: str) -> dict[str, str]:
    """<namespace> ("" or "/ns", a topic prefix) and <frame_prefix> ("" or "ns/") of a node's --namespace."""
    ns = namespace.strip("/")
    return {"namespace": f"/{ns}" if ns else "", "frame_prefix": f"{ns}/" if ns else ""}


def expand(
    mapping: MappingDoc,
    scene: Scene | None,
    node_name: str,
    namespace: str = "",
    node_namespace: str = "",
    ros_node: str = "",
    ros: int = 1,
) -> tuple[BridgeSpec, ...]:
    """All concrete bridges of `mapping` over `scene` (only the node's own without one); MappingError when
    names are illegal or collide. Names are compared as ROS resolves them for the node `ros_node` (the last
    part of its ROS name; `node_name`, the mapping's <node_name>, when not given) in its ROS namespace
    `node_namespace` ("" for the root): `x` and `/x` are one topic there, `~x` the node's. With `ros` 2,
    a name must also be one that ROS 2 takes."""
    bridges: list[BridgeSpec] = []
    problems: list[Problem] = []
    owners: dict[str, BridgeSpec] = {}
    places = {rule.name: (rule.file or mapping.source, rule.line) for rule in mapping.rules}
    on = clock_rule_on(rule.converter for rule in mapping.rules if rule.options.enabled)
    ros_node = ros_node or node_name
    owned = node_names(
        ros_node, namespace_variables(namespace)["namespace"], clock_rule=on, node_namespace=node_namespace
    )
    for rule in mapping.rules:
        if not rule.options.enabled:
            continue
        for key, variables, source in elements(rule, mapping, scene, node_name, namespace):
            if rule.match and not matches(rule.match, variables):
                continue
            if rule.domain == "streaming_camera" and rule.frame_id is not None:
                for camera in source["cameras"]:  # the frame follows the active camera (switch_view)
                    names = {k: camera[k] for k in ("robot_name", "camera_name")}
                    camera["frame_id"] = template.render(rule.frame_id, {**variables, **names})
            bridge = _bridge(rule, key, variables, source)
            unfit = _image_kind_problem(bridge)
            if unfit:
                problems.append(Problem(rule.file or mapping.source, rule.line, 1, unfit))
            if bridge.ros is not None:
                at = rule.ros_place or (rule.file or mapping.source, rule.line, 1)  # its `ros`, or the rule
                why = ros_name_problem(bridge.ros)
                if not why and ros == 2:
                    why = ros2_name_problem(bridge.ros, ros_node, node_namespace)
                    why = why and f"ROS 2 refuses it: {why}"
                full = resolve_name(bridge.ros, ros_node, node_namespace) if not why else bridge.ros
                taken = taken_problem(full, bridge.converter, owned)
                if why:
                    message = f"bridge {bridge.name}: ROS name '{bridge.ros}' is not valid: {why}"
                    problems.append(Problem(*at, message))
                elif taken:
                    problems.append(Problem(*at, f"bridge {bridge.name}: {taken}"))
                elif full in owners:
                    other = owners[full]
                    file, line = places[other.rule]
                    where = place_text(file, line, rule.file or mapping.source)
                    written = f"'{bridge.ros}'" + (f" (that is, '{full}')" if full != bridge.ros else "")
                    message = (
                        f"bridge {bridge.name}: ROS name {written} is also used by "
                        f"{other.name} (rule at {where})"
                    )
                    problems.append(Problem(*at, message))
                else:
                    owners[full] = bridge
            bridges.append(bridge)
    if problems:
        raise MappingError(problems)
    return tuple(bridges)


def selected(
    mapping: MappingDoc, scene: Scene, node_name: str, namespace: str = ""
) -> dict[str, tuple[int, int]]:
    """For each enabled rule with a `match`: (elements it matches, elements of its domain) in `scene`."""
    counts = {}
    for rule in mapping.rules:
        if rule.match and rule.options.enabled:
            found = [variables for _, variables, _ in elements(rule, mapping, scene, node_name, namespace)]
            counts[rule.name] = (sum(matches(rule.match, v) for v in found), len(found))
    return counts
