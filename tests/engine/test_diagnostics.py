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


def test_a_recent_jump_back_in_sim_time_is_a_warning_on_the_simulator_entry():
    from airsim_mapper.engine.diagnostics import WARN
    from airsim_mapper.engine.simtime import SimTimeWatch

    watch = SimTimeWatch()
    watch.observe(5_000_000_000, 10.0)
    watch.observe(0, 11.0)
    status = diagnostics(sim_time=watch).connection_status(now=12.0)
    assert status["level"] == WARN
    assert status["message"] == "connected; simulation time went back 5.000 s 1 s ago (1 jumps back in all)"
    assert status["values"]["sim_time_jumps_back"] == "1"
    assert diagnostics(sim_time=watch).connection_status(now=100.0)["level"] == OK
