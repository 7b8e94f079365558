#!/usr/bin/env python3
"""The headless Project AirSim server as a ROS package executable (for roslaunch)."""

import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))  # run from a checkout without install

import rospy

from airsim_mapper.simserver.cli import main

if __name__ == "__main__":
    sys.exit(main(rospy.myargv(sys.argv)[1:]))
