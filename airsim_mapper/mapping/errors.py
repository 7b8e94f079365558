"""The mapping layer's errors: every problem found in a mapping or a scene, each located as FILE:LINE:COL.

`Problem` and `ConfigError` live in the leaf `airsim_mapper.common.errors`; they are re-exported here for
the mapping modules."""

from __future__ import annotations

from airsim_mapper.common.errors import ConfigError, Problem

__all__ = ["ConfigError", "MappingError", "Problem"]


class MappingError(ConfigError):
    """The mapping YAML or the scene is invalid, or the mapping cannot be expanded over the scene (the
    mapping layer's base)."""
