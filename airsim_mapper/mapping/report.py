"""Plain views of bridges and rules: JSON-ready rows and an aligned text table."""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

from airsim_mapper.mapping.model import BridgeSpec, Qos, Rule

COLUMNS = ("direction", "sim", "ros", "ros_type", "frame_id")
HEADERS = ("DIRECTION", "SIMULATOR", "ROS", "TYPE", "FRAME")


def bridge_row(bridge: BridgeSpec) -> dict[str, Any]:
    """One bridge as a JSON-ready dict."""
    return {
        "name": bridge.name,
        "rule": bridge.rule,
        "direction": bridge.direction,
        "sim": bridge.sim,
        "sim_kind": bridge.sim_kind,
        "ros": bridge.ros,
        "ros_kind": bridge.ros_kind,
        "ros_type": bridge.ros_type,
        "converter": bridge.converter,
        "frame_id": bridge.frame_id,
        "tf": _tf(bridge.tf),
        "convention": bridge.convention,
        "lazy": bridge.options.lazy,
        "latch": bridge.options.latch,
        "qos": _qos(bridge.qos),
    }


def rule_row(rule: Rule) -> dict[str, Any]:
    """One rule (templates unexpanded) as a JSON-ready dict with the same keys as a bridge row."""
    return {
        "name": rule.name,
        "rule": rule.name,
        "for_each": rule.domain,
        "direction": rule.direction,
        "sim": rule.sim,
        "ros": rule.ros,
        "ros_kind": rule.ros_kind,
        "ros_type": rule.ros_type,
        "converter": rule.converter,
        "frame_id": rule.frame_id,
        "tf": _tf(rule.tf),
        "convention": rule.convention,
        "enabled": rule.options.enabled,
    }


def _cell(row: dict[str, Any], column: str) -> str:
    value = row.get(column)
    if column == "ros" and value is None and row.get("tf"):
        return f"(tf {row['tf']['parent']} -> {row['tf']['child']})"
    if column == "ros" and row.get("ros_kind") == "service":
        return f"{value} (service)"
    return "-" if value is None else str(value)


def format_rows(rows: Sequence[dict[str, Any]]) -> str:
    """An aligned text table of rows: direction, simulator side, ROS side, ROS type, frame."""
    cells = [HEADERS, *([_cell(row, c) for c in COLUMNS] for row in rows)]
    widths = [max(len(line[i]) for line in cells) for i in range(len(COLUMNS))]
    return "\n".join("  ".join(text.ljust(w) for text, w in zip(line, widths)).rstrip() for line in cells)


def format_table(bridges: Sequence[BridgeSpec]) -> str:
    """The bridges as an aligned text table."""
    return format_rows([bridge_row(b) for b in bridges])


def _qos(qos: Qos) -> dict[str, Any]:
    """A QoS as JSON: its four settings."""
    return {
        "reliability": qos.reliability,
        "durability": qos.durability,
        "depth": qos.depth,
        "history": qos.history,
    }


def _tf(tf: Any) -> dict[str, Any] | None:
    """A tf spec as JSON: parent and child, and `static` for a mount sent on /tf_static."""
    if tf is None:
        return None
    return {"parent": tf.parent, "child": tf.child, **({"static": True} if tf.static else {})}
