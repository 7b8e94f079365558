"""The mapping layer's errors: every problem found in a mapping, each located as FILE:LINE:COL.

`Problem` and `ConfigError` live in the leaf `airsim_mapper.common.errors` (scene.py, below this layer, raises
ConfigErrors too); they are re-exported here for the mapping modules."""

from __future__ import annotations

from airsim_mapper.common.errors import ConfigError, Problem

__all__ = ["ConfigError", "MappingError", "Problem"]


class MappingError(ConfigError):
    """The mapping YAML is invalid, or cannot be expanded over the scene (the mapping layer's base)."""
