"""Log helpers every layer may use: the bridge's loggers (`ros_logger`), one rate-limited logger, and
`shorten` for long values in log lines.

`ros_logger(name)` is `rosout.<name>`, whose records rospy forwards to /rosout, as a `CallerLogger`: rospy
makes every logger created after it is imported a `RospyLogger`, whose findCaller looks for rospy's own
log wrappers (rospy.loginfo and friends) and, for any other call, names the thread's outermost frame (every
/rosout record of the node said `threading.py`, `Thread._bootstrap`). A CallerLogger finds its caller as the
standard library does, so /rosout records carry the calling file, function and line.

A leaf module (it imports nothing of the package).
"""

from __future__ import annotations

import logging
import threading
import time
from typing import Callable

__all__ = ["SHOWN_NAME", "CallerLogger", "RateLimitedLog", "caller_logger", "ros_logger", "shorten"]
__all__ += ["wait_for_rosout"]

SHOWN_NAME = 200  # characters of a user-given name (a scene file, say) a log line shows
ROSOUT_WAIT_S = 2.0  # how long a node waits for the rosout node to connect before it logs on
_ROSOUT_WAITED = threading.Event()  # one wait per process: the node's, or else its first wrapper's


class CallerLogger(logging.Logger):
    """A logger whose records name the code that called it (the standard library's findCaller)."""

    findCaller = logging.Logger.findCaller


def caller_logger(logger: logging.Logger) -> logging.Logger:
    """`logger`, made a CallerLogger if rospy (or anything else) made it another class."""
    if type(logger) is not CallerLogger:
        logger.__class__ = CallerLogger
    return logger


def ros_logger(name: str) -> logging.Logger:
    """The logger `rosout.<name>`: to the console and, once rospy runs, to /rosout with its caller."""
    return caller_logger(logging.getLogger(f"rosout.{name}"))


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


def wait_for_rosout(timeout: float = ROSOUT_WAIT_S, stopping: Callable[[], bool] = lambda: False) -> bool:
    """Wait, at most `timeout` seconds, until the rosout node listens to this node's /rosout.

    /rosout latches: a subscriber that connects late gets only the last record. The rosout node connects a
    moment after init_node, and a node that starts quickly has by then logged its settings and its bridge
    table, which never reached rosout.log or rqt_console. Returns False at once when nothing subscribes
    to /rosout (a master started with `--core`), when rospy is not logging to it, or on `stopping()`.
    A process waits once: a later call only tells whether rosout is connected.
    """
    import rosgraph
    import rospy
    from rospy.impl import rosout

    publisher = rosout._rosout_pub
    if publisher is None:
        return False
    if _ROSOUT_WAITED.is_set():  # waited already (the node, before it made its wrapper)
        return bool(publisher.get_num_connections())
    _ROSOUT_WAITED.set()
    try:
        _publishers, subscribers, _services = rosgraph.Master(rospy.get_name()).getSystemState()
    except Exception:  # the master went away: the records go to the console and the log file only
        return False
    if not any(topic == "/rosout" and nodes for topic, nodes in subscribers):
        return False
    deadline = time.monotonic() + timeout
    while not publisher.get_num_connections():
        if stopping() or time.monotonic() >= deadline:
            return False
        time.sleep(0.01)
    return True


def shorten(text: str, keep: int = SHOWN_NAME) -> str:
    """`text`, or its first `keep` characters and how many more there were (for log lines)."""
    return text if len(text) <= keep else f"{text[:keep]}...({len(text) - keep} more)"
