"""The engine: runs the bridges of a mapping for the current scene, and follows scene changes.

Data flows one way: scene + mapping --expand--> BridgeSpecs --build--> runners wired to the sim link and
the ROS link. The node's own bridges (load_scene) start before any scene (`start_node_bridges`) and keep
running, untouched, across scene changes; a scene change tears the scene's runners down and builds the new
scene's.

Simulator loss (health.py decides; only a closed connection is a loss): the link is abandoned at once
(its calls fail fast, its sockets are closed so a restarted server's single topics connection is free),
the status topic says "stale", and robots are no longer considered moving. A simulator that stops
answering on an open connection is only reported stale ("unresponsive") until it answers again: nothing
is reloaded, because it still has its scene. The status topic is published by a thread of its own, at
its rate, whatever the simulator does. If the engine may make clients (`client_factory`), it reconnects
with backoff: a new client, the last scene reloaded, and the same streams re-subscribed on the new link,
so ROS publishers, subscribers and their peers never notice more than a pause. A client supplied by a
mission script is never replaced behind its owner's back: the engine only reports "stale" until the
script loads or adopts a scene again.
"""

from __future__ import annotations

import contextlib
import copy
import functools
import gc
import logging
import queue
import threading
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

from airsim_mapper.convert.command import shorten
from airsim_mapper.engine.bridges import Bridge, RosToSim, Services, Throttled, build
from airsim_mapper.engine.health import LOST, OK, PROBE_PERIOD_S, Backoff, HealthCheck, SimUnreachable
from airsim_mapper.engine.hub import StreamHub
from airsim_mapper.engine.realtime import GcPauses, freeze_heap, thaw_heap, tune_process
from airsim_mapper.engine.ros_link import RosLink
from airsim_mapper.engine.sim_link import FrameCounts, SimLink, close_client
from airsim_mapper.engine.simtime import SimTimeWatch
from airsim_mapper.engine.status import CONNECTED, STALE, STOPPED, StatusPublisher
from airsim_mapper.mapping.diff import BridgeDiff, bridge_diff
from airsim_mapper.mapping.errors import ConfigError
from airsim_mapper.mapping.expand import expand
from airsim_mapper.mapping.model import BridgeSpec, Mapping
from airsim_mapper.ros_log import ros_logger
from airsim_mapper.scene import Scene, read_scene

log = ros_logger("airsim_mapper.engine")
WATCHDOG_PERIOD_S = 0.05
STATUS_PERIOD_S = 1.0
RELOAD_TIMEOUT_S = 20.0  # a reconnect's scene load that takes longer is abandoned (its client closed)
MAX_QUEUED_SCENES = 8  # load_scene requests waiting for the scene-loader thread
REFUSALS_LOGGED, REFUSALS_PERIOD_S = 10, 10.0  # at most this many refused loads logged per period
SHOWN_LINE = 300  # characters of an error line a refusal log shows
SHUTDOWN_TIMEOUT_S = 5.0  # shutdown's total budget; the simulator gets at most UNSUBSCRIBE_TIMEOUT_S of it
UNSUBSCRIBE_TIMEOUT_S = 2.0


class EngineError(RuntimeError):
    """The engine cannot do what was asked right now (the message says why)."""


class LogBudget:
    """Warnings limited to `count` per `period` seconds; the next one logged says how many were held back."""

    def __init__(self, logger: logging.Logger, count: int, period: float) -> None:
        self.logger, self.count, self.period = logger, count, period
        self._window_start = -1e9
        self._logged = 0
        self._held = 0
        self._lock = threading.Lock()

    def warn(self, message: str) -> None:
        with self._lock:
            now = time.monotonic()
            if now - self._window_start >= self.period:
                self._window_start, self._logged = now, 0
            if self._logged >= self.count:
                self._held += 1
                return
            self._logged += 1
            held, self._held = self._held, 0
        suffix = f" ({held} more not logged before this one)" if held else ""
        self.logger.error("%s%s", message, suffix)


