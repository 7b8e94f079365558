"""The topics the real server registers for a loaded scene (protocol.md §4).

Per robot `actual_pose`, `desired_pose`, `collision_info`, `rotor_info`; per enabled sensor its leaves; per
capture-enabled camera setting the image topic and its `_info` topic, except type 5 whose info topic has the
image topic's own name (a real-server quirk: one row, message type `image`; its CameraInfo is not published,
so the topic carries only images).
"""

from __future__ import annotations

from airsim_mapper.simserver.scene.config import IMAGE_TYPE_NAMES, SENSOR_LEAVES, SceneSpec, SensorSpec
from airsim_mapper.simserver.wire.topics import PUBLISHED, SUBSCRIBED, TopicInfo

DISPARITY_NORMALIZED = 5


def camera_topics(prefix: str, sensor: SensorSpec) -> list[TopicInfo]:
    rows = []
    for capture in sensor.enabled_captures():
        name = IMAGE_TYPE_NAMES[capture.image_type]
        rows.append(TopicInfo(f"{prefix}/{name}", PUBLISHED, "image", 60))
        if capture.image_type != DISPARITY_NORMALIZED:
            rows.append(TopicInfo(f"{prefix}/{name}_info", PUBLISHED, "camera-info", 60))
    return rows


def info_topic_path(prefix: str, image_type: int) -> str:
    """The path of a camera's info topic (type 5: the image topic's own, the real quirk)."""
    name = IMAGE_TYPE_NAMES[image_type]
    return f"{prefix}/{name}" if image_type == DISPARITY_NORMALIZED else f"{prefix}/{name}_info"


def sensor_topics(prefix: str, sensor: SensorSpec) -> list[TopicInfo]:
    if sensor.type == "camera":
        return camera_topics(prefix, sensor)
    if sensor.type == "radar":
        return [
            TopicInfo(f"{prefix}/radar_detections", PUBLISHED, "", 60),
            TopicInfo(f"{prefix}/radar_tracks", PUBLISHED, "", 60),
        ]
    leaf, message_type, frequency = SENSOR_LEAVES[sensor.type]
    return [TopicInfo(f"{prefix}/{leaf}", PUBLISHED, message_type, frequency)]


def topic_table(scene: SceneSpec) -> list[TopicInfo]:
    """Every topic the scene registers, `/$topics` included, in path order."""
    rows = [TopicInfo("/$topics", PUBLISHED, "topic-list", 0)]
    for robot in scene.robots:
        base = scene.robot_prefix(robot.name)
        rows += [
            TopicInfo(f"{base}/actual_pose", PUBLISHED, "", 0),
            TopicInfo(f"{base}/desired_pose", SUBSCRIBED, "", 0),
            TopicInfo(f"{base}/collision_info", PUBLISHED, "collision-info", 0),
            TopicInfo(f"{base}/rotor_info", PUBLISHED, "", 0),
        ]
        for sensor in robot.sensors:
            rows += sensor_topics(scene.sensor_prefix(robot.name, sensor.id), sensor)
    for actor in scene.env_actors:
        rows.append(TopicInfo(f"{scene.prefix}/env_actors/{actor.name}/actual_kinematics", PUBLISHED, "", 0))
    return sorted(rows, key=lambda row: row.path)
