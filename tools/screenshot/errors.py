"""The screenshot's errors: one root, and a process of the pipeline that exited early."""

from __future__ import annotations

import contextlib
from pathlib import Path


class ScreenshotError(RuntimeError):
    """The screenshot could not be taken (the message says which part failed)."""


class ChildExited(ScreenshotError):
    """A process of the pipeline exited early; the message ends with the tail of its log."""

    def __init__(self, name: str, log: Path) -> None:
        self.log = log
        super().__init__(f"{name} exited early; see {log}:\n{tail(log)}")

    def log_text(self) -> str:
        with contextlib.suppress(OSError):
            return self.log.read_text(errors="replace")
        return ""


def tail(path: Path, lines: int = 25) -> str:
    with contextlib.suppress(OSError):
        return "\n".join(path.read_text(errors="replace").splitlines()[-lines:])
    return ""
