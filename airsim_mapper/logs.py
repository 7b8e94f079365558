"""Log helpers every layer may use: one rate-limited logger, and `shorten` for long values in log lines.

A leaf module (it imports nothing of the package).
"""

from __future__ import annotations

import logging
import threading
import time

__all__ = ["SHOWN_NAME", "RateLimitedLog", "shorten"]

SHOWN_NAME = 200  # characters of a user-given name (a scene file, say) a log line shows


class RateLimitedLog:
    """At most `count` messages per `period` seconds on `logger` at `level`, each after `prefix` (if any);
    the next one logged says how many were held back. Thread-safe."""

    def __init__(
        self,
        logger: logging.Logger,
        period: float = 5.0,
        count: int = 1,
        level: int = logging.WARNING,
        prefix: str = "",
    ) -> None:
        self.logger, self.period, self.count, self.level = logger, period, count, level
        self.prefix = f"{prefix}: " if prefix else ""
        self._window_start = -1e9
        self._logged = 0
        self._held = 0
        self._lock = threading.Lock()

    def warn(self, message: str, exc_info: BaseException | None = None) -> None:
        """Log `message` (with `exc_info`'s traceback, if given) unless this period's budget is spent."""
        with self._lock:
            now = time.monotonic()
            if now - self._window_start >= self.period:
                self._window_start, self._logged = now, 0
            if self._logged >= self.count:
                self._held += 1
                return
            self._logged += 1
            held, self._held = self._held, 0
        suffix = f" ({held} more not logged before this one)" if held else ""
        self.logger.log(self.level, "%s%s%s", self.prefix, message, suffix, exc_info=exc_info)


def shorten(text: str, keep: int = SHOWN_NAME) -> str:
    """`text`, or its first `keep` characters and how many more there were (for log lines)."""
    return text if len(text) <= keep else f"{text[:keep]}...({len(text) - keep} more)"