class Engine:
    """Owns the runners of one node: builds them from specs, reloads them on scene changes."""

    def __init__(
        self,
        client: Any,
        mapping: Mapping,
        sim_config_path: str | Path,
        node_name: str,
        namespace: str = "",
        load_world: Callable[[Any, Scene, str], Any] | None = None,
        client_factory: Callable[[], Any] | None = None,
        tune: bool = False,
        ros: RosLink | None = None,
        link: Callable[[Any, FrameCounts], SimLink] = SimLink,
        frame_counts: FrameCounts | None = None,
    ) -> None:
        if tune:
            tune_process()
        self._freeze_heap = tune  # gc.freeze is process-wide: only for a process that asked for tuning
        self.gc_pauses = GcPauses()
        self.gc_frozen = 0
        self.client = client
        self.mapping = mapping
        self.sim_config_path = str(sim_config_path)
        self.node_name = node_name
        self.namespace = namespace
        self.frame_counts = frame_counts or FrameCounts()  # kept across reconnects
        self._link = link
        self.sim = link(client, self.frame_counts)
        self.ros = ros or RosLink()
        self.hub = StreamHub(self.sim, self.ros.send_tf)
        self.shared: dict[Any, Any] = {}
        self.sim_time = SimTimeWatch(warn=Throttled("sim time").warn)
        self.services = Services(
            self.sim,
            self.hub,
            self.ros,
            self.shared,
            self._node_action,
            counts=self.frame_counts,
            sim_time=self.sim_time,
        )
        self.bridges: dict[str, Bridge] = {}
        self._refused: dict[str, str] = {}  # bridges that could not start (ROS refused them): name -> why
        self.scene: Scene | None = None
        self.world: Any = None
        self._load_world = load_world or _load_world
        self._lock = threading.RLock()
        self._scene_requests: queue.Queue[str | None] = queue.Queue(MAX_QUEUED_SCENES)
        self._loading: str | None = None  # the scene file being loaded by the scene-loader thread
        self._refusals = LogBudget(log, REFUSALS_LOGGED, REFUSALS_PERIOD_S)
        self._running = True
        self._client_factory = client_factory
        self.state = CONNECTED
        self.reason = ""
        self.counters = {"sim_losses": 0, "reconnects": 0, "stalls": 0}
        self.mapping_report: dict[str, Any] = {}  # live reload's state (engine/mapping_reload.py)
        self._stalled_since: float | None = None  # unresponsive on an open connection since (monotonic)
        self._stopping = threading.Event()
        self._status = StatusPublisher(self.ros, node_name)
        self._threads = [
            threading.Thread(target=self._watchdog_loop, name="watchdog", daemon=True),
            threading.Thread(target=self._scene_loop, name="scene-loader", daemon=True),
            threading.Thread(target=self._health_loop, name="sim-health", daemon=True),
            threading.Thread(target=self._status_loop, name="status", daemon=True),
        ]
        for thread in self._threads:
            thread.start()

    # --- building ---------------------------------------------------------------------------
    def specs_for(self, scene: Scene | None) -> tuple[BridgeSpec, ...]:
        """The bridges of `scene`, or the node's own (load_scene) without one."""
        return expand(self.mapping, scene, self.node_name, self.namespace)

    def start_node_bridges(self) -> tuple[BridgeSpec, ...]:
        """Before any scene: run the node's own bridges, so a scene can be loaded over ROS."""
        with self._lock:
            if self.scene is not None:
                return tuple(b.spec for b in self.bridges.values())
            return self.apply(None)

    def apply(
        self, scene: Scene | None, specs: tuple[BridgeSpec, ...] | None = None
    ) -> tuple[BridgeSpec, ...]:
        """Run exactly the bridges of `scene` (its `specs`, when already expanded): stop the old scene's,
        start the new ones."""
        specs = self.specs_for(scene) if specs is None else specs
        with self._lock:
            self._stop_scene_bridges(keep={s.name: s for s in specs})
            if self._freeze_heap:
                thaw_heap()  # the old scene's bridges are garbage now: let the collector see them again
            self.scene = scene
            self.shared.clear()
            self._start_bridges(specs, {s.name for s in specs} - set(self.bridges))
            if self._freeze_heap:
                took_ms = freeze_heap()
                self.gc_frozen = gc.get_freeze_count()  # counted once here: counting walks every object
                log.debug("heap frozen in %.1f ms (%d objects)", took_ms, self.gc_frozen)
        return specs

    def _start_bridges(self, specs: tuple[BridgeSpec, ...], names: set[str]) -> None:
        """Start the bridges of `specs` named in `names`, keeping `self.bridges` in the order of `specs`.
        A bridge that cannot start (ROS refuses a name, say) is logged with its reason, left out and kept in
        `refused_bridges()`; the others start."""
        wanted = {s.name for s in specs}
        self._refused = {n: why for n, why in self._refused.items() if n in wanted and n not in names}
        for spec in specs:
            if spec.name not in names:
                continue
            try:
                bridge = build(spec, self.services)
                bridge.start()
            except Exception as exc:
                self._refused[spec.name] = f"{type(exc).__name__}: {exc}"
                log.error("bridge %s could not start and stays off: %s", spec.name, self._refused[spec.name])
                continue
            self.bridges[spec.name] = bridge
        self.bridges = {s.name: self.bridges[s.name] for s in specs if s.name in self.bridges}

    def refused_bridges(self) -> dict[str, str]:
        """The bridges of the running mapping that could not start, with why (for /diagnostics, reloads)."""
        with self._lock:
            return dict(self._refused)

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

    # --- mappings ---------------------------------------------------------------------------
    def apply_mapping(self, mapping: Mapping) -> BridgeDiff:
        """Run `mapping` instead of the current one, touching only what differs: bridges whose expanded
        spec is unchanged keep running (their publishers, subscribers and simulator subscriptions), removed
        and changed ones stop, new and changed ones start. Without a scene that is the node's own bridges.
        MappingError (nothing changed) when `mapping` does not expand over the running scene."""
        with self._lock:
            specs = expand(mapping, self.scene, self.node_name, self.namespace)
            diff = bridge_diff((b.spec for b in self.bridges.values()), specs)
            self.mapping = mapping
            for name in (*diff.removed, *diff.changed):
                try:
                    self.bridges.pop(name).stop()
                except Exception:
                    log.exception("stopping %s failed", name)
            self._start_bridges(specs, {*diff.added, *diff.changed})
            if self._freeze_heap:
                # No full collection here (freeze_heap's would stop every running bridge for tens of ms):
                # the new objects join the frozen heap as they are; the stopped bridges' cycles stay.
                gc.freeze()
                self.gc_frozen = gc.get_freeze_count()
        return diff

    # --- scenes -----------------------------------------------------------------------------
    def load_scene(self, scene_file: str | Scene, specs: tuple[BridgeSpec, ...] | None = None) -> Scene:
        """Validate, load into the simulator, and re-bridge. On any error the current scene stays.

        A Scene already read (and its specs, expanded for this engine's node name and namespace) is used
        as it is: the node reads and expands once at start-up and hands the result on.
        """
        if isinstance(scene_file, Scene):
            scene, scene_file = scene_file, scene_file.file
        else:
            scene = read_scene(self.sim_config_path, scene_file)  # path and config checks first
        # The mapping must expand for the scene before anything is torn down.
        specs = self.specs_for(scene) if specs is None else specs
        with self._lock:
            self._require_link(f"load_scene {scene_file}")
            self._stop_scene_bridges(keep={s.name: s for s in specs})  # the node's own bridges stay
            self.hub.drop_all()
            self.sim.forget_all()
            try:
                self.world = self._load_world(self.client, scene, self.sim_config_path)
            except Exception:
                if self.scene is not None:
                    log.error("loading %s failed; restoring the bridges of %s", scene_file, self.scene.file)
                    self.apply(self.scene)
                raise
            self.apply(scene, specs)
        log.info("scene %s (%s) loaded: %d bridges", scene.name, scene_file, len(self.bridges))
        return scene

    def adopt(self, scene: Scene, world: Any = None) -> None:
        """A mission script loaded `scene` itself: its load cleared every subscription, so re-bridge."""
        specs = self.specs_for(scene)
        with self._lock:
            self._require_link("adopt")
            self._stop_scene_bridges(keep={s.name: s for s in specs})  # the node's own bridges stay
            self.hub.drop_all()
            self.sim.forget_all()
            self.world = world
            self.apply(scene, specs)

    def request_scene(self, scene_file: str) -> None:
        """Queue a scene load (from a ROS callback); it runs on the scene-loader thread. At most
        MAX_QUEUED_SCENES wait; a request beyond that is refused (EngineError) and logged."""
        loading = self._loading
        try:
            self._scene_requests.put_nowait(scene_file)
        except queue.Full:
            self._refusals.warn(
                f"load_scene {shorten(scene_file)!r} refused: {MAX_QUEUED_SCENES} loads are already waiting"
                + (f" behind {shorten(loading)!r}" if loading else "")
            )
            raise EngineError(f"{MAX_QUEUED_SCENES} scene loads are already waiting") from None
        if loading is not None:
            log.info(
                "load_scene %r queued behind %r (%d waiting)",
                shorten(scene_file),
                shorten(loading),
                self._scene_requests.qsize(),
            )

    def _scene_loop(self) -> None:
        while True:
            scene_file = self._scene_requests.get()
            if scene_file is None or not self._running:
                return
            self._loading = scene_file
            try:
                self.load_scene(scene_file)
            except ConfigError as exc:
                report = "\n".join(shorten(line, SHOWN_LINE) for line in str(exc).splitlines())
                self._refusals.warn(
                    f"load_scene {shorten(scene_file)!r} refused; the current scene stays:\n{report}"
                )
            except Exception as exc:
                self._refusals.warn(
                    f"load_scene {shorten(scene_file)!r} failed: {shorten(str(exc), SHOWN_LINE)}"
                )
            finally:
                self._loading = None

    def _node_action(self, action: str, params: dict) -> None:
        """An engine action a bridge asked for, by the name the converter catalogue gives it."""
        actions: dict[str, Callable[[dict], Any]] = {"load_scene": lambda p: self.request_scene(p["scene"])}
        if action not in actions:
            raise ValueError(f"the engine has no action {action!r}")
        actions[action](params)

    # --- simulator health and reconnection ---------------------------------------------------
    def _require_link(self, what: str) -> None:
        """Before a scene change: a lost link is an error, except a supplied client the owner revived."""
        if not self.sim.dead:
            return
        if self._client_factory is not None:
            raise EngineError(f"{what}: the simulator connection is lost; the node is reconnecting")
        self.sim.stop_loop()  # the mission script's client: its owner says it works again
        self._swap_link(self._link(self.client, self.frame_counts), self.client, self.world)

    def _swap_link(self, link: SimLink, client: Any, world: Any) -> None:
        self.client, self.sim, self.services.sim, self.world = client, link, link, world
        self.hub.rebind(link)
        self.state, self.reason = CONNECTED, ""

    def _health_loop(self) -> None:
        check, backoff = HealthCheck(), Backoff()
        next_attempt = 0.0
        while self._running:
            now = time.monotonic()
            if self.state == CONNECTED or self._stalled_since is not None:
                self.sim.ensure_receiver()
                verdict = check.check(self.sim)
                if not self._running:
                    break
                if verdict.kind == LOST:
                    self.sim_lost(verdict.reason)
                    backoff.reset()
                    next_attempt = time.monotonic() + backoff.next_delay()
                elif verdict.kind == OK:
                    self._answering()
                else:
                    self._stalled(verdict.reason)
            elif self._client_factory is not None and now >= next_attempt and self._running:
                failure = self._reconnect()
                if failure is None:
                    check.reset()
                    backoff.reset()
                else:
                    attempt, delay = backoff.attempt, backoff.next_delay()
                    next_attempt = time.monotonic() + delay
                    log.warning("reconnect attempt %d: %s; next in %.1f s", attempt, failure, delay)
            wait = PROBE_PERIOD_S
            if self.state != CONNECTED and self._stalled_since is None:
                wait = min(wait, max(0.02, next_attempt - time.monotonic()))
            self._stopping.wait(wait)

    def _status_loop(self) -> None:
        while not self._stopping.wait(STATUS_PERIOD_S):
            self.publish_status()

    def _stalled(self, reason: str) -> None:
        """The simulator stopped answering on an open connection: stale, but nothing is torn down."""
        with self._lock:
            if self.state != CONNECTED:
                return
            self.state, self.reason = STALE, f"unresponsive: {reason}"
            self._stalled_since = time.monotonic()
            self.counters["stalls"] += 1
        log.error("simulator not answering (%s); topics are stale; waiting for it", reason)
        self.publish_status()

    def _answering(self) -> None:
        """A probe was answered: an unresponsive simulator is back, on the same connection and scene."""
        with self._lock:
            since = self._stalled_since
            if since is None:
                return
            self._stalled_since = None
            self.state, self.reason = CONNECTED, ""
        log.warning(
            "simulator answers again after %.1f s; its scene kept running, nothing reloaded",
            time.monotonic() - since,
        )
        self.publish_status()

    def sim_lost(self, reason: str) -> None:
        """Mark the link lost: nothing more is sent on it; robots are no longer driven."""
        with self._lock:
            if self.state != CONNECTED and self._stalled_since is None:
                return
            self._stalled_since = None
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
        """One attempt: new client, last scene reloaded, streams moved over. None on success, else why not.

        The scene is loaded on the new client before anything is swapped, without the engine's lock, so a
        slow simulator never holds up status, scene requests or shutdown."""
        try:
            client = self._client_factory()
        except SimUnreachable as exc:
            return str(exc)
        start = time.monotonic()
        scene = self.scene
        link = self._link(client, self.frame_counts)  # first, so the scene load already uses its receive loop
        guard = threading.Timer(RELOAD_TIMEOUT_S, close_client, (client,))
        guard.start()
        try:
            world = self._load_world(client, scene, self.sim_config_path) if scene else None
        except Exception as exc:
            link.abandon()
            return f"reloading {scene.file if scene else 'the scene'} failed: {type(exc).__name__}: {exc}"
        finally:
            guard.cancel()
        with self._lock:
            if not self._running or self.scene is not scene:
                link.abandon()
                return "shutting down" if not self._running else "the scene changed meanwhile"
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
            "bad_frames": self.frame_counts.bad,
            "oversized_frames": self.frame_counts.oversized,
            "sim_time_jumps_back": self.sim_time.jumps_back,
            "sim_time_last_jump_back_s": round(self.sim_time.last_jump_s, 3),
            "gc_max_ms": self.gc_pauses.take_peak_ms(),
            "gc_frozen": self.gc_frozen,  # objects kept out of full collections (freeze_heap)
            "streams": streams,
            "bridge_errors": errors,
            **({"mapping": self.mapping_report} if self.mapping_report else {}),
        }

    def publish_status(self) -> None:
        status = self.status()
        try:
            self._status.publish(status)
        except Exception as exc:  # rospy shutting down
            log.debug("status not published: %s", exc)

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

    def shutdown(self, timeout: float = SHUTDOWN_TIMEOUT_S, client_topics: bool = False) -> bool:
        """Stop every bridge (robots with a running velocity command are stopped) and the link, within
        `timeout` seconds whatever the simulator does: the server is told to unsubscribe in one request,
        which gets what is left of the budget (at most UNSUBSCRIBE_TIMEOUT_S). With `client_topics` the
        client's own subscriptions go too (its owner closes it next). False if the simulator did not
        answer."""
        end = time.monotonic() + timeout
        self._running = False
        self._stopping.set()
        with contextlib.suppress(queue.Full):  # a full queue's loader sees _running false after its load
            self._scene_requests.put_nowait(None)
        self.sim.begin_close()  # unsubscribes are collected, sent once below
        locked = self._lock.acquire(timeout=max(0.0, (end - time.monotonic()) / 2))
        try:
            for name, bridge in list(self.bridges.items()):
                try:
                    bridge.stop()
                except Exception:
                    log.exception("stopping %s failed", name)
            self.bridges.clear()
        finally:
            if locked:
                self._lock.release()
        time.sleep(0.1)  # let the last stop commands leave
        budget = min(UNSUBSCRIBE_TIMEOUT_S, max(0.1, end - time.monotonic() - 0.5))
        answered = self.sim.close(timeout=budget, client_topics=client_topics)
        self.hub.drop_all()
        self.ros.close()
        self.state = STOPPED
        self.publish_status()
        self._status.close()
        self.gc_pauses.close()
        return answered


