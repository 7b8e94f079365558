"""The bridge's process settings: the shared thread tuning, and rospy publishing without a yield.

`airsim_mapper.tuning` gives one BLAS thread and a 0.5 ms GIL switch interval. On top, the bridge uses
`PromptQueuedConnection`: rospy's queued connection without its `time.sleep(0)` after every enqueue, which
gave up the GIL once per publish, so a pose that fans out to six topics waited a switch interval per
topic. `freeze_heap` keeps the objects of a running scene out of full collections, and `GcPauses` reports
the longest garbage collection for the status topic.

The soak (`make soak`) measures their effect; `AIRSIM_MAPPER_NO_TUNING=1` turns them off for comparison.
"""

from __future__ import annotations

import gc
import time

import rospy
import rospy.topics
from rospy.impl.tcpros_pubsub import QueuedConnection

from airsim_mapper.tuning import tune_threads


class PromptQueuedConnection(QueuedConnection):
    """rospy's queued publisher connection without the `time.sleep(0)` after each enqueue.

    rospy ends every queued `write_data` with `time.sleep(0)` to let the connection's writer thread run.
    That gives up the GIL once per publish and subscriber; with busy threads in the process, getting it
    back costs up to a switch interval (5 ms) each time, so a pose message that fans out to six topics
    waited tens of milliseconds between its own publishes (see the README's reliability section). Without
    the yield the writer thread still wakes on the condition and sends as soon as it holds the GIL.
    """

    def write_data(self, data: bytes) -> bool:
        with self._lock:
            if self._error:
                error, self._error = self._error, None
                raise error
            if self._queue_size > 0 and len(self._queue) == self._queue_size:
                del self._queue[0]
            self._queue.append(data)
            self._cond_data_available.notify()
        return True


def tune_process() -> None:
    """Apply the settings to this process (idempotent; the engine calls it, so the node and the wrapper)."""
    if tune_threads():
        rospy.topics.QueuedConnection = PromptQueuedConnection


def freeze_heap() -> float:
    """Collect once, then move every surviving object out of the collector's sight; the time in ms.

    A full collection stops every thread for as long as it takes to walk all tracked objects: about
    70,000 after the bridge's imports alone, 29 ms on this machine and 52 ms seen on a slow stretch, in
    the middle of the pose path. After `gc.freeze()` later collections walk only what was made since.
    """
    started = time.perf_counter()
    gc.collect()
    gc.freeze()
    return (time.perf_counter() - started) * 1000.0


def thaw_heap() -> None:
    """Undo `freeze_heap` (before a scene change), so the replaced bridges' cycles are still collected."""
    gc.unfreeze()


class GcPauses:
    """The longest garbage collection of this process per window: a collection stops every thread."""

    def __init__(self) -> None:
        self._started = 0.0
        self.longest = 0.0
        self.collections = 0
        gc.callbacks.append(self._on_gc)

    def _on_gc(self, phase: str, _info: dict) -> None:
        if phase == "start":
            self._started = time.perf_counter()
        else:
            self.collections += 1
            self.longest = max(self.longest, time.perf_counter() - self._started)

    def take_peak_ms(self) -> float:
        """The longest pause since the previous call, in milliseconds."""
        longest, self.longest = self.longest, 0.0
        return round(longest * 1000, 1)

    def close(self) -> None:
        if self._on_gc in gc.callbacks:
            gc.callbacks.remove(self._on_gc)
