"""Unit tests of the pure parts: backoff, the loss verdict, opening a client, the start-up wait,
re-registration with a restarted master, and the converter registry's closed world."""

from __future__ import annotations

import logging
import math
import socket
import sys
import threading
import time
from dataclasses import dataclass, field

import pytest
from harness import free_port

from airsim_mapper.cli.node import connect
from airsim_mapper.convert import registry
from airsim_mapper.engine.health import (
    CONNECT_LINE,
    FRAMES_FRESH_S,
    LOST,
    OK,
    PROBE_MISSES,
    PROBE_PERIOD_S,
    PROBE_TIMEOUT_S,
    UNRESPONSIVE,
    Backoff,
    HealthCheck,
    SimUnreachable,
    Verdict,
    open_client,
    retry_quietly,
)
from airsim_mapper.engine.reregister import ReregisterError, _check, needs_registration
from airsim_mapper.engine.sim_link import SimLink, SimLinkDead, SimLinkError
from airsim_mapper.engine.status import status_topic
from airsim_mapper.wrapper import redirect_client_log


def test_backoff_doubles_to_half_a_second_then_slows_to_two_and_five_seconds():
    backoff = Backoff()
    delays = [backoff.next_delay() for _ in range(35)]
    assert delays[:3] == [0.25, 0.5, 0.5]
    assert set(delays[2:10]) == {0.5}
    assert set(delays[10:30]) == {2.0}
    assert set(delays[30:]) == {5.0}
    backoff.reset()
    assert backoff.next_delay() == 0.25


@dataclass
class FakeLink:
    up: bool = True
    answers: list[bool] = field(default_factory=list)

    def connected(self) -> bool:
        return self.up

    def probe(self, timeout: float) -> bool:
        return self.answers.pop(0)


def no_frames() -> float:
    return math.inf


def test_a_dropped_connection_is_lost_at_once():
    verdict = HealthCheck().check(FakeLink(up=False), no_frames)
    assert verdict == Verdict(LOST, "the simulator closed the connection")


def test_unanswered_probes_on_an_open_connection_mean_unresponsive_never_lost_until_an_answer():
    check = HealthCheck()
    link = FakeLink(answers=[False, False, True, False, False, False, False, True])
    verdicts = [check.check(link, no_frames) for _ in range(8)]
    assert [v.kind for v in verdicts] == [OK] * 5 + [UNRESPONSIVE] * 2 + [OK]
    assert verdicts[5].reason == "no answer to 3 probes of 1 s; the connection is open"


def test_topic_frames_arriving_while_probes_go_unanswered_are_no_stall_and_the_verdict_says_so():
    """After a network outage the topics connection may flow seconds before the probes' one recovers."""
    check = HealthCheck()
    link = FakeLink(answers=[False] * 7 + [True])
    ages = [math.inf, math.inf, math.inf, math.inf, 0.2, 1.4, 1.6, 9.0]  # seconds, at each check
    verdicts = [check.check(link, lambda age=age: age) for age in ages]
    assert [v.kind for v in verdicts] == [OK, OK, UNRESPONSIVE, UNRESPONSIVE, OK, OK, UNRESPONSIVE, OK]
    assert verdicts[4] == Verdict(OK, "no answer to 5 probes of 1 s, but topic frames arrive")
    assert verdicts[6].reason == "no answer to 7 probes of 1 s; the connection is open"
    assert verdicts[7] == Verdict(OK)
    # a frozen simulator's last frame is at least PROBE_MISSES - 1 checks old at the PROBE_MISSES-th miss
    assert FRAMES_FRESH_S <= 0.5 * (PROBE_MISSES - 1) * (PROBE_TIMEOUT_S + PROBE_PERIOD_S)


def test_opening_a_client_where_no_simulator_runs_raises_sim_unreachable_saying_why():
    port = free_port()
    with pytest.raises(SimUnreachable, match=rf"simulator at 127\.0\.0\.1:{port}/{port} not reachable"):
        open_client("127.0.0.1", port, port)
    with socket.socket() as listening:  # one port taken, the other free: the free one is named
        listening.bind(("127.0.0.1", 0))
        listening.listen()
        taken = listening.getsockname()[1]
        with pytest.raises(SimUnreachable) as raised:
            open_client("127.0.0.1", taken, port)
    assert str(raised.value).endswith(f"not reachable (nothing listens on port {port})")  # not "silent"
    with pytest.raises(SimUnreachable, match=r"\(Address invalid: is the address or host name right\?\)"):
        open_client("no.such.host.invalid", port, port)


