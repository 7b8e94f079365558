"""The engine's supervisor: the simulator's health, reconnection, the command watchdog and the status topic.

Simulator loss (health.py decides; only a closed connection is a loss): the link is abandoned at once
(its calls fail fast, its sockets are closed so a restarted server's single topics connection is free),
the status topic says "stale", and robots are no longer considered moving. A simulator that stops
answering on an open connection, and sends no topic frames either, is only reported stale
("unresponsive") until it answers or sends again: nothing is reloaded, because it still has its scene.
The status topic is published by a thread of its own, at its rate, whatever the simulator does. If the
engine may make clients (`client_factory`), the supervisor reconnects with backoff: a new client, the
last scene reloaded, and the same streams re-subscribed on the new link, so ROS publishers, subscribers
and their peers never notice more than a pause. A client supplied by a mission script is never replaced
behind its owner's back: the engine only reports "stale" until the script loads or adopts a scene again.

The supervisor owns the connection state (`state`, `reason`, `counters`, when a stall began); it changes
it under the engine's lock, which it is given, since a loss also stops the bridges' robots and a reconnect
swaps the link the bridges use. It asks the engine through the methods of `Supervised` only.
"""

from __future__ import annotations

import math
import threading
import time
from collections.abc import Callable
from typing import Any, Protocol

from airsim_mapper.common.logs import ros_logger
from airsim_mapper.engine.errors import EngineError
from airsim_mapper.engine.health import (
    LOST,
    OK,
    PROBE_PERIOD_S,
    Backoff,
    HealthCheck,
    SimUnreachable,
    retry_quietly,
)
from airsim_mapper.engine.ros_to_sim import RosToSim
from airsim_mapper.engine.sim_link import SimLink, close_client
from airsim_mapper.engine.status import CONNECTED, STALE, STOPPED, StatusPublisher
from airsim_mapper.mapping.scene import Scene

log = ros_logger("airsim_mapper.engine")
WATCHDOG_PERIOD_S = 0.05  # the shortest wait between two checks
WATCHDOG_IDLE_S = 0.5  # the longest
STATUS_PERIOD_S = 1.0
RELOAD_TIMEOUT_S = 20.0  # a reconnect's scene load that takes longer is abandoned (its client closed)


class Supervised(Protocol):
    """What the supervisor asks of the engine it watches (core.Engine)."""

    def link(self) -> SimLink: ...
    def scene_now(self) -> Scene | None: ...
    def make_link(self, client: Any) -> SimLink: ...
    def world_on(self, client: Any, scene: Scene) -> Any: ...
    def move_to(self, link: SimLink, client: Any, world: Any) -> SimLink: ...
    def revive_link(self) -> None: ...
    def link_lost(self, abandon: bool) -> None: ...
    def commands(self) -> list[RosToSim]: ...
    def bridge_count(self) -> int: ...
    def newest_arrival(self) -> float: ...
    def report(self) -> dict[str, Any]: ...


