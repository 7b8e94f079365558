"""Command-line entry points: `node` (the ROS node), `main` (airsim-mapper) and `validate`
(validate-mapping)."""

from __future__ import annotations

__all__ = ["main", "node", "validate"]