def _scene_independent(spec: BridgeSpec) -> bool:
    return "scene_name" not in spec.variables


def _load_world(client: Any, scene: Scene, sim_config_path: str) -> Any:
    """A projectairsim World on `scene` as it was validated (`Scene.config`): no file is read again."""
    return validated_world_class()(client, scene, sim_config_path)


@functools.cache
def validated_world_class() -> type:
    """The World subclass `_load_world` uses (made on first use: projectairsim is imported lazily)."""
    from projectairsim import World

    class ValidatedWorld(World):
        """World.__init__ of projectairsim 1.1.0 step for step, except that the scene dict is the one
        read_scene validated instead of whatever the file holds now (it may have been edited, or replaced
        by a symlink out of the config directory, since)."""

        def __init__(self, client: Any, scene: Scene, sim_config_path: str) -> None:
            self.client = client
            self.sim_config_path = sim_config_path.rstrip("/") + "/"
            self.sim_instance_idx = -1
            self.parent_topic = "/Sim/SceneBasicDrone"
            self.sim_config = None
            self.home_geo_point = None
            self.scene_config_path = str(Path(scene.config_dir) / scene.file)
            self.robot_config_paths: list[str] = []
            self.envactor_config_paths: list[str] = []
            self.load_scene(copy.deepcopy(dict(scene.config)), delay_after_load_sec=0)
            zeros = [0, 0]
            self.import_ned_trajectory("null_trajectory", [0, 1], zeros, zeros, zeros, zeros, zeros, zeros)

    return ValidatedWorld
