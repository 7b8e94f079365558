#!/usr/bin/env python3
"""radar_markers: republishes radar_msgs/RadarScan as visualization_msgs/MarkerArray for RViz.

RViz has no display for radar_msgs, so this node turns each scan into one SPHERE_LIST marker in the
radar's frame (`airsim_mapper.convert.rviz_radar`). Run it with the venv's python (it needs the generated
radar_msgs). `--convention frd` matches mappings/default.yaml, `--convention flu` mappings/enu.yaml.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))  # run from a checkout without install

DEFAULT_SCAN = "/airsim_node/Drone1/radar1/radar_detections"
DEFAULT_MARKERS = "/airsim_node/Drone1/radar1/radar_markers"


def parse_args(argv: list[str]) -> argparse.Namespace:
    parser = argparse.ArgumentParser(description="RadarScan -> MarkerArray (one SPHERE_LIST per scan).")
    parser.add_argument("--scan", default=DEFAULT_SCAN, help="the radar_msgs/RadarScan topic")
    parser.add_argument("--markers", default=DEFAULT_MARKERS, help="the MarkerArray topic to publish")
    parser.add_argument("--convention", choices=("frd", "flu"), default="frd", help="the mapping's frames")
    parser.add_argument("--diameter", type=float, default=1.0, help="sphere diameter, m")
    parser.add_argument("--lifetime", type=float, default=1.0, help="marker lifetime, s (0: forever)")
    return parser.parse_args(argv)


def run(argv: list[str]) -> int:
    import rospy
    from radar_msgs.msg import RadarScan
    from visualization_msgs.msg import MarkerArray

    from airsim_mapper.convert.rviz_radar import MarkerStyle, scan_markers

    args = parse_args(rospy.myargv(argv)[1:])
    rospy.init_node("radar_markers")
    style = MarkerStyle(diameter_m=args.diameter, lifetime_s=args.lifetime)
    publisher = rospy.Publisher(args.markers, MarkerArray, queue_size=2)

    def on_scan(scan: RadarScan) -> None:
        publisher.publish(scan_markers(scan, args.convention, style))

    rospy.Subscriber(args.scan, RadarScan, on_scan, queue_size=2)
    rospy.loginfo("radar_markers: %s -> %s (%s)", args.scan, args.markers, args.convention)
    rospy.spin()
    return 0


if __name__ == "__main__":
    sys.exit(run(sys.argv))
