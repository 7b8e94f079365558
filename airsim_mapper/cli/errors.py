"""The command-line layer's base exception, and the node's setting error."""

from __future__ import annotations

from typing import Any

from airsim_mapper.common.errors import AirsimMapperError

__all__ = ["CliError", "FlavourError", "SettingError"]


class CliError(AirsimMapperError):
    """The command-line layer's base."""


class SettingError(CliError, ValueError):
    """A private parameter holds a value of the wrong type."""

    def __init__(self, name: str, value: Any, kind: type) -> None:
        super().__init__(f"parameter ~{name}: {value!r} is not a valid {kind.__name__}")


class FlavourError(CliError):
    """The ROS flavour asked for (or, unasked, either) is not importable by this interpreter."""

    def __init__(self, flavour: str, library: str, python: str) -> None:
        ros, venv = ("ROS1", ".venv") if flavour == "1" else ("ROS 2", ".venv-ros2")
        super().__init__(
            f"{ros}: {library} is not importable by {python}; run {venv}/bin/airsim-mapper-node of "
            f"the checkout (`make setup` builds {venv}), or an interpreter that has {library}"
        )
