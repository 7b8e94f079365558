"""The per-bridge context every converter receives alongside the message.

Converters are functions of (message, context). Two parts of a context change between messages, each
with one owner: `mounts` (the engine's camera mounts, written only by a camera pose command's reply and
read here) and `state` (the bridge's own memory across its messages, written only by its converter on
the bridge's one worker thread, such as odometry's previous pose). No converter writes state that another
bridge reads.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, MutableMapping
from dataclasses import dataclass, field
from typing import Any

from airsim_mapper.convert.errors import ContextError

NED = "ned"
ENU = "enu"
CONVENTIONS = (NED, ENU)
STAMP_SIM = "sim"
STAMP_ROS = "ros"
STAMPS = (STAMP_SIM, STAMP_ROS)


@dataclass(frozen=True)
class ConvertContext:
    """What a converter needs besides the message itself.

    - frame_id: header.frame_id to set ("" = none).
    - convention: "ned" passes the simulator's NED/FRD data through; "enu" converts to REP-103
      (world ENU, body FLU).
    - stamp: "sim" stamps headers with the sim message's ``time_stamp`` (int ns); "ros" with ``now()``.
    - now: the node's clock (rospy.Time.now in the engine); needed when stamp == "ros".
    - params: the rule's free-form converter parameters.
    - source: the scene element (capture setting + "camera_origin", sensor config, robot actor).
    - variables: the template variables of the bridge (robot_name, camera_name, ...).
    - options: the rule's airsim_mapper.mapping.model.Options (command limits, watchdog).
    - mounts: read-only, the camera mounts commanded since the scene loaded, keyed
      ``convert.pose.camera_pose_key(robot_name, camera_name)`` (engine/mounts.py owns them).
    - state: this bridge's own memory across messages (each bridge gets a fresh dict).
    - on_clamp: told what a command converter changed to keep a command within its limits (the engine
      counts and warns); None ignores it.
    """

    frame_id: str = ""
    convention: str = NED
    stamp: str = STAMP_SIM
    now: Callable[[], Any] | None = None
    params: Mapping[str, Any] = field(default_factory=dict)
    source: Mapping[str, Any] = field(default_factory=dict)
    variables: Mapping[str, str] = field(default_factory=dict)
    options: Any = None
    mounts: Mapping[Any, Any] = field(default_factory=dict)
    state: MutableMapping[Any, Any] = field(default_factory=dict)
    on_clamp: Callable[[str], None] | None = None

    def __post_init__(self) -> None:
        if self.convention not in CONVENTIONS:
            raise ContextError(f"convention must be one of {CONVENTIONS}, got {self.convention!r}")
        if self.stamp not in STAMPS:
            raise ContextError(f"stamp must be one of {STAMPS}, got {self.stamp!r}")

    @property
    def enu(self) -> bool:
        return self.convention == ENU

    def clamped(self, what: str) -> None:
        """A command was changed to keep it within its limits: say what (see `on_clamp`)."""
        if self.on_clamp is not None:
            self.on_clamp(what)
