"""The shared leaves: every layer may import them, and they import nothing of the package above them
(errors' root, config files, the Fast DDS profile, geometry, image types, logging, waiting on NNG, ports,
resources, ROS type names, process tuning)."""

from __future__ import annotations

__all__ = [
    "dds_profile",
    "errors",
    "files",
    "geometry",
    "image_types",
    "logs",
    "nng_wait",
    "ports",
    "resources",
    "ros_types",
    "tuning",
]
