"""The engine layer's base exception (every engine error is an EngineError, hence an AirsimMapperError)."""

from __future__ import annotations

from airsim_mapper.errors import AirsimMapperError

__all__ = ["EngineError"]


class EngineError(AirsimMapperError, RuntimeError):
    """The engine cannot do what was asked right now (the message says why); the engine layer's base."""
