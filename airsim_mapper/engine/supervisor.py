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
it under the engine's lock, since a loss also stops the bridges' robots and a reconnect swaps the link
the bridges use.
"""

from __future__ import annotations

import math
import threading
import time
from collections.abc import Callable
from typing import TYPE_CHECKING, Any

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
from airsim_mapper.engine.sim_link import close_client
from airsim_mapper.engine.status import CONNECTED, STALE, STOPPED, StatusPublisher
from airsim_mapper.logs import ros_logger

if TYPE_CHECKING:
    from airsim_mapper.engine.engine import Engine

log = ros_logger("airsim_mapper.engine")
WATCHDOG_PERIOD_S = 0.05  # the shortest wait between two checks
WATCHDOG_IDLE_S = 0.5  # the longest
STATUS_PERIOD_S = 1.0
RELOAD_TIMEOUT_S = 20.0  # a reconnect's scene load that takes longer is abandoned (its client closed)


class Supervisor:
    """Watches one engine's simulator link, reconnects it, runs the command watchdog, publishes status."""

    def __init__(self, engine: Engine, client_factory: Callable[[], Any] | None) -> None:
        self.engine = engine
        self.client_factory = client_factory
        self.state = CONNECTED
        self.reason = ""
        self.counters = {"sim_losses": 0, "reconnects": 0, "stalls": 0}
        self.stalled_since: float | None = None  # unresponsive on an open connection since (monotonic)
        self.running = True
        self._stopping = threading.Event()
        self._status = StatusPublisher(engine.ros.publisher, engine.ros_name)
        self._threads = [
            threading.Thread(target=self._watchdog_loop, name="watchdog", daemon=True),
            threading.Thread(target=self._health_loop, name="sim-health", daemon=True),
            threading.Thread(target=self._status_loop, name="status", daemon=True),
        ]

    def start(self) -> None:
        for thread in self._threads:
            thread.start()

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
        engine = self.engine
        if not engine.sim.dead:
            return
        if self.client_factory is not None:
            raise EngineError(f"{what}: the simulator connection is lost; the node is reconnecting")
        engine.sim.stop_loop()  # the mission script's client: its owner says it works again
        engine.swap_link(engine.make_link(engine.client), engine.client, engine.world)
        self.state, self.reason = CONNECTED, ""

    def _health_loop(self) -> None:
        check, backoff = HealthCheck(), Backoff()
        next_attempt = 0.0
        while self.running:
            now = time.monotonic()
            if self.state == CONNECTED or self.stalled_since is not None:
                self.engine.sim.ensure_receiver()
                verdict = check.check(self.engine.sim, self._frame_age)
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
        with self.engine.lock:
            if self.state != CONNECTED:
                return
            self.state, self.reason = STALE, f"unresponsive: {reason}"
            self.stalled_since = time.monotonic()
            self.counters["stalls"] += 1
        log.error("simulator not answering (%s); topics are stale; waiting for it", reason)
        self.publish_status()

    def _frame_age(self) -> float:
        """Seconds since the newest topic frame arrived (infinite before any)."""
        newest = self.engine.hub.newest_arrival()
        return time.monotonic() - newest if newest else math.inf

    def _answering(self, reason: str) -> None:
        """A probe was answered (no `reason`), or topic frames arrive while probes go unanswered (`reason`
        counts them): an unresponsive simulator is back, on the same connection and scene."""
        with self.engine.lock:
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
        engine = self.engine
        with engine.lock:
            if self.state != CONNECTED and self.stalled_since is None:
                return
            self.stalled_since = None
            self.state, self.reason = STALE, reason
            self.counters["sim_losses"] += 1
            for bridge in list(engine.bridges.values()):
                if isinstance(bridge, RosToSim):
                    bridge.moving = False
            if self.client_factory is not None:
                engine.sim.abandon()
            else:
                engine.sim.mark_dead()
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
        scene = engine.scene
        link = engine.make_link(client)  # first, so the scene load already uses its receive loop
        guard = threading.Timer(RELOAD_TIMEOUT_S, close_client, (client,))
        guard.start()
        try:
            world = engine.load_world(client, scene, engine.sim_config_path) if scene else None
        except Exception as exc:
            link.abandon()
            return f"reloading {scene.file if scene else 'the scene'} failed: {type(exc).__name__}: {exc}"
        finally:
            guard.cancel()
        with engine.lock:
            if not self.running or engine.scene is not scene:
                link.abandon()
                return "shutting down" if not self.running else "the scene changed meanwhile"
            old = engine.sim
            engine.mounts.clear()
            engine.swap_link(link, client, world)
            self.state, self.reason = CONNECTED, ""
            self.counters["reconnects"] += 1
        old.stop_loop()
        log.info(
            "simulator back: %s reloaded, %d bridges restored in %.2f s",
            scene.file if scene else "no scene",
            len(engine.bridges),
            time.monotonic() - start,
        )
        self.publish_status()
        return None

    # --- status -----------------------------------------------------------------------------
    def _status_loop(self) -> None:
        while not self._stopping.wait(STATUS_PERIOD_S):
            self.publish_status()

    def status(self) -> dict[str, Any]:
        """The node's state, its counters and the statistics of every simulator stream."""
        engine = self.engine
        now = time.monotonic()
        streams = {
            topic: {
                "received": s.stats.received,
                "dropped": s.stats.dropped,
                "handled": s.stats.handled,
                "errors": s.stats.errors,
                "age_s": round(now - s.stats.last_receive, 3) if s.stats.last_receive else None,
                **s.stats.take_peaks(),
            }
            for topic, s in engine.hub.streams().items()
        }
        errors = {name: b.stats.errors for name, b in list(engine.bridges.items()) if b.stats.errors}
        return {
            "state": self.state,
            "reason": self.reason,
            "scene": engine.scene.file if engine.scene else None,
            **self.counters,
            "bad_frames": engine.frame_counts.bad,
            "oversized_frames": engine.frame_counts.oversized,
            "callback_errors": engine.frame_counts.callback_errors,
            "sim_time_jumps_back": engine.sim_time.jumps_back,
            "sim_time_last_jump_back_s": round(engine.sim_time.last_jump_s, 3),
            "gc_max_ms": engine.gc_pauses.take_peak_ms(),
            "gc_frozen": engine.gc_frozen,  # objects kept out of full collections (freeze_heap)
            "streams": streams,
            "bridge_errors": errors,
            **({"mapping": engine.mapping_report} if engine.mapping_report else {}),
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
            for bridge in list(self.engine.bridges.values()):
                if isinstance(bridge, RosToSim):
                    try:
                        due = bridge.check_watchdog(now)
                    except Exception:
                        log.exception("watchdog of %s failed", bridge.spec.name)
                        continue
                    if due is not None:
                        wait = min(wait, due)
            self._stopping.wait(max(wait, WATCHDOG_PERIOD_S))
