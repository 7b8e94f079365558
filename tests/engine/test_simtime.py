"""SimTimeWatch: steps back in published sim time are counted, sized, logged and reported for a while."""

from __future__ import annotations

from airsim_mapper.engine.simtime import RECENT_S, SimTimeWatch

S = 1_000_000_000


def test_time_going_forward_or_standing_still_is_no_jump():
    watch = SimTimeWatch()
    assert [watch.observe(t, 0.0) for t in (0, 5 * S, 5 * S, 6 * S)] == [None] * 4
    assert watch.jumps_back == 0 and watch.recent(0.0) == ""


def test_a_step_back_is_counted_sized_and_logged_once():
    said: list[str] = []
    watch = SimTimeWatch(warn=said.append)
    watch.observe(7_600_000_000, 10.0)
    assert watch.observe(2 * S, 11.0) == 5.6
    assert watch.observe(3 * S, 12.0) is None  # forward again from the new time
    assert (watch.jumps_back, watch.last_jump_s) == (1, 5.6)
    assert said == [
        "simulation time went back 5.600 s (from 7.600 s to 2.000 s; the simulator restarted or reloaded "
        "its scene): nodes with /use_sim_time see time jump back"
    ]


def test_the_latest_jump_is_reported_while_it_is_recent():
    watch = SimTimeWatch()
    watch.observe(9 * S, 0.0)
    watch.observe(1 * S, 100.0)
    assert watch.recent(104.0) == "simulation time went back 8.000 s 4 s ago (1 jumps back in all)"
    assert watch.recent(100.0 + RECENT_S + 1) == ""
