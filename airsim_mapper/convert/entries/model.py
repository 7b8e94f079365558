"""What a catalogue entry says about a converter: its direction, ROS types, runner and example message.

Pure data, importable without ROS (the mapping's validation reads it).
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping
from dataclasses import dataclass, field
from typing import Any

SIM_TO_ROS = "sim_to_ros"
ROS_TO_SIM = "ros_to_sim"

# How the engine runs a converter's bridges (engine/bridges.py has one runner for each).
PUBLISH = "publish"  # a simulator topic -> the converter -> a ROS topic and/or tf
STREAM = "stream"  # the active streaming camera's image -> a ROS topic (the camera follows switch_view)
SEND = "send"  # a ROS topic -> the converter -> a simulator topic
CALL = "call"  # a ROS topic -> the converter -> a simulator service call (with the command watchdog)
SERVE = "serve"  # a ROS service -> the converter -> a simulator service call; answered from its result
SERVE_ALL = "serve_all"  # a ROS service -> the rule's robot method on every robot of the scene
ACTION = "action"  # a ROS topic -> the converter -> an engine action (the entry's `action`)
RUNNERS = (PUBLISH, STREAM, SEND, CALL, SERVE, SERVE_ALL, ACTION)
SIM_KINDS = {PUBLISH: "topic", SEND: "topic", CALL: "service", SERVE: "service", SERVE_ALL: "service"}
# What runs after a successful simulator call (engine/bridges.py AFTER_HOOKS), and the engine's actions.
AFTER_HOOKS = ("remember_camera_pose", "next_streaming_camera")
ACTIONS = ("load_scene",)
# What an image-encoding converter takes (`image_kind`): 8-bit colour/mono images, or float depth images
# (image_types.FLOAT_IMAGE_TYPES); the expansion refuses a bridge of it on the other kind.
COLOUR, FLOAT = "colour", "float"

# The ROS 2 QoS profiles a rule's `qos` may name (their settings: mapping/qos.py); each entry's `qos` is
# the one its bridges get unless the rule says otherwise
SENSOR_DATA = "sensor_data"  # best-effort, volatile, small depth: streams where the newest sample matters
DEFAULT_QOS = "default"  # reliable, volatile: state (poses, odometry) and commands
TRANSIENT_LOCAL = "transient_local"  # reliable, transient-local, depth 1: latched topics
SERVICES = "services"  # ROS services
QOS_PROFILES = (SENSOR_DATA, DEFAULT_QOS, TRANSIENT_LOCAL, SERVICES)

# Pieces of the example messages that several families share.
STAMP = {"time_stamp": 1}
POSE = {"position": {"x": 1.0, "y": 2.0, "z": 3.0}, "orientation": {"w": 1.0, "x": 0.0, "y": 0.0, "z": 0.0}}


@dataclass(frozen=True)
class Example:
    """A message the converter turns into a result, and the rule parameters and scene element it needs."""

    message: Mapping[str, Any]  # sim -> ROS: the simulator message; ROS -> sim: the ROS message's fields
    params: Mapping[str, Any] = field(default_factory=dict)  # the rule's params
    source: Mapping[str, Any] = field(default_factory=dict)  # the scene element (robot actor, sensor, ...)


@dataclass(frozen=True)
class ConverterInfo:
    name: str
    direction: str  # SIM_TO_ROS or ROS_TO_SIM
    ros_types: tuple[str, ...]  # ROS message (or service) types it produces / consumes
    runner: str  # one of RUNNERS
    module: str  # module in airsim_mapper.convert holding the function
    function: str
    summary: str
    after: str | None = None  # one of AFTER_HOOKS
    action: str | None = None  # one of ACTIONS (runner ACTION)
    example: Example | None = None  # what the property tests start from (every entry has one)
    max_pixels: bool = False  # takes the rule's params.max_pixels and params.max_bytes (images)
    inline: bool = False  # light: a few fields in, one small message out; run on the receive thread
    events: bool = False  # the simulator sends one only when something happens: silence is no fault
    # params it cannot run without, with what each is
    required_params: Mapping[str, str] = field(default_factory=dict)
    # params with a fixed set of values: each value with the simulator method it goes with ("" for any)
    param_choices: Mapping[str, Mapping[str, str]] = field(default_factory=dict)
    # the only images it can encode: COLOUR (8-bit) or FLOAT (depth) image types; None: any
    image_kind: str | None = None
    qos: str = DEFAULT_QOS  # the QoS profile its bridges get on ROS 2 (one of QOS_PROFILES)

    @property
    def sim_kind(self) -> str:
        """What the rule's `sim` names: "topic", "service", or "node" (the engine supplies the source)."""
        return SIM_KINDS.get(self.runner, "node")


def converter_info(
    name: str,
    direction: str,
    ros_types: Iterable[str],
    runner: str,
    module: str,
    function: str,
    summary: str,
    **more: Any,
) -> ConverterInfo:
    """A catalogue entry, its ROS types given as any sequence (an entry lists them as a list)."""
    return ConverterInfo(name, direction, tuple(ros_types), runner, module, function, summary, **more)
