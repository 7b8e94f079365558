"""Simulator liveness: opening a client, backoff between attempts, and deciding that a link is lost.

A server that is killed or restarted closes its TCP connections, which NNG reports as a pipe removal:
the link notices that at once (SimLink.connected), and only then is the link lost (the node reconnects
and reloads the scene). A server that stalls (stopped, swapping, stuck in a long frame) keeps its
connections and its scene; `HealthCheck` then calls it unresponsive after a few unanswered probes in a
row with no topic frame arriving either, and answering again at the first answer or frame after that,
without any reload: reloading would reset the simulation. Frames count as answers because the two
connections recover apart: after a network outage each waits for its own TCP retransmission backoff, and
the topics could flow again for seconds while the probes' connection still waited.

A port that accepts connections but never answers (another program, or a hung simulator) is told apart
from one where nothing listens: `open_client` waits at most `first_answer` seconds for the NNG handshake
and then for the answer to one cheap request, and raises SimSilent if either does not come.
"""

from __future__ import annotations

import contextlib
import logging
import threading
import time
from collections.abc import Callable, Iterator
from dataclasses import dataclass
from typing import Any, Protocol

from airsim_mapper.engine.errors import EngineError

PROBE_PERIOD_S = 0.5
PROBE_TIMEOUT_S = 1.0
PROBE_MISSES = 3
# A topic frame this recent (since about the previous check) shows the simulator runs. A frozen one is
# still found at the PROBE_MISSES-th miss, (PROBE_MISSES - 1) checks after its last frame at the earliest.
FRAMES_FRESH_S = PROBE_TIMEOUT_S + PROBE_PERIOD_S
PROBE_METHOD = "/Sim/GetBuildCommitHash"  # cheap, side-effect free, answered by every server
FIRST_ANSWER_S = 10.0  # a new connection's first answer; NNG's own handshake timeout is also 10 s
PORT_CHECK_S = 0.5  # a refused connection: how long each port is tried, to say which one refused
RETRY_FIRST_S = 0.25
RETRY_STEPS: tuple[tuple[int, float], ...] = (
    (10, 0.5),  # the first ~5 s: a restarted server is found within half a second of listening
    (30, 2.0),  # the next ~40 s
    (1 << 30, 5.0),  # then one attempt (and one log line) per 5 s
)


OK, UNRESPONSIVE, LOST = "ok", "unresponsive", "lost"


@dataclass(frozen=True)
class Verdict:
    """What a health check concluded: OK, UNRESPONSIVE (connection open, no answers) or LOST."""

    kind: str
    reason: str = ""


class SimUnreachable(EngineError, ConnectionError):
    """No simulator answers at an address."""

    def __init__(self, address: str, topicsport: int, servicesport: int, reason: str) -> None:
        super().__init__(f"simulator at {address}:{topicsport}/{servicesport} not reachable ({reason})")


def unreachable_reason(address: str, ports: tuple[int, ...], cause: BaseException) -> str:
    """Why a connection failed, in NNG's words ("Connection refused"), with what it means here: which of
    the ports refused it (a quick TCP connect to each), or that the host name may not resolve."""
    import pynng

    words = str(cause) or type(cause).__name__
    if isinstance(cause, pynng.exceptions.ConnectionRefused) and (closed := closed_ports(address, ports)):
        words += f": {closed}"
    elif isinstance(cause, pynng.exceptions.AddressInvalid):
        words += ": is the address or host name right?"
    return words


def closed_ports(address: str, ports: tuple[int, ...]) -> str:
    """Says "nothing listens on port P" of the ports at `address` that refuse a TCP connection; "" if none
    does."""
    from airsim_mapper.common.ports import accepts_connections

    closed = [str(port) for port in ports if not accepts_connections(address, port, PORT_CHECK_S)]
    return f"nothing listens on port {' or '.join(closed)}" if closed else ""


class SimSilent(SimUnreachable):
    """Something holds the simulator's ports but does not answer: retrying at start would wait forever."""

    def __init__(self, address: str, topicsport: int, servicesport: int, seconds: float) -> None:
        ConnectionError.__init__(
            self,
            f"simulator at {address}:{topicsport}/{servicesport} accepted the connection but did not answer "
            f"within {seconds:g} s: is another program listening on these ports, or is the simulator hung?",
        )


class Probed(Protocol):
    def connected(self) -> bool: ...

    def probe(self, timeout: float) -> bool: ...


def open_client(
    address: str, topicsport: int, servicesport: int, first_answer: float = FIRST_ANSWER_S
) -> Any:
    """A connected ProjectAirSimClient that has answered one request within `first_answer` seconds.
    SimUnreachable when nothing listens, SimSilent when the ports are held but nothing answers (the
    sockets are closed either way)."""
    import pynng
    from projectairsim import ProjectAirSimClient

    from airsim_mapper.engine.receive import close_client

    ports = (topicsport, servicesport)
    client = ProjectAirSimClient(address, topicsport, servicesport)
    try:
        client.connect()
    except pynng.exceptions.Timeout:  # connected, but NNG's handshake never came
        close_client(client)
        raise _silent(address, ports, first_answer) from None
    except Exception as exc:
        close_client(client)
        raise SimUnreachable(address, *ports, unreachable_reason(address, ports, exc)) from None
    if not answered_within(client, first_answer):
        close_client(client)
        raise _silent(address, ports, first_answer)
    return client


