#!/usr/bin/env python3
"""The Project AirSim ROS bridge node (rosrun projectairsim_ros projectairsim_node.py)."""

import signal

# Before anything is imported: a signal during the imports is only noted, and the node stops cleanly.
EARLY_SIGNALS: list[int] = []
for _number in (signal.SIGINT, signal.SIGTERM):
    signal.signal(_number, lambda number, _frame: EARLY_SIGNALS.append(number))

import sys  # noqa: E402
from pathlib import Path  # noqa: E402

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))  # run from a checkout without install

from airsim_mapper.cli.node import run  # noqa: E402

if __name__ == "__main__":
    run(EARLY_SIGNALS)
