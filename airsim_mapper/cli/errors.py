"""The command-line layer's base exception, and the node's setting error."""

from __future__ import annotations

from typing import Any

from airsim_mapper.errors import AirsimMapperError

__all__ = ["CliError", "SettingError"]


class CliError(AirsimMapperError):
    """The command-line layer's base."""


class SettingError(CliError, ValueError):
    """A private parameter holds a value of the wrong type."""

    def __init__(self, name: str, value: Any, kind: type) -> None:
        super().__init__(f"parameter ~{name}: {value!r} is not a valid {kind.__name__}")