CONNECT_LINE = "Connecting to simulation server"  # how the client's connect() announces each attempt


class _QuietConnects(logging.Filter):
    """Drops the client's connect line on the threads that are retrying (`quiet`, per thread)."""

    def __init__(self) -> None:
        super().__init__()
        self.quiet = threading.local()

    def filter(self, record: logging.LogRecord) -> bool:
        return not (getattr(self.quiet, "on", False) and str(record.msg).startswith(CONNECT_LINE))


_QUIET = _QuietConnects()
_QUIET_LOCK = threading.Lock()


@contextlib.contextmanager
def retry_quietly(quiet: bool = True) -> Iterator[None]:
    """While a retry runs on this thread (`quiet`), the client's own "Connecting to simulation server"
    line is left out: the retry logs one line of its own per attempt, not two."""
    logger = logging.getLogger("projectairsim")
    with _QUIET_LOCK:
        if _QUIET not in logger.filters:
            # First, before the wrapper's redirect to rosout (which passes records on); a new list, so that
            # a thread logging meanwhile goes on over the old one.
            logger.filters = [_QUIET, *logger.filters]
    before = getattr(_QUIET.quiet, "on", False)
    _QUIET.quiet.on = quiet or before
    try:
        yield
    finally:
        _QUIET.quiet.on = before


def _silent(address: str, ports: tuple[int, int], seconds: float) -> SimUnreachable:
    """SimSilent, unless one of the ports refuses connections: then the simulator is not (yet) there, and
    the caller retries as for any unreachable one."""
    closed = closed_ports(address, ports)
    return SimUnreachable(address, *ports, closed) if closed else SimSilent(address, *ports, seconds)


def answered_within(client: Any, seconds: float, encode: Callable[[dict], bytes] | None = None) -> bool:
    """Whether the client's server answers one cheap request within `seconds`.

    The request goes out and is awaited on the calling thread, on an NNG context of its own with its own
    timeouts (the socket's, and other requests, are left alone), the reply within what is left of
    `seconds` after the send: a blocking call costs a fraction of a request through the link's asyncio
    loop, which takes several thread hand-offs each way. `encode` makes the request's bytes (the client's
    `preprocess_request`, which numbers requests from a generator: a link that also sends from another
    thread passes its own, locked, encoder)."""
    from airsim_mapper.engine.receive import nng_handles

    _ffi, lib, check_err = nng_handles()
    sock = getattr(client, "socket_services", None)
    if sock is None:
        return False
    deadline = time.monotonic() + seconds
    try:
        ctx = sock.new_context()
    except Exception:
        return False
    try:
        check_err(lib.nng_ctx_set_ms(ctx.context, b"send-timeout", _ms(seconds)))  # NNG_OPT_SENDTIMEO
        request = {"method": PROBE_METHOD, "params": {}, "version": 1.0}
        ctx.send((encode or client.preprocess_request)(request))
        left = _ms(deadline - time.monotonic())
        check_err(lib.nng_ctx_set_ms(ctx.context, b"recv-timeout", left))  # NNG_OPT_RECVTIMEO
        client.postprocess_response(ctx.recv_msg())
    except Exception:
        return False
    finally:
        with contextlib.suppress(Exception):
            ctx.close()
    return True


def _ms(seconds: float) -> int:
    """NNG's duration for a timeout of `seconds`: whole milliseconds, at least one (0 would mean none)."""
    return max(1, int(seconds * 1000))


@dataclass
class Backoff:
    """Delays between attempts: doubling from `first`, capped by the step the attempt count is in."""

    first: float = RETRY_FIRST_S
    steps: tuple[tuple[int, float], ...] = RETRY_STEPS
    attempt: int = 0

    def next_delay(self) -> float:
        cap = next((cap for upto, cap in self.steps if self.attempt < upto), self.steps[-1][1])
        delay = min(self.first * 2 ** min(self.attempt, 16), cap)
        self.attempt += 1
        return delay

    def reset(self) -> None:
        self.attempt = 0


@dataclass
class HealthCheck:
    """Turns per-period observations of a link into a Verdict.

    `frame_age` gives the seconds since the newest topic frame arrived (read after the probe, so that
    frames arriving while it waited count). From the `misses_to_stall`-th missed probe in a row, a frame
    under `frames_fresh` old means no stall: the verdict is OK, with the missed probes as its reason."""

    misses_to_stall: int = PROBE_MISSES
    probe_timeout: float = PROBE_TIMEOUT_S
    frames_fresh: float = FRAMES_FRESH_S
    misses: int = 0

    def check(self, link: Probed, frame_age: Callable[[], float]) -> Verdict:
        if not link.connected():
            return Verdict(LOST, "the simulator closed the connection")
        if link.probe(self.probe_timeout):
            self.misses = 0
            return Verdict(OK)
        self.misses += 1
        if self.misses < self.misses_to_stall:
            return Verdict(OK)
        why = f"no answer to {self.misses} probes of {self.probe_timeout:g} s"
        if frame_age() < self.frames_fresh:
            return Verdict(OK, f"{why}, but topic frames arrive")
        return Verdict(UNRESPONSIVE, f"{why}; the connection is open")

    def reset(self) -> None:
        self.misses = 0
