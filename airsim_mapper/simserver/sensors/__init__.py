"""Sensors: when each sensor of a robot samples, what it measures, and where its messages go.

`sensor_streams` schedules the instruments, lidars and radars of a robot and `camera_stream` its cameras;
the sensor models are `instrument_models` (with `battery`), `lidar_model` and `radar_model`. Its face
(`__all__`, the modules the rooms above import): `camera_stream`, `sensor_streams`.
"""

from __future__ import annotations

__all__ = ["camera_stream", "sensor_streams"]