@pytest.fixture
def redirected():
    """The client's records redirected to rosout.projectairsim, as in the node; its filters put back after."""
    client_log = logging.getLogger("projectairsim")
    before = list(client_log.filters)
    redirect_client_log()
    yield client_log
    client_log.filters = before


def test_connect_retries_with_backoff_and_gives_up_when_ros_shuts_down(caplog, redirected):
    port = free_port()
    slept: list[float] = []
    with caplog.at_level(logging.INFO):
        result = connect("127.0.0.1", port, port, lambda: len(slept) >= 4, sleep=slept.append)
        redirected.info(f"{CONNECT_LINE} at 127.0.0.1 (after the retries)")
    assert result is None
    assert slept == [0.25, 0.5, 0.5, 0.5]
    lines = [r.getMessage() for r in caplog.records if "waiting for it" in r.getMessage()]
    assert len(lines) == 4 and "attempt 4, next in 0.5 s" in lines[-1]
    # One line per attempt: the client announces the first, the retries only say they wait; the quiet
    # ends with the retries.
    announced = [r.getMessage() for r in caplog.records if r.getMessage().startswith(CONNECT_LINE)]
    assert announced == [f"{CONNECT_LINE} at 127.0.0.1", f"{CONNECT_LINE} at 127.0.0.1 (after the retries)"]


def test_a_quiet_retry_leaves_other_threads_connect_lines_alone(caplog, redirected):
    port = free_port()
    other: list[threading.Thread] = []
    with caplog.at_level(logging.INFO), retry_quietly():
        with pytest.raises(SimUnreachable):
            open_client("127.0.0.1", port, port)
        other.append(threading.Thread(target=redirected.info, args=(f"{CONNECT_LINE} at elsewhere",)))
        other[0].start()
        other[0].join()
    assert [r.getMessage() for r in caplog.records if r.getMessage().startswith(CONNECT_LINE)] == [
        f"{CONNECT_LINE} at elsewhere"
    ]


def test_records_keep_their_way_to_rosout_while_retries_come_and_go(redirected):
    """Another thread's records all go through the redirect while a retry begins and ends over and over
    (taking the quiet filter out of the logger's list had let some skip it)."""

    class Count(logging.Handler):
        def __init__(self) -> None:
            super().__init__()
            self.seen = 0

        def emit(self, record: logging.LogRecord) -> None:
            self.seen += 1

    target = logging.getLogger("rosout.projectairsim")
    passed, skipped = Count(), Count()  # through the redirect; past it, to the client logger's own
    loggers = ((target, passed), (redirected, skipped))
    saved = [(logger, logger.propagate) for logger, _ in loggers]
    for logger, handler in loggers:
        logger.addHandler(handler)
        logger.propagate = False  # nothing reaches the root logger's handlers
    stop = threading.Event()
    sent: list[int] = []

    def spam() -> None:
        n = 0
        while not stop.is_set():
            redirected.error("tick")
            n += 1
        sent.append(n)

    interval = sys.getswitchinterval()
    sys.setswitchinterval(1e-6)  # the two threads take turns as often as they can
    spammer = threading.Thread(target=spam)
    try:
        spammer.start()
        end = time.monotonic() + 2.0
        while time.monotonic() < end:
            with retry_quietly():
                pass
        stop.set()
        spammer.join()
    finally:
        sys.setswitchinterval(interval)
        for (logger, handler), (_, propagate) in zip(loggers, saved, strict=True):
            logger.removeHandler(handler)
            logger.propagate = propagate
    assert (passed.seen, skipped.seen) == (sent[0], 0)


