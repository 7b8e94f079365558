"""The mapping language: load and validate a mapping YAML, and expand its rules over a scene.

Its face (`__all__`, the modules the layers above import): `loader`, `expand`, `pipeline` (both in one
call), `model` (MappingDoc, BridgeSpec), `errors`, `diff`, `report`, `match`, `names` and `extends` (what the
command line shows of a mapping), `reserved` (the names the node owns, its status topic's among them),
`scene` (the scene configuration as the bridge reads it), `qos` (the ROS 2 QoS profiles, and those of the
node's own tf and clock publishers) and `ros2_names` (ROS 2's name rules, which a ROS 2 node checks).
Everything else is the mapping layer's own.
"""

from __future__ import annotations

__all__ = [
    "diff",
    "errors",
    "expand",
    "extends",
    "loader",
    "match",
    "model",
    "names",
    "pipeline",
    "qos",
    "report",
    "reserved",
    "ros2_names",
    "scene",
]
