"""The bridge's process settings: the shared thread tuning, prompt rospy publishing, a frozen heap.

`airsim_mapper.common.tuning` gives one BLAS thread and a 0.5 ms GIL switch interval. On top, the bridge uses
`PromptQueuedConnection` (rospy_internals.py): rospy's queued connection, which here sends on the
publishing thread when the socket takes the message at once, instead of waking a writer thread and
yielding the GIL on every publish. `freeze_heap` keeps the objects of a running scene out of full
collections, and `GcPauses` reports the longest garbage collection for the status topic.

The soak (`make soak`) measures their effect; `AIRSIM_MAPPER_NO_TUNING=1` turns off the thread settings and
prompt publishing for comparison (the heap is frozen either way).
"""

from __future__ import annotations

import gc
import time

from airsim_mapper.common.tuning import tune_threads
from airsim_mapper.convert.flavour import ROS2


def tune_process() -> None:
    """Apply the thread settings and prompt publishing to this process (idempotent).

    The node applies them; a mission script's wrapper only with `tune_process=True`. rospy's topics also
    watch their connections without an open file of their own (`ConnectionPoll`): with the heap frozen,
    the one rospy makes would outlive every topic."""
    if ROS2:
        tune_threads()
        return
    from airsim_mapper.engine.rospy_internals import publish_promptly, watch_connections_without_a_file

    watch_connections_without_a_file()
    if tune_threads():
        publish_promptly()


def freeze_heap() -> float:
    """Collect once, then move every surviving object out of the collector's sight; the time in ms.

    A full collection stops every thread for as long as it takes to walk all tracked objects, tens of
    thousands after the bridge's imports alone, in the middle of the pose path (docs/reliability.md has
    the measured pauses). After `gc.freeze()` later collections walk only what was made since.
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
