"""Sim clocks: steppable time follows wall time unless paused; continue-for/until pause at the target."""

from __future__ import annotations

import time

import pytest

from airsim_mapper.simserver.scene.sim_clock import SimClock
from airsim_mapper.simserver.wire.services import ServiceError


def test_a_steppable_clock_starts_near_zero_and_advances_with_wall_time():
    clock = SimClock()
    first = clock.now_ns()
    time.sleep(0.05)
    assert 0 <= first < 50_000_000
    assert clock.now_ns() - first >= 40_000_000


def test_a_paused_clock_stands_still_and_resumes_where_it_stopped():
    clock = SimClock()
    message = clock.pause(True)
    frozen = clock.now_ns()
    assert message == f"Sim time paused at t = {frozen}"
    time.sleep(0.03)
    assert clock.now_ns() == frozen and clock.is_paused()
    assert clock.pause(False) == f"Sim time resumed from t = {frozen}"
    time.sleep(0.02)
    assert clock.now_ns() > frozen and not clock.is_paused()


def test_pause_on_start_begins_paused_at_zero():
    clock = SimClock(paused=True)
    assert clock.now_ns() == 0 and clock.is_paused()


def test_continue_for_runs_exactly_that_long_and_pauses_again():
    clock = SimClock(step_ns=3_000_000, paused=True)
    assert clock.continue_for(20_000_000, wait=True) == 20_000_000
    assert clock.is_paused()
    assert clock.continue_until(50_000_000, wait=True) == 50_000_000


def test_continue_without_waiting_returns_at_once_and_pauses_later():
    clock = SimClock(paused=True)
    returned = clock.continue_for(30_000_000, wait=False)
    assert returned < 30_000_000
    assert clock.wait_until(30_000_000, timeout_s=2.0)
    assert clock.now_ns() == 30_000_000 and clock.is_paused()


def test_continue_until_a_past_time_does_nothing():
    clock = SimClock(paused=True)
    clock.continue_for(10_000_000, wait=True)
    assert clock.continue_until(5_000_000, wait=True) == 10_000_000


def test_wait_until_gives_up_after_its_timeout():
    clock = SimClock(paused=True)
    assert clock.wait_until(1_000_000, timeout_s=0.01) is False


def test_a_real_time_clock_reads_unix_time_and_refuses_to_pause():
    clock = SimClock("real-time")
    assert abs(clock.now_ns() - time.time_ns()) < 1_000_000_000
    with pytest.raises(ServiceError, match=r"This clock type doesn't support SimPause\."):
        clock.pause(True)
    with pytest.raises(ServiceError, match=r"This clock type doesn't support ContinueForNSteps\."):
        clock.continue_for(1, wait=False, what="ContinueForNSteps")
    with pytest.raises(ServiceError, match=r"This clock type doesn't support ContinueUntilSimTime\."):
        clock.continue_until(1, wait=False)


def test_lock_step_continues_wait_for_each_step_to_be_driven_and_finished():
    import threading

    clock = SimClock(step_ns=3_000_000, paused=True, lock_step=True)
    seen: list[int] = []
    stop = threading.Event()

    def drive():  # the server's simulation loop: one step, its work, then the step is done
        while not stop.is_set():
            if clock.stepping():
                seen.append(clock.begin_step())
                assert clock.now_ns() == seen[-1] and not clock.is_paused()
                time.sleep(0.002)  # a slow render must not let time run on
                clock.finish_step()
            else:
                time.sleep(0.0005)

    driver = threading.Thread(target=drive)
    driver.start()
    try:
        assert clock.continue_for(10_000_000, wait=True) == 10_000_000
        assert seen == [3_000_000, 6_000_000, 9_000_000, 10_000_000]
        assert clock.is_paused() and not clock.stepping()
        time.sleep(0.01)
        assert clock.now_ns() == 10_000_000
        seen.clear()
        assert clock.continue_for(clock.step_ns, wait=True) == 13_000_000 and seen == [13_000_000]
    finally:
        stop.set()
        driver.join()


def test_a_running_lock_step_clock_continues_in_wall_time():
    clock = SimClock(step_ns=3_000_000, lock_step=True)
    start = clock.now_ns()
    assert clock.continue_for(20_000_000, wait=True) >= start + 20_000_000
    assert not clock.stepping() and clock.is_paused()
