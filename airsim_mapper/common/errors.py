"""The package's exceptions share one root, so `except AirsimMapperError` catches every error it raises.

A leaf module (it imports nothing of the package), so every layer can use it. Under the root, each
subpackage has one base of its own (`mapping.errors.MappingError`, `convert.errors.ConvertError`,
`engine.errors.EngineError`, `simserver.errors.SimServerError`, `cli.errors.CliError`); the shared modules
at the top (files, geometry, scene, wrapper, rviz_radar) raise classes based on the root or on
`ConfigError`. A class that callers may catch as a ValueError, LookupError, ... has that base as well.

`ConfigError` is here because both the mapping layer and `scene.py` (below it) raise it: a mapping or a
scene is invalid, and `str()` is the full report, one `FILE:LINE:COL: message` a line.
"""

from __future__ import annotations

from collections.abc import Iterable
from dataclasses import asdict, dataclass, field

__all__ = ["AirsimMapperError", "ConfigError", "Problem"]


class AirsimMapperError(Exception):
    """The root of every exception airsim-mapper raises."""


def _one_line(message: str) -> str:
    """The message with unprintable characters (newlines, form feeds, ...) escaped, so it stays one line."""
    if message.isprintable():
        return message
    return "".join(char if char.isprintable() else repr(char)[1:-1] for char in message)


@dataclass(frozen=True, order=True)
class Problem:
    """One problem at one place in one file (line and column are 1-based; 0 means unknown)."""

    file: str
    line: int
    column: int
    message: str
    key: str = field(default="", compare=False)  # the key path in the file (`rules[3].queue_size`)

    def __str__(self) -> str:
        message = _one_line(self.message)
        if self.line <= 0:
            return f"{self.file}: {message}"
        return f"{self.file}:{self.line}:{max(self.column, 1)}: {message}"

    def as_dict(self) -> dict[str, str | int]:
        """The problem as plain data (validate-mapping --format json)."""
        return asdict(self)


class ConfigError(AirsimMapperError):
    """A mapping or a scene is invalid; str() is the full report, one `FILE:LINE:COL: message` a line."""

    def __init__(self, problems: Iterable[Problem], unreadable: bool = False) -> None:
        self.problems: tuple[Problem, ...] = tuple(problems)
        self.unreadable = unreadable  # the file itself could not be read (the CLI exits 2, not 1)
        super().__init__("\n".join(str(p) for p in self.problems))

    @classmethod
    def single(cls, file: str, message: str, line: int = 0, column: int = 0, unreadable: bool = False):
        return cls([Problem(file, line, column, message)], unreadable=unreadable)
