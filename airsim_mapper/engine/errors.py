"""The engine layer's base exception (every engine error is an EngineError, hence an AirsimMapperError)."""

from __future__ import annotations

from airsim_mapper.common.errors import AirsimMapperError

__all__ = ["EngineError", "InternalsChanged", "RosTypeError"]


class EngineError(AirsimMapperError, RuntimeError):
    """The engine cannot do what was asked right now (the message says why); the engine layer's base."""


class RosTypeError(EngineError, LookupError):
    """A ROS message or service type could not be imported."""


class InternalsChanged(EngineError):
    """A private part of a pinned library the bridge relies on is gone or different."""

    def __init__(self, library: str, missing: list[str]) -> None:
        super().__init__(
            f"{library}'s internals changed: {', '.join(missing)} no longer as the bridge expects "
            f"(it was written against {library}); see its adapter module in airsim_mapper/engine/"
        )
        self.missing = missing
