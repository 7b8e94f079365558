"""ROS 2 quality of service in the mapping: the named profiles, a rule's `qos` value made concrete, and
the QoS each bridge and each of the node's own topics gets: the one source of these facts for the ROS 2
link.

A rule's `qos` is a profile name, or a mapping of reliability, durability, depth and history, optionally
starting from a `profile` that it overrides. Without one, a bridge gets its converter's profile from the
catalogue, or `transient_local` when the rule latches. ROS1 has no QoS and ignores all of it.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import replace
from typing import Any

from airsim_mapper.convert import catalog
from airsim_mapper.mapping.model import Options, Qos

# The profiles by name, with rclpy's settings (rmw's qos_profiles.h) where rclpy has one of that name.
PROFILES: dict[str, Qos] = {
    catalog.SENSOR_DATA: Qos("best_effort", "volatile", 5),
    catalog.DEFAULT_QOS: Qos("reliable", "volatile", 10),
    catalog.TRANSIENT_LOCAL: Qos("reliable", "transient_local", 1),
    catalog.SERVICES: Qos("reliable", "volatile", 10),
}
RELIABILITY = ("reliable", "best_effort")
DURABILITY = ("volatile", "transient_local")
HISTORY = ("keep_last", "keep_all")
SETTINGS = ("reliability", "durability", "depth", "history")

# What the node's own tf publishers get: /tf as tf2_ros's broadcaster (reliable, depth 100), /tf_static
# as its static broadcaster (latched, depth 1).
TF_QOS = Qos("reliable", "volatile", 100)
TF_STATIC_QOS = PROFILES[catalog.TRANSIENT_LOCAL]
SERVICE_QOS = PROFILES[catalog.SERVICES]


def qos_of(raw: str | Mapping[str, Any]) -> Qos:
    """A rule's schema-valid `qos` value as a concrete Qos: a profile, or settings over a profile (the
    `default` one when none is named)."""
    if isinstance(raw, str):
        return PROFILES[raw]
    base = PROFILES[raw.get("profile", catalog.DEFAULT_QOS)]
    return replace(base, **{key: raw[key] for key in SETTINGS if key in raw})


def bridge_qos(options: Options, converter: str) -> Qos:
    """The QoS a bridge of a rule with `options` and `converter` gets: the rule's own, else a latched rule's
    transient_local, else its converter's profile."""
    if options.qos is not None:
        return options.qos
    if options.latch:
        return PROFILES[catalog.TRANSIENT_LOCAL]
    info = catalog.find(converter)
    return PROFILES[info.qos if info else catalog.DEFAULT_QOS]


def node_topic_qos(latch: bool) -> Qos:
    """The QoS of a topic the node makes without a rule (its status topic, /diagnostics): transient_local
    when latched, else default (both carry state a monitor should not miss)."""
    return PROFILES[catalog.TRANSIENT_LOCAL if latch else catalog.DEFAULT_QOS]
