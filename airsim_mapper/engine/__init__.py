"""The live engine: runs expanded bridges between the simulator client and ROS."""
