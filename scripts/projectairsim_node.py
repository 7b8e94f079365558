#!/usr/bin/env python3
"""The Project AirSim ROS bridge node (rosrun projectairsim_ros projectairsim_node.py)."""

import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))  # run from a checkout without install

from airsim_mapper.cli.node import run

if __name__ == "__main__":
    run()
