"""The headless simulator's base exception (every simserver error is a SimServerError)."""

from __future__ import annotations

from airsim_mapper.common.errors import AirsimMapperError

__all__ = ["SimServerError"]


class SimServerError(AirsimMapperError):
    """The simulator server's base."""
