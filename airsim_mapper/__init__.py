"""airsim-mapper: a declarative ROS1 bridge for Project AirSim."""

from __future__ import annotations

__version__ = "0.1.0"
