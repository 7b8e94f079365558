"""SimTimeWatch: steps back in published sim time are counted, sized, logged and reported for a while."""

from __future__ import annotations

from airsim_mapper.engine.simtime import RECENT_S, SETTLE_S, SimTimeWatch
from airsim_mapper.engine.streams import Stream

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


def test_a_stream_behind_another_is_no_jump_and_each_jump_is_told():
    told: list[float] = []
    watch = SimTimeWatch(on_jump=told.append)
    for t in range(1, 50):  # poses run ahead; a camera's images come 0.6 s behind them, as on a busy host
        assert watch.observe(t * S // 10 + 600_000_000, t, "/pose") is None
        assert watch.observe(t * S // 10, t, "/image") is None
    assert watch.jumps_back == 0 and told == []
    assert watch.observe(6 * S, 100.0, "/image") is None  # forward in its own stream
    assert watch.observe(0, 101.0, "/pose") == 5.5  # the simulator restarted
    assert told == [5.5]


def test_one_restart_is_one_jump_whichever_streams_follow_it_and_in_what_order():
    watch = SimTimeWatch()
    for topic in ("/pose", "/image", "/lidar"):
        watch.observe(60 * S, 10.0, topic)
    assert watch.observe(1 * S, 20.0, "/pose") == 59.0
    assert watch.observe(59 * S, 20.1, "/lidar") is None  # the old session's frame still in flight
    assert watch.observe(1 * S, 20.2, "/lidar") is None  # then its new session
    assert watch.observe(2 * S, 20.3, "/image") is None  # a stream's first stamp after the restart
    assert watch.jumps_back == 1
    assert watch.observe(0, 20.0 + SETTLE_S + 1, "/lidar") == 1.0  # a later restart is a jump again
    assert watch.jumps_back == 2


def test_a_stream_tells_every_stamp_but_its_first_which_may_be_the_simulators_cached_frame():
    seen: list[int] = []
    stream = Stream("/t", on_stamp=lambda stamp, _now, _topic: seen.append(stamp))
    try:
        for stamp in (5, 1, 2, "x"):
            stream.offer(None, {"time_stamp": stamp})
        stream.offer(None, b"no stamp")
    finally:
        stream.stop()
    assert seen == [1, 2]
