"""/diagnostics' simulator entry: state, scene and the counts of refused simulator frames."""

from __future__ import annotations

from types import SimpleNamespace

from airsim_mapper.engine.diagnostics import OK, Diagnostics
from airsim_mapper.engine.sim_link import FrameCounts


def diagnostics(**engine: object) -> Diagnostics:
    made = Diagnostics.__new__(Diagnostics)  # no ROS: only the pure report is used
    made.engine = SimpleNamespace(state="connected", reason="", scene=None, bridges={}, **engine)
    made.prefix = "node: "
    return made


def test_the_simulator_entry_counts_bad_and_oversized_frames():
    status = diagnostics(frame_counts=FrameCounts(bad=3, oversized=2)).connection_status()
    assert status["level"] == OK
    assert (status["values"]["bad_frames"], status["values"]["oversized_frames"]) == ("3", "2")
