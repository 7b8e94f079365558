"""Test node: publishes a known sensor_msgs/Image and radar_msgs/RadarScan at 10 Hz until killed."""

from __future__ import annotations

import rospy
from radar_msgs.msg import RadarReturn, RadarScan
from sensor_msgs.msg import Image


def main() -> None:
    rospy.init_node("talker")
    image_pub = rospy.Publisher("/test/image", Image, queue_size=1)
    radar_pub = rospy.Publisher("/test/radar", RadarScan, queue_size=1)
    image = Image(height=2, width=3, encoding="bgr8", step=9, data=bytes(range(18)))
    image.header.frame_id = "cam"
    scan = RadarScan(
        returns=[RadarReturn(range=12.5, azimuth=0.25, elevation=-0.1, doppler_velocity=-3.0, amplitude=7.0)]
    )
    scan.header.frame_id = "radar"
    rate = rospy.Rate(10)
    while not rospy.is_shutdown():
        image.header.stamp = scan.header.stamp = rospy.Time.now()
        image_pub.publish(image)
        radar_pub.publish(scan)
        rate.sleep()


if __name__ == "__main__":
    main()
