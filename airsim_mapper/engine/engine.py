"""The engine: runs the bridges of a mapping for the current scene, and follows scene changes.

Data flows one way: scene + mapping --expand--> BridgeSpecs --build--> runners wired to the sim link and
the ROS link. A scene change tears the scene's runners down and builds the new scene's; bridges that do
not depend on the scene (load_scene itself) keep running.

Simulator loss (health.py decides): the link is abandoned at once (its calls fail fast, its sockets are
closed so a restarted server's single topics connection is free), the status topic says "stale", and
robots are no longer considered moving. If the engine may make clients (`client_factory`), it reconnects
with backoff: a new client, the last scene reloaded, and the same streams re-subscribed on the new link,
so ROS publishers, subscribers and their peers never notice more than a pause. A client supplied by a
mission script is never replaced behind its owner's back: the engine only reports "stale" until the
script loads or adopts a scene again.
"""

from __future__ import annotations

import gc
import logging
import queue
import threading
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

from airsim_mapper.engine.bridges import Bridge, RosToSim, Services, StreamingImage, build
from airsim_mapper.engine.health import PROBE_PERIOD_S, Backoff, HealthCheck, SimUnreachable
from airsim_mapper.engine.hub import StreamHub
from airsim_mapper.engine.realtime import GcPauses, freeze_heap, thaw_heap, tune_process
from airsim_mapper.engine.ros_link import TfBroadcaster
from airsim_mapper.engine.sim_link import SimLink, close_client
from airsim_mapper.engine.status import CONNECTED, STALE, STOPPED, StatusPublisher
from airsim_mapper.mapping.errors import ConfigError
from airsim_mapper.mapping.expand import expand
from airsim_mapper.mapping.model import BridgeSpec, Mapping
from airsim_mapper.scene import Scene, read_scene

log = logging.getLogger("rosout.airsim_mapper.engine")
WATCHDOG_PERIOD_S = 0.05
STATUS_PERIOD_S = 1.0
RELOAD_TIMEOUT_S = 20.0  # a reconnect's scene load that takes longer is abandoned (its client closed)


class EngineError(RuntimeError):
    """The engine cannot do what was asked right now (the message says why)."""


