"""Simulation time going backwards: a new simulator session.

A restarted simulator, or a scene loaded again, starts its clock from zero, so the /clock the node
publishes jumps back. ROS nodes with /use_sim_time see it: rospy.sleep and Rate.sleep raise
ROSTimeMovedBackwardsException, a rospy.Timer made without reset=True ends for good, and tf listeners
clear their buffers. The node cannot prevent the jump; it counts it (status `sim_time_jumps_back`), logs
it and shows the latest on /diagnostics for a while, and whatever depended on the old time starts over
(`on_jump`: the engine clears its tf buffer and the streams' stale filters). The stamps watched are those
of every frame the node receives (the hub's streams), so the pose streams that feed tf see a jump whether
or not anything subscribes to /clock.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

NS_PER_S = 1_000_000_000
RECENT_S = 30.0  # how long /diagnostics keeps warning about the latest jump
TOLERANCE_NS = 100_000_000  # a stamp this much older than the newest is a jump (streams interleave)


@dataclass
class SimTimeWatch:
    """Follows the simulator's stamps and notices each step back in time."""

    warn: Callable[[str], None] | None = None
    on_jump: Callable[[float], None] | None = None  # told the size of each jump back, in seconds
    last_ns: int | None = None
    jumps_back: int = 0
    last_jump_s: float = 0.0  # size of the latest jump back, in seconds
    last_jump_at: float | None = None  # time.monotonic() when it was seen

    def observe(self, stamp_ns: int, now: float) -> float | None:
        """Note one stamp; the size of the jump back in seconds if time went backwards (more than
        TOLERANCE_NS behind the newest stamp seen: frames of different topics may interleave)."""
        last = self.last_ns
        if last is None or stamp_ns >= last - TOLERANCE_NS:
            if last is None or stamp_ns > last:
                self.last_ns = stamp_ns
            return None
        self.last_ns = stamp_ns
        jump = (last - stamp_ns) / NS_PER_S
        self.jumps_back += 1
        self.last_jump_s, self.last_jump_at = jump, now
        if self.warn is not None:
            self.warn(
                f"simulation time went back {jump:.3f} s (from {last / NS_PER_S:.3f} s to "
                f"{stamp_ns / NS_PER_S:.3f} s; the simulator restarted or reloaded its scene): nodes with "
                "/use_sim_time see time jump back"
            )
        if self.on_jump is not None:
            self.on_jump(jump)
        return jump

    def recent(self, now: float) -> str:
        """A warning for /diagnostics while the latest jump is recent, else ""."""
        if self.last_jump_at is None or now - self.last_jump_at > RECENT_S:
            return ""
        return (
            f"simulation time went back {self.last_jump_s:.3f} s {now - self.last_jump_at:.0f} s ago "
            f"({self.jumps_back} jumps back in all)"
        )
