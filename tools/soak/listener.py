"""The soak's monitor: subscribes to every topic of the bridge node, counts messages, times actual_pose
and keeps the status topic's peaks."""

from __future__ import annotations

import json
import threading
import time

from tools.soak.probes import POSE_TOPIC


class Listener:
    """Subscribes to every topic of the bridge node; counts messages and times actual_pose."""

    def __init__(self) -> None:
        self.counts: dict[str, int] = {}
        self.pose_times: list[float] = []
        self.pose_stamps: list[float] = []  # header stamps (sim time): tells lost messages from late ones
        self.status: dict = {}
        self.peaks: dict[str, dict[str, float]] = {}  # per simulator topic: the largest status peaks
        self.collect_peaks = False
        self.gc_max_ms = 0.0  # the bridge's longest garbage collection after warm-up
        self._lock = threading.Lock()
        self._subs: list = []

    def attach(self, topics: list[str]) -> None:
        import rospy
        from std_msgs.msg import String

        for topic in topics:
            if topic.endswith("/status"):
                self._subs.append(rospy.Subscriber(topic, String, self._on_status))
            elif topic == POSE_TOPIC:
                from geometry_msgs.msg import PoseStamped

                self._subs.append(
                    rospy.Subscriber(topic, PoseStamped, self._on_pose, queue_size=50, tcp_nodelay=True)
                )
            else:
                self._subs.append(rospy.Subscriber(topic, rospy.AnyMsg, self._counter(topic), queue_size=50))

    def _counter(self, topic: str):
        def on_message(_msg) -> None:
            with self._lock:
                self.counts[topic] = self.counts.get(topic, 0) + 1

        return on_message

    def _on_pose(self, msg) -> None:
        now = time.monotonic()
        with self._lock:
            self.counts[POSE_TOPIC] = self.counts.get(POSE_TOPIC, 0) + 1
            self.pose_times.append(now)
            self.pose_stamps.append(msg.header.stamp.to_sec())

    def _on_status(self, msg) -> None:
        self.status = json.loads(msg.data)
        if not self.collect_peaks:
            return
        with self._lock:
            self.gc_max_ms = max(self.gc_max_ms, self.status.get("gc_max_ms") or 0.0)
            for topic, stream in self.status.get("streams", {}).items():
                mine = self.peaks.setdefault(topic, {})
                for key, value in stream.items():
                    if key.endswith("_max_ms"):
                        mine[key] = max(mine.get(key, 0.0), value)

    def snapshot(self) -> tuple[dict[str, int], list[float], list[float]]:
        with self._lock:
            return dict(self.counts), list(self.pose_times), list(self.pose_stamps)


def node_topics(node: str) -> list[str]:
    import rosgraph

    state = rosgraph.Master("/soak").getSystemState()
    return sorted(topic for topic, nodes in state[0] if f"/{node}" in nodes and topic not in ("/rosout",))
