"""The data RViz shows, watched: messages counted per topic, the latest radar marker and drone position."""

from __future__ import annotations

import math
import threading
from collections.abc import Iterable
from dataclasses import dataclass, field
from typing import Any

IMAGE_TOPIC = "/airsim_node/Drone1/Chase/scene_camera/image"
LIDAR_TOPIC = "/airsim_node/Drone1/lidar1/lidar"
MARKER_TOPIC = "/airsim_node/Drone1/radar1/radar_markers"
ODOM_TOPIC = "/airsim_node/Drone1/odom"


@dataclass
class Watch:
    """Counts messages on the topics RViz shows; keeps the latest radar marker and drone position."""

    counts: dict[str, int] = field(default_factory=dict)
    marker_points: int = 0
    marker_frame: str = ""
    position: tuple[float, float, float] = (0.0, 0.0, 0.0)
    receding: bool = False  # the last odometry message was farther from the pad than the one before
    lock: threading.Lock = field(default_factory=threading.Lock)

    def start(self, topics: Iterable[str]) -> None:
        import rospy
        from nav_msgs.msg import Odometry
        from visualization_msgs.msg import MarkerArray

        for topic in topics:
            cls = {MARKER_TOPIC: MarkerArray, ODOM_TOPIC: Odometry}.get(topic, rospy.AnyMsg)
            rospy.Subscriber(topic, cls, self.on_message, callback_args=topic, queue_size=1)

    def on_message(self, msg: Any, topic: str) -> None:
        with self.lock:
            self.counts[topic] = self.counts.get(topic, 0) + 1
            if topic == MARKER_TOPIC:
                points = sum(len(m.points) for m in msg.markers)
                if points:
                    self.marker_points = points
                    self.marker_frame = msg.markers[0].header.frame_id
            elif topic == ODOM_TOPIC:
                p = msg.pose.pose.position
                self.receding = math.hypot(p.x, p.y) > math.hypot(*self.position[:2])
                self.position = (p.x, p.y, p.z)

    def away(self, metres: float) -> bool:
        """The drone is at least `metres` from the pad (horizontally) and still flying away from it."""
        with self.lock:
            return math.hypot(*self.position[:2]) >= metres and self.receding

    def flowing(self, topics: Iterable[str], at_least: int) -> bool:
        with self.lock:
            return all(self.counts.get(t, 0) >= at_least for t in topics) and self.marker_points > 0
