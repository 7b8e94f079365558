"""Simulation time going backwards: a new simulator session.

A restarted simulator, or a scene loaded again, starts its clock from zero, so the /clock the node
publishes jumps back. ROS nodes with /use_sim_time see it: rospy.sleep and Rate.sleep raise
ROSTimeMovedBackwardsException, a rospy.Timer made without reset=True ends for good, and tf listeners
clear their buffers. The node cannot prevent the jump; it counts it (status `sim_time_jumps_back`), logs
it and shows the latest on /diagnostics for a while, and whatever depended on the old time starts over
(`on_jump`: the engine clears its tf buffer and the streams' stale filters). The stamps watched are those
of every frame the node receives (the hub's streams), so the pose streams that feed tf see a jump whether
or not anything subscribes to /clock.

Each stream is compared with itself: one topic's stamps only go forward within a session, while different
topics lag each other by any amount (a camera image, rendered and sent after the poses of its tick, is
hundreds of milliseconds behind them on a busy host; one watch over all stamps took that lag for a
restart). After a jump the other streams jump too, and old frames still in flight may come after new
ones, so for SETTLE_S every stream starts over quietly: a session restarts once.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field

NS_PER_S = 1_000_000_000
RECENT_S = 30.0  # how long /diagnostics keeps warning about the latest jump
SETTLE_S = 1.0  # after a jump, other streams' steps back are the same restart


@dataclass
class SimTimeWatch:
    """Follows each stream's simulator stamps and notices each step back in time.

    `observe` runs on the link's one receive thread, so the per-stream stamps need no lock."""

    warn: Callable[[str], None] | None = None
    on_jump: Callable[[float], None] | None = None  # told the size of each jump back, in seconds
    jumps_back: int = 0
    last_jump_s: float = 0.0  # size of the latest jump back, in seconds
    last_jump_at: float | None = None  # time.monotonic() when it was seen
    _last: dict[str, int] = field(default_factory=dict, init=False, repr=False)  # each stream's newest stamp

    def observe(self, stamp_ns: int, now: float, topic: str = "") -> float | None:
        """Note one stamp of `topic`; the size of the jump back in seconds if that stream's time went
        backwards (a new simulator session), else None."""
        last = self._last.get(topic)
        self._last[topic] = stamp_ns
        if last is None or stamp_ns >= last:
            return None
        if self.last_jump_at is not None and now - self.last_jump_at < SETTLE_S:
            return None  # this stream follows the restart already seen on another
        self._last = {topic: stamp_ns}
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
