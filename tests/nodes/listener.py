"""Test node: waits for one Image and one RadarScan and prints what arrived as JSON."""

from __future__ import annotations

import json

import rospy
from radar_msgs.msg import RadarScan
from sensor_msgs.msg import Image


def main() -> None:
    rospy.init_node("listener")
    image = rospy.wait_for_message("/test/image", Image, timeout=20)
    scan = rospy.wait_for_message("/test/radar", RadarScan, timeout=20)
    ret = scan.returns[0]
    print(
        "RESULT "
        + json.dumps(
            {
                "image": {
                    "shape": [image.height, image.width],
                    "encoding": image.encoding,
                    "data": list(bytearray(image.data)),
                    "frame": image.header.frame_id,
                },
                "radar": {
                    "frame": scan.header.frame_id,
                    "n": len(scan.returns),
                    "range": ret.range,
                    "azimuth": ret.azimuth,
                    "doppler": ret.doppler_velocity,
                    "amplitude": ret.amplitude,
                },
            }
        )
    )


if __name__ == "__main__":
    main()