def test_a_dead_link_fails_every_call_at_once_and_only_remembers_subscriptions():
    class Client:
        socket_topics = None

        def __init__(self) -> None:
            self.subs: dict = {}

    client = Client()
    link = SimLink(client)
    link.mark_dead()
    with pytest.raises(SimLinkDead, match=r"^/Sim/X/Hover: the simulator connection is lost$"):
        link.call("/Sim/X/Hover", {}, timeout=5)
    with pytest.raises(SimLinkDead, match=r"^/Sim/x: the simulator connection is lost$"):
        link.publish("/Sim/x", {})
    link.subscribe("/Sim/t", print)
    assert client.subs == {} and not link.probe(0.1)
    link.stop_loop()


def test_a_closed_link_closes_its_request_loop_at_once_and_fails_later_calls():
    class Client:
        socket_topics = None

    link = SimLink(Client())
    link.close()  # a live link, closed on purpose (shutdown, or a replaced link)
    assert link._loop.is_closed()  # its selector and wake-up pipe are closed now, not at collection time
    with pytest.raises(SimLinkDead, match=r"^/Sim/X/Hover: the simulator connection is lost$"):
        link.call("/Sim/X/Hover", {}, timeout=5)
    link.stop_loop()  # a second stop is harmless


def test_a_master_refusal_names_what_was_refused():
    assert _check("publisher", "/a", [1, "ok", 7]) == 7
    with pytest.raises(ReregisterError, match=r"^the master refused to register subscriber /b: nope$"):
        _check("subscriber", "/b", [-1, "nope", 0])


def test_a_master_that_does_not_know_the_node_is_new_even_with_the_same_pid():
    assert needs_registration(known=False, pid=42, last_pid=42)  # a container's restarted master
    assert needs_registration(known=True, pid=43, last_pid=42)
    assert not needs_registration(known=True, pid=42, last_pid=42)
    assert not needs_registration(known=None, pid=None, last_pid=42)  # no answer: nothing to do yet
    assert not needs_registration(known=False, pid=None, last_pid=42)


def test_the_status_topic_lives_under_the_node_name():
    assert status_topic("/bridge") == "/airsim_mapper/bridge/status"


def test_a_mapping_can_only_name_converters_from_the_catalogue():
    with pytest.raises(LookupError, match=r"os\.system"):
        registry.get("os.system")


def test_a_log_budget_logs_so_many_per_period_then_says_how_many_it_held_back(caplog, monkeypatch):
    import logging

    from airsim_mapper.common import logs

    now = [100.0]
    monkeypatch.setattr(logs.time, "monotonic", lambda: now[0])
    budget = logs.RateLimitedLog(logging.getLogger("budget.test"), 10.0, 2, logging.ERROR)
    for index in range(5):
        budget.warn(f"refused {index}")
    now[0] += 10.0
    budget.warn("refused 5")
    assert [r.getMessage() for r in caplog.records] == [
        "refused 0",
        "refused 1",
        "refused 5 (3 more not logged before this one)",
    ]


@pytest.mark.filterwarnings("error::pytest.PytestUnraisableExceptionWarning")
def test_requests_still_waiting_when_the_link_stops_end_before_its_loop_closes(capfd):
    """A frozen simulator leaves requests waiting on NNG; stopping the link cancels them and lets NNG's
    completions reach the loop before it closes (after it, pynng's callback raises on NNG's thread)."""
    import msgpack
    import pynng

    class Client:
        socket_topics = None

        def __init__(self, address: str) -> None:
            self.socket_services = pynng.Req0(dial=address)

        def preprocess_request(self, request: dict) -> bytes:
            return msgpack.packb(request)

    address = f"tcp://127.0.0.1:{free_port()}"
    with pynng.Rep0(listen=address) as silent:  # takes every request, answers none
        client = Client(address)
        link = SimLink(client)
        waiting = [link.call_async("/Sim/Frozen", {}) for _ in range(3)]
        with pytest.raises(SimLinkError, match=r"^/Sim/Frozen: no reply within 0\.2 s$"):
            link.call("/Sim/Frozen", {}, timeout=0.2)
        link.stop_loop()
        assert link._loop.is_closed() and all(future.done() for future in waiting)
        client.socket_services.close()  # any completion still owed would arrive now, to a closed loop
        silent.close()
    time.sleep(0.2)
    assert "Traceback" not in capfd.readouterr().err
