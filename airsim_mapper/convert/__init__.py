"""Converters between Project AirSim messages and ROS messages (pure functions, numpy fast paths).

`catalog` lists them (importable without ROS); `registry.get(name)` returns the implementation. Its face
(`__all__`, the modules the layers above import): `catalog`, `registry`, `context` (ConvertContext),
`errors`, and the helpers the engine's runners share with the converters (`command.require_finite`,
`pose.camera_pose_key`).
"""

from __future__ import annotations

__all__ = ["catalog", "command", "context", "errors", "pose", "registry"]
