"""Converters between Project AirSim messages and ROS messages (pure functions, numpy fast paths).

`catalog` lists them (importable without ROS); `registry.get(name)` returns the implementation. Its face
(`__all__`, the modules the layers above import): `catalog`, `registry`, `context` (ConvertContext),
`errors`, the helpers the engine's runners share with the converters (`command.require_finite`,
`pose.camera_pose_key`), `buffer_data` (the parts of a message sent apart, which the engine publishes),
`flavour` (which ROS's messages the converters build, decided at import), `transport_params`
(image_transport's per-topic ROS parameters over a rule's params) and `rviz_radar` (radar scans as RViz
markers, for `scripts/radar_markers.py`).
"""

from __future__ import annotations

__all__ = [
    "buffer_data",
    "catalog",
    "command",
    "context",
    "errors",
    "flavour",
    "pose",
    "registry",
    "rviz_radar",
    "transport_params",
]
