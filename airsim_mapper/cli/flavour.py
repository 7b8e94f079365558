"""Which ROS the node runs on: `--ros 1|2`, else the one this interpreter can import.

ROS1 (rospy, from Debian) and ROS 2 (rclpy, from PyPI's wheels) live in two environments, `.venv` and
`.venv-ros2`, because their message packages share names. The choice is made before either is imported.
"""

from __future__ import annotations

import importlib.util
import sys
from collections.abc import Callable, Sequence

from airsim_mapper.cli.errors import FlavourError

__all__ = ["FLAVOURS", "choose", "requested"]

FLAVOURS = {"1": "rospy", "2": "rclpy"}  # the flavour and the library that is it
SWITCH = "--ros"


def requested(argv: Sequence[str]) -> str | None:
    """The value of the last `--ros N` or `--ros=N` on the command line, if any (argparse checks it)."""
    found = None
    for i, arg in enumerate(argv):
        if arg == SWITCH and i + 1 < len(argv):
            found = argv[i + 1]
        elif arg.startswith(f"{SWITCH}="):
            found = arg.split("=", 1)[1]
    return found


def _importable(name: str) -> bool:
    return importlib.util.find_spec(name) is not None


def choose(asked: str | None, importable: Callable[[str], bool] = _importable) -> str:
    """The flavour to run: the one asked for if its library is importable, unasked ROS1 before ROS 2;
    `FlavourError` (naming `make setup`) when that is not possible. An unknown value is left to argparse."""
    if asked in FLAVOURS:
        if not importable(FLAVOURS[asked]):
            raise FlavourError(asked, FLAVOURS[asked], sys.executable)
        return asked
    for flavour, library in FLAVOURS.items():
        if importable(library):
            return flavour
    raise FlavourError("1", FLAVOURS["1"], sys.executable)
