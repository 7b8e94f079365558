"""Plain immutable values of the mapping language: options, rules, and the expanded bridges.

`MappingDoc` is what the loader returns for a YAML file; `BridgeSpec` is one concrete bridge that expansion
produces from a rule and a scene. Nothing here imports ROS or the simulator client.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any

SIM_TO_ROS = "sim_to_ros"
ROS_TO_SIM = "ros_to_sim"

# Domains a rule can expand over, and the template variables each provides.
DOMAIN_VARIABLES: dict[str, tuple[str, ...]] = {
    "node": ("node_name", "namespace"),
    "scene": ("node_name", "namespace", "scene_name"),
    "robot": ("node_name", "namespace", "scene_name", "robot_name"),
    # once per scene, for its first robot (scene order): one stream per scene, e.g. /clock
    "first_robot": ("node_name", "namespace", "scene_name", "robot_name"),
    "camera": ("node_name", "namespace", "scene_name", "robot_name", "camera_name"),
    "camera_capture": (
        "node_name",
        "namespace",
        "scene_name",
        "robot_name",
        "camera_name",
        "image_type",
        "image_type_id",
        "sim_image_type",
    ),
    "streaming_camera": ("node_name", "namespace", "scene_name", "robot_name", "camera_name"),
    "lidar": ("node_name", "namespace", "scene_name", "robot_name", "lidar_name", "sensor_name"),
    "radar": ("node_name", "namespace", "scene_name", "robot_name", "radar_name", "sensor_name"),
    # one domain per other sensor type: imu, gps, barometer, magnetometer, distance_sensor, battery, airspeed
    **{
        kind: ("node_name", "namespace", "scene_name", "robot_name", "sensor_name")
        for kind in ("imu", "gps", "barometer", "magnetometer", "distance_sensor", "battery", "airspeed")
    },
}
# Every domain also has <frame_prefix>: the frame-id form of <namespace> ("" or "sim2/" for "/sim2").
DOMAIN_VARIABLES = {
    domain: (names[0], names[1], "frame_prefix", *names[2:]) for domain, names in DOMAIN_VARIABLES.items()
}


@dataclass(frozen=True)
class PositionBox:
    """An axis-aligned box (metres, in the rule's convention) that commanded positions must lie in."""

    min: tuple[float, float, float]
    max: tuple[float, float, float]


@dataclass(frozen=True)
class Limits:
    """Bounds applied to incoming commands (absent = unbounded)."""

    max_linear_speed: float | None = None  # m/s, norm of the linear velocity
    max_vertical_speed: float | None = None  # m/s, |z|
    max_yaw_rate: float | None = None  # rad/s
    position_box: PositionBox | None = None  # desired_pose, camera_desired_pose
    on_violation: str = "clamp"  # "clamp" or "reject"


@dataclass(frozen=True)
class Qos:
    """A concrete ROS 2 quality of service: what a ROS 2 publisher, subscriber or service is made with."""

    reliability: str  # "reliable" or "best_effort"
    durability: str  # "volatile" or "transient_local"
    depth: int  # history depth (keep_last)
    history: str = "keep_last"  # or "keep_all"

    def __str__(self) -> str:
        depth = "all" if self.history == "keep_all" else str(self.depth)
        return f"{self.reliability}/{self.durability}/{depth}"


@dataclass(frozen=True)
class Options:
    """Per-rule options; the mapping's `defaults` fill whatever a rule leaves out."""

    queue_size: int = 1
    latch: bool = False
    lazy: bool = True
    rate_limit_hz: float | None = None
    stamp: str = "sim"  # "sim" (simulator time stamp) or "ros" (rospy.Time.now())
    first_message: str = "fresh"  # lazy: "fresh" drops the simulator's cached frame; "cached" keeps it
    enabled: bool = True
    watchdog_s: float | None = None  # ros_to_sim: act when no message arrives for this long
    limits: Limits = field(default_factory=Limits)
    qos: Qos | None = None  # ROS 2 only; None: the converter's default profile (latched: transient_local)


@dataclass(frozen=True)
class TfSpec:
    parent: str  # template
    child: str  # template
    static: bool = False  # a mount on the robot: sent on /tf_static relative to the robot's frame


@dataclass(frozen=True)
class Rule:
    name: str
    domain: str  # a key of DOMAIN_VARIABLES
    direction: str  # SIM_TO_ROS or ROS_TO_SIM
    sim: str | None  # sim topic path or service method template
    ros: str | None  # ROS topic or service name template (None: tf only)
    ros_type: str | None
    converter: str
    frame_id: str | None
    tf: TfSpec | None
    convention: str  # "ned" or "enu"
    options: Options
    params: Mapping[str, Any]  # free-form converter parameters (e.g. body_frame, method params)
    line: int = 0  # 1-based line of the rule in its file, for messages
    ros_kind: str = "topic"  # "topic" or "service" (the ROS type lives in <pkg>.srv)
    # selections, any of which keeps an element; each maps a variable to glob patterns ("!" = none of);
    # empty: every element (see mapping.match)
    match: tuple[Mapping[str, tuple[str, ...]], ...] = ()
    file: str = ""  # the file the rule (or its override) is written in, when not the mapping's own
    ros_place: tuple[str, int, int] | None = None  # file, line and column of its `ros` value, when known


@dataclass(frozen=True)
class MappingDoc:
    version: int
    image_types: Mapping[int, str]  # image-type id -> <image_type> name
    defaults: Options
    rules: tuple[Rule, ...]
    source: str = "<string>"  # file the mapping came from
    files: tuple[str, ...] = ()  # source and, with extends, every base it builds on (what a node watches)


@dataclass(frozen=True)
class BridgeSpec:
    """One concrete bridge: a rule expanded for one element of the scene."""

    name: str  # unique and stable, e.g. "camera_image[Drone1/DownCamera/scene_camera]"
    rule: str
    direction: str
    converter: str
    sim: str | None  # concrete sim topic path or service method
    sim_kind: str  # "topic", "service" or "node" (from the converter catalogue)
    ros: str | None  # concrete ROS topic or service name
    ros_type: str | None
    frame_id: str | None
    tf: TfSpec | None  # concrete parent/child frame ids
    convention: str
    options: Options
    params: Mapping[str, Any]
    variables: Mapping[str, str]  # the template variables this bridge was expanded with
    source: Mapping[str, Any]  # the scene element it came from (capture setting, sensor config, ...)
    qos: Qos  # what a ROS 2 link makes it with (mapping/qos.py's bridge_qos; ROS1 ignores it)
    ros_kind: str = "topic"  # "topic" or "service" (the ROS type lives in <pkg>.srv)