class Supervisor:
    """Watches one engine's simulator link, reconnects it, runs the command watchdog, publishes status.

    `lock` is the engine's: the connection state changes with the engine's link and bridges. Construction
    starts nothing; `start` starts the health, watchdog and status threads."""

    def __init__(
        self,
        engine: Supervised,
        lock: threading.RLock,
        client_factory: Callable[[], Any] | None,
        status: StatusPublisher,
    ) -> None:
        self.engine = engine
        self._lock = lock
        self.client_factory = client_factory
        self.state = CONNECTED
        self.reason = ""
        self.counters = {"sim_losses": 0, "reconnects": 0, "stalls": 0}
        self.stalled_since: float | None = None  # unresponsive on an open connection since (monotonic)
        self.running = True
        self._stopping = threading.Event()
        self._status = status

    def start(self) -> None:
        for loop, name in (
            (self._watchdog_loop, "watchdog"),
            (self._health_loop, "sim-health"),
            (self._status_loop, "status"),
        ):
            threading.Thread(target=loop, name=name, daemon=True).start()

    def stop(self) -> None:
        """The loops end (within a probe period); the status publisher stays until `close`."""
        self.running = False
        self._stopping.set()

    def close(self) -> None:
        """Last words: the status says "stopped", then its publisher goes."""
        self.state = STOPPED
        self.publish_status()
        self._status.close()

    # --- the link ---------------------------------------------------------------------------
    def require_link(self, what: str) -> None:
        """Before a scene change (under the engine's lock): a lost link is an error, except a supplied
        client the owner revived."""
        if not self.engine.link().dead:
            return
        if self.client_factory is not None:
            raise EngineError(f"{what}: the simulator connection is lost; the node is reconnecting")
        self.engine.revive_link()  # the mission script's client: its owner says it works again
        self.state, self.reason = CONNECTED, ""

    def _health_loop(self) -> None:
        check, backoff = HealthCheck(), Backoff()
        next_attempt = 0.0
        while self.running:
            now = time.monotonic()
            if self.state == CONNECTED or self.stalled_since is not None:
                link = self.engine.link()
                link.ensure_receiver()
                verdict = check.check(link, self._frame_age)
                if not self.running:
                    break
                if verdict.kind == LOST:
                    self.sim_lost(verdict.reason)
                    check.reset()
                    backoff.reset()
                    next_attempt = time.monotonic() + backoff.next_delay()
                elif verdict.kind == OK:
                    self._answering(verdict.reason)
                else:
                    self._stalled(verdict.reason)
            elif self.client_factory is not None and now >= next_attempt and self.running:
                failure = self._reconnect()
                if failure is None:
                    check.reset()
                    backoff.reset()
                else:
                    attempt, delay = backoff.attempt, backoff.next_delay()
                    next_attempt = time.monotonic() + delay
                    log.warning("reconnect attempt %d: %s; next in %.1f s", attempt, failure, delay)
            wait = PROBE_PERIOD_S
            if self.state != CONNECTED and self.stalled_since is None:
                wait = min(wait, max(0.02, next_attempt - time.monotonic()))
            self._stopping.wait(wait)

    def _stalled(self, reason: str) -> None:
        """The simulator stopped answering on an open connection: stale, but nothing is torn down."""
        with self._lock:
            if self.state != CONNECTED:
                return
            self.state, self.reason = STALE, f"unresponsive: {reason}"
            self.stalled_since = time.monotonic()
            self.counters["stalls"] += 1
        log.error("simulator not answering (%s); topics are stale; waiting for it", reason)
        self.publish_status()

    def _frame_age(self) -> float:
        """Seconds since the newest topic frame arrived (infinite before any)."""
        newest = self.engine.newest_arrival()
        return time.monotonic() - newest if newest else math.inf

    def _answering(self, reason: str) -> None:
        """A probe was answered (no `reason`), or topic frames arrive while probes go unanswered (`reason`
        counts them): an unresponsive simulator is back, on the same connection and scene."""
        with self._lock:
            if self.state != CONNECTED and self.stalled_since is None:
                return  # lost: only a reconnect brings it back
            since, before = self.stalled_since, self.reason
            self.stalled_since = None
            self.state, self.reason = CONNECTED, reason
        if since is not None:
            log.warning(
                "simulator answers again after %.1f s (%s); its scene kept running, nothing reloaded",
                time.monotonic() - since,
                "its topic frames arrive; its probes not yet" if reason else "a probe was answered",
            )
        elif bool(reason) == bool(before):
            return  # no news: the status loop sends the count
        elif reason:
            log.warning("simulator sends topic frames but answers no requests (%s)", reason)
        else:
            log.warning("simulator answers requests again")
        self.publish_status()

    def sim_lost(self, reason: str) -> None:
        """Mark the link lost: nothing more is sent on it; robots are no longer driven."""
        with self._lock:
            if self.state != CONNECTED and self.stalled_since is None:
                return
            self.stalled_since = None
            self.state, self.reason = STALE, reason
            self.counters["sim_losses"] += 1
            self.engine.link_lost(abandon=self.client_factory is not None)
        how = "reconnecting" if self.client_factory is not None else "the mission script owns the client"
        log.error("simulator lost (%s); topics are stale; %s", reason, how)
        self.publish_status()

    def _reconnect(self) -> str | None:
        """One attempt: new client, last scene reloaded, streams moved over. None on success, else why not.

        The scene is loaded on the new client before anything is swapped, without the engine's lock, so a
        slow simulator never holds up status, scene requests or shutdown."""
        engine = self.engine
        try:
            with retry_quietly():
                client = self.client_factory()
        except SimUnreachable as exc:
            return str(exc)
        start = time.monotonic()
        scene = engine.scene_now()
        link = engine.make_link(client)  # first, so the scene load already uses its receive loop
        guard = threading.Timer(RELOAD_TIMEOUT_S, close_client, (client,))
        guard.start()
        try:
            world = engine.world_on(client, scene) if scene else None
        except Exception as exc:
            link.abandon()
            return f"reloading {scene.file if scene else 'the scene'} failed: {type(exc).__name__}: {exc}"
        finally:
            guard.cancel()
        with self._lock:
            if not self.running or engine.scene_now() is not scene:
                link.abandon()
                return "shutting down" if not self.running else "the scene changed meanwhile"
            old = engine.move_to(link, client, world)
            self.state, self.reason = CONNECTED, ""
            self.counters["reconnects"] += 1
        old.stop_loop()
        log.info(
            "simulator back: %s reloaded, %d bridges restored in %.2f s",
            scene.file if scene else "no scene",
            engine.bridge_count(),
            time.monotonic() - start,
        )
        self.publish_status()
        return None

    # --- status -----------------------------------------------------------------------------
    def _status_loop(self) -> None:
        while not self._stopping.wait(STATUS_PERIOD_S):
            self.publish_status()

    def status(self) -> dict[str, Any]:
        """The node's state, its counters and the engine's report (the scene, every simulator stream's
        statistics, ...)."""
        report = self.engine.report()
        return {
            "state": self.state,
            "reason": self.reason,
            "scene": report["scene"],
            **self.counters,
            **report,
        }

    def publish_status(self) -> None:
        status = self.status()
        try:
            self._status.publish(status)
        except Exception as exc:  # rospy shutting down
            log.debug("status not published: %s", exc)

    # --- watchdog ---------------------------------------------------------------------------
    def _watchdog_loop(self) -> None:
        """Check the command watchdogs when one can be due: at its deadline while commands flow, at most
        WATCHDOG_IDLE_S apart otherwise (a new command is due no sooner than its `watchdog_s`)."""
        while self.running:
            now = time.monotonic()
            wait = WATCHDOG_IDLE_S
            for command in self.engine.commands():
                try:
                    due = command.check_watchdog(now)
                except Exception:
                    log.exception("watchdog of %s failed", command.spec.name)
                    continue
                if due is not None:
                    wait = min(wait, due)
            self._stopping.wait(max(wait, WATCHDOG_PERIOD_S))
