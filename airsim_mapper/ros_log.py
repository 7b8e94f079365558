"""The bridge's loggers: `rosout.<name>`, whose records rospy forwards to /rosout, each naming its caller.

rospy makes every logger created after it is imported a `RospyLogger`, whose findCaller looks for rospy's
own log wrappers (rospy.loginfo and friends) and, for any other call, names the thread's outermost frame:
every /rosout record of the node said `threading.py`, `Thread._bootstrap`. A `CallerLogger` finds its
caller as the standard library does, so /rosout records carry the calling file, function and line.
"""

from __future__ import annotations

import logging


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