class Engine:
    """Owns the runners of one node: builds them from specs, reloads them on scene changes."""

    def __init__(
        self,
        client: Any,
        mapping: Mapping,
        sim_config_path: str | Path,
        node_name: str,
        namespace: str = "",
        load_world: Callable[[Any, str, str], Any] | None = None,
        client_factory: Callable[[], Any] | None = None,
    ) -> None:
        tune_process()
        self.gc_pauses = GcPauses()
        self.gc_frozen = 0
        self.client = client
        self.mapping = mapping
        self.sim_config_path = str(sim_config_path)
        self.node_name = node_name
        self.namespace = namespace
        self.sim = SimLink(client)
        self.tf = TfBroadcaster()
        self.hub = StreamHub(self.sim, self.tf.send)
        self.shared: dict[Any, Any] = {}
        self.services = Services(self.sim, self.hub, self.tf, self.shared, self._node_action)
        self.bridges: dict[str, Bridge] = {}
        self.scene: Scene | None = None
        self.world: Any = None
        self._load_world = load_world or _load_world
        self._lock = threading.RLock()
        self._scene_requests: queue.Queue[str | None] = queue.Queue()
        self._running = True
        self._client_factory = client_factory
        self.state = CONNECTED
        self.reason = ""
        self.counters = {"sim_losses": 0, "reconnects": 0}
        self._stopping = threading.Event()
        self._status = StatusPublisher(node_name)
        self._status_hooks: list[Callable[[dict], None]] = []
        self._threads = [
            threading.Thread(target=self._watchdog_loop, name="watchdog", daemon=True),
            threading.Thread(target=self._scene_loop, name="scene-loader", daemon=True),
            threading.Thread(target=self._health_loop, name="sim-health", daemon=True),
        ]
        for thread in self._threads:
            thread.start()

    # --- building ---------------------------------------------------------------------------
    def specs_for(self, scene: Scene) -> tuple[BridgeSpec, ...]:
        return expand(self.mapping, scene, self.node_name, self.namespace)

    def apply(self, scene: Scene) -> tuple[BridgeSpec, ...]:
        """Run exactly the bridges of `scene`: stop the old scene's, start the new ones."""
        specs = self.specs_for(scene)
        with self._lock:
            self._stop_scene_bridges(keep={s.name: s for s in specs})
            thaw_heap()  # the old scene's bridges are garbage now: let the collector see them again
            self.scene = scene
            self.shared.clear()
            streaming: list[StreamingImage] = [
                b for b in self.bridges.values() if isinstance(b, StreamingImage)
            ]
            for spec in specs:
                if spec.name in self.bridges:
                    continue
                bridge = build(spec, self.services, streaming)
                bridge.start()
                self.bridges[spec.name] = bridge
            took_ms = freeze_heap()
            self.gc_frozen = gc.get_freeze_count()  # counted here once: counting walks every frozen object
            log.debug("heap frozen in %.1f ms (%d objects)", took_ms, self.gc_frozen)
        return specs

    def _stop_scene_bridges(self, keep: dict[str, BridgeSpec]) -> None:
        """Stop every bridge except scene-independent ones whose spec is unchanged."""
        for name, bridge in list(self.bridges.items()):
            spec = keep.get(name)
            if spec is not None and spec == bridge.spec and _scene_independent(spec):
                continue
            try:
                bridge.stop()
            except Exception:
                log.exception("stopping %s failed", name)
            del self.bridges[name]

    # --- scenes -----------------------------------------------------------------------------
    def load_scene(self, scene_file: str) -> Scene:
        """Validate, load into the simulator, and re-bridge. On any error the current scene stays."""
        scene = read_scene(self.sim_config_path, scene_file)  # path and config checks first
        self.specs_for(scene)  # the mapping must expand for it before anything is torn down
        with self._lock:
            self._require_link(f"load_scene {scene_file}")
            self._stop_scene_bridges(keep={})
            self.hub.drop_all()
            self.sim.forget_all()
            try:
                self.world = self._load_world(self.client, scene_file, self.sim_config_path)
            except Exception:
                if self.scene is not None:
                    log.error("loading %s failed; restoring the bridges of %s", scene_file, self.scene.file)
                    self.apply(self.scene)
                raise
            self.apply(scene)
        log.info("scene %s (%s) loaded: %d bridges", scene.name, scene_file, len(self.bridges))
        return scene

    def adopt(self, scene: Scene, world: Any = None) -> None:
        """A mission script loaded `scene` itself: its load cleared every subscription, so re-bridge."""
        with self._lock:
            self._require_link("adopt")
            self._stop_scene_bridges(keep={})
            self.hub.drop_all()
            self.sim.forget_all()
            self.world = world
            self.apply(scene)

    def request_scene(self, scene_file: str) -> None:
        """Queue a scene load (from a ROS callback); it runs on the scene-loader thread."""
        self._scene_requests.put(scene_file)

    def _scene_loop(self) -> None:
        while True:
            scene_file = self._scene_requests.get()
            if scene_file is None:
                return
            try:
                self.load_scene(scene_file)
            except ConfigError as exc:
                log.error("load_scene %r refused; the current scene stays:\n%s", scene_file, exc)
            except Exception as exc:
                log.error("load_scene %r failed: %s", scene_file, exc)

    def _node_action(self, spec: BridgeSpec, params: dict) -> None:
        if spec.converter == "load_scene":
            self.request_scene(params["scene"])
        else:
            raise ValueError(f"{spec.name}: converter {spec.converter!r} has no engine action")

    # --- simulator health and reconnection ---------------------------------------------------
    def _require_link(self, what: str) -> None:
        """Before a scene change: a lost link is an error, except a supplied client the owner revived."""
        if not self.sim.dead:
            return
        if self._client_factory is not None:
            raise EngineError(f"{what}: the simulator connection is lost; the node is reconnecting")
        self.sim.stop_loop()  # the mission script's client: its owner says it works again
        self._swap_link(SimLink(self.client), self.client, self.world)

    def _swap_link(self, link: SimLink, client: Any, world: Any) -> None:
        self.client, self.sim, self.services.sim, self.world = client, link, link, world
        self.hub.rebind(link)
        self.state, self.reason = CONNECTED, ""

    def _health_loop(self) -> None:
        check, backoff = HealthCheck(), Backoff()
        next_attempt = next_status = 0.0
        while self._running:
            now = time.monotonic()
            if self.state == CONNECTED:
                self.sim.ensure_receiver()
                reason = check.check(self.sim)
                if reason is not None and self._running:
                    self.sim_lost(reason)
                    backoff.reset()
                    next_attempt = time.monotonic() + backoff.next_delay()
                    next_status = 0.0
            elif self._client_factory is not None and now >= next_attempt and self._running:
                failure = self._reconnect()
                if failure is None:
                    check.reset()
                    backoff.reset()
                    next_status = 0.0
                else:
                    attempt, delay = backoff.attempt, backoff.next_delay()
                    next_attempt = time.monotonic() + delay
                    log.warning("reconnect attempt %d: %s; next in %.1f s", attempt, failure, delay)
            if time.monotonic() >= next_status:
                self.publish_status()
                next_status = time.monotonic() + STATUS_PERIOD_S
            wait = PROBE_PERIOD_S
            if self.state != CONNECTED:
                wait = min(wait, max(0.02, next_attempt - time.monotonic()))
            self._stopping.wait(wait)

    def sim_lost(self, reason: str) -> None:
        """Mark the link lost: nothing more is sent on it; robots are no longer driven."""
        with self._lock:
            if self.state != CONNECTED:
                return
            self.state, self.reason = STALE, reason
            self.counters["sim_losses"] += 1
            for bridge in list(self.bridges.values()):
                if isinstance(bridge, RosToSim):
                    bridge.moving = False
            if self._client_factory is not None:
                self.sim.abandon()
            else:
                self.sim.mark_dead()
        how = "reconnecting" if self._client_factory is not None else "the mission script owns the client"
        log.error("simulator lost (%s); topics are stale; %s", reason, how)
        self.publish_status()

    def _reconnect(self) -> str | None:
        """One attempt: new client, last scene reloaded, streams moved over. None on success, else why not."""
        try:
            client = self._client_factory()
        except SimUnreachable as exc:
            return str(exc)
        start = time.monotonic()
        with self._lock:
            if not self._running:
                close_client(client)
                return "shutting down"
            scene = self.scene
            link = SimLink(client)  # first, so the scene load already uses the link's receive loop
            guard = threading.Timer(RELOAD_TIMEOUT_S, close_client, (client,))
            guard.start()
            try:
                world = self._load_world(client, scene.file, self.sim_config_path) if scene else None
            except Exception as exc:
                link.abandon()
                return f"reloading {scene.file if scene else 'the scene'} failed: {type(exc).__name__}: {exc}"
            finally:
                guard.cancel()
            old = self.sim
            self.shared.clear()
            self._swap_link(link, client, world)
            self.counters["reconnects"] += 1
        old.stop_loop()
        log.info(
            "simulator back: %s reloaded, %d bridges restored in %.2f s",
            scene.file if scene else "no scene",
            len(self.bridges),
            time.monotonic() - start,
        )
        self.publish_status()
        return None

    # --- status -----------------------------------------------------------------------------
    def add_status_hook(self, hook: Callable[[dict], None]) -> None:
        """Call `hook(status)` whenever the status is published (diagnostics, tests)."""
        self._status_hooks.append(hook)

    def status(self) -> dict[str, Any]:
        """The node's state, its counters and the statistics of every simulator stream."""
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
            for topic, s in self.hub.streams().items()
        }
        errors = {name: b.stats.errors for name, b in list(self.bridges.items()) if b.stats.errors}
        return {
            "state": self.state,
            "reason": self.reason,
            "scene": self.scene.file if self.scene else None,
            **self.counters,
            "bad_frames": self.sim.bad_frames,
            "gc_max_ms": self.gc_pauses.take_peak_ms(),
            "gc_frozen": self.gc_frozen,  # objects kept out of full collections (freeze_heap)
            "streams": streams,
            "bridge_errors": errors,
        }

    def publish_status(self) -> None:
        status = self.status()
        try:
            self._status.publish(status)
        except Exception as exc:  # rospy shutting down
            log.debug("status not published: %s", exc)
        for hook in list(self._status_hooks):
            try:
                hook(status)
            except Exception:
                log.exception("status hook failed")

    # --- watchdog and shutdown --------------------------------------------------------------
    def _watchdog_loop(self) -> None:
        while self._running:
            now = time.monotonic()
            for bridge in list(self.bridges.values()):
                if isinstance(bridge, RosToSim):
                    try:
                        bridge.check_watchdog(now)
                    except Exception:
                        log.exception("watchdog of %s failed", bridge.spec.name)
            time.sleep(WATCHDOG_PERIOD_S)

    def shutdown(self) -> None:
        """Stop every bridge (robots with a running velocity command are stopped) and the link."""
        self._running = False
        self._stopping.set()
        self._scene_requests.put(None)
        with self._lock:
            for name, bridge in list(self.bridges.items()):
                try:
                    bridge.stop()
                except Exception:
                    log.exception("stopping %s failed", name)
            self.bridges.clear()
        time.sleep(0.1)  # let the last stop commands leave
        self.sim.close()
        self.hub.drop_all()
        self.state = STOPPED
        self.publish_status()
        self._status.close()
        self.gc_pauses.close()


def _scene_independent(spec: BridgeSpec) -> bool:
    return "scene_name" not in spec.variables


def _load_world(client: Any, scene_file: str, sim_config_path: str) -> Any:
    from projectairsim import World

    return World(client, scene_file, sim_config_path=sim_config_path.rstrip("/") + "/")
