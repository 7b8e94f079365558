"""The node's status topic: `/airsim_mapper/<node>/status` (`<node>` its full ROS name), a latched
std_msgs/String holding JSON.

Before the first connection the node publishes state "connecting", reason (why the simulator is not
reached), attempts and an empty scene (`WaitingStatus`). Then the fields are:
state ("connected", "stale" or "stopped"), scene, reason (why stale: the connection closed, or
"unresponsive: ..." while it is open; while connected: probes unanswered though topic frames arrive),
reconnects, sim_losses, stalls (times the simulator stopped
answering on an open connection), master_reregistrations, bad_frames and oversized_frames (simulator
frames dropped: undecodable, or over --max-frame-mb / an image's max_pixels), callback_errors (a callback
on the receive thread raised, a mission script's say; logged with its traceback), sim_time_jumps_back and
sim_time_last_jump_back_s (/clock going backwards, see simtime.py), and per simulator topic stream: received,
dropped, handled, errors, age_s (seconds since its last message), and the peaks since the previous
status: arrival_gap_max_ms (longest interval between two arrivals), wait_max_ms (longest wait for the
worker), handle_max_ms (longest handling). Published on every state change and once a second, by a
thread of its own.
"""

from __future__ import annotations

import json
import threading
from collections.abc import Callable
from typing import Any

from airsim_mapper.mapping.reserved import status_topic

CONNECTING = "connecting"  # before the first connection (WaitingStatus)
CONNECTED = "connected"
STALE = "stale"
STOPPED = "stopped"


class StatusPublisher:
    """Publishes status dicts as JSON; skips nothing, so subscribers see every change."""

    def __init__(self, make_publisher: Callable[..., Any], node_name: str) -> None:
        """`make_publisher` is RosLink.publisher or ros_link.publisher."""
        from std_msgs.msg import String

        self._string = String
        self._lock = threading.Lock()
        self.publisher = make_publisher(status_topic(node_name), "std_msgs/String", queue_size=2, latch=True)

    def publish(self, status: dict[str, Any]) -> None:
        text = json.dumps(status, sort_keys=True)
        with self._lock:
            self.publisher.publish(self._string(data=text))

    def close(self) -> None:
        self.publisher.unregister()


class WaitingStatus:
    """The status topic while the node waits for its first connection to the simulator: state "connecting",
    why, and the attempts so far (made on the first wait; the engine's own status follows it)."""

    def __init__(self, ros_name: str, make_publisher: Callable[..., Any] | None = None) -> None:
        """`make_publisher` is a ROS link's `publisher` (ROS1's `ros_link.publisher` when None)."""
        self.ros_name = ros_name
        self._make_publisher = make_publisher
        self._status: Any = None

    def publish(self, reason: str, attempts: int) -> None:
        if self._status is None:
            make = self._make_publisher
            if make is None:
                from airsim_mapper.engine.ros_link import publisher as make
            self._status = StatusPublisher(make, self.ros_name)
        self._status.publish({"state": CONNECTING, "reason": reason, "attempts": attempts, "scene": ""})

    def close(self) -> None:
        if self._status is not None:
            self._status.close()
