"""The engine: runs the bridges of a mapping for the current scene, and follows scene changes.

Data flows one way: scene + mapping --expand--> BridgeSpecs --build--> runners wired to the sim link and
the ROS link. The node's own bridges (load_scene) start before any scene (`start_node_bridges`) and keep
running, untouched, across scene changes; a scene change tears the scene's runners down and builds the new
scene's. Scene requests from ROS wait in a short queue for the scene-loader thread (scene_requests.py).

The engine owns the bridges, the scene and the link, and the one lock they change under. Its supervisor
(supervisor.py) owns the connection state: it watches the link's health, reconnects, runs the command
watchdog and publishes the status, asking the engine through the methods `supervisor.Supervised` names;
it is given the engine's lock, since its state changes with the link and the bridges.
"""

from __future__ import annotations

import gc
import threading
import time
from collections.abc import Callable
from typing import Any

from airsim_mapper.common.logs import RateLimitedLog, ros_logger
from airsim_mapper.engine.bridges import WARN_PERIOD_S, Bridge, BridgeParts, RosLink, SimToRos
from airsim_mapper.engine.hub import StreamHub
from airsim_mapper.engine.mounts import CameraMounts
from airsim_mapper.engine.node_setup import NodeNames, SimAccess
from airsim_mapper.engine.process_tuning import GcPauses, freeze_heap, thaw_heap, tune_process
from airsim_mapper.engine.ros_to_sim import RosToSim
from airsim_mapper.engine.runners import build
from airsim_mapper.engine.scene_requests import SceneRequests
from airsim_mapper.engine.sim_link import FrameCounts, SimLink
from airsim_mapper.engine.simtime import SimTimeWatch
from airsim_mapper.engine.status import StatusPublisher
from airsim_mapper.engine.supervisor import Supervisor
from airsim_mapper.mapping.diff import BridgeDiff, bridge_diff
from airsim_mapper.mapping.expand import expand
from airsim_mapper.mapping.model import BridgeSpec, MappingDoc
from airsim_mapper.mapping.names import ros_namespace
from airsim_mapper.mapping.report import format_table
from airsim_mapper.mapping.scene import Scene, read_scene

log = ros_logger("airsim_mapper.engine")
bridge_log = ros_logger("airsim_mapper.bridge")  # sim-time warnings, as the bridges' own
SHUTDOWN_TIMEOUT_S = 5.0  # shutdown's total budget; the simulator gets at most UNSUBSCRIBE_TIMEOUT_S of it
UNSUBSCRIBE_TIMEOUT_S = 2.0


class Engine:
    """Owns the runners of one node: builds them from specs, reloads them on scene changes.

    Construction starts nothing: `start` starts the scene-loader thread and the supervisor's."""

    def __init__(
        self,
        client: Any,
        mapping: MappingDoc,
        names: NodeNames,
        sim: SimAccess,
        ros: RosLink | None = None,
        frame_counts: FrameCounts | None = None,
        tune: bool = False,
    ) -> None:
        if tune:
            tune_process()
        self._freeze_heap = tune  # gc.freeze is process-wide: only for a process that asked for tuning
        self.gc_pauses = GcPauses()
        self.gc_frozen = 0
        self.client = client
        self.mapping = mapping
        self.sim_config_path = str(sim.config_path)
        self.node_name = names.node  # the mapping's <node_name>
        self.ros_name = names.ros or names.node  # the node's ROS name: its status topic's, diagnostics' name
        self.namespace = names.namespace
        # Where the mapping's relative and private names resolve: the ROS node's namespace and own name
        # (the mapping's <node_name> may differ, given to a wrapper).
        self._ros_place = (ros_namespace(self.ros_name), self.ros_name.rsplit("/", 1)[-1])
        self.frame_counts = frame_counts or FrameCounts()  # kept across reconnects
        self._link = sim.link
        self.sim = self.make_link(client)
        self.ros = ros or RosLink()
        # Every frame's stamp feeds the time watch; a jump back starts what depends on the old time over.
        self.sim_time = SimTimeWatch(
            warn=RateLimitedLog(bridge_log, WARN_PERIOD_S, prefix="sim time").warn,
            on_jump=self._time_went_back,
        )
        self.hub = StreamHub(self.sim, self.ros.send_tf, on_stamp=self.sim_time.observe)
        self.mounts = CameraMounts()
        self.parts = BridgeParts(
            self.sim,
            self.hub,
            self.ros,
            self.mounts,
            self._node_action,
            counts=self.frame_counts,
            sim_time=self.sim_time,
        )
        self.bridges: dict[str, Bridge] = {}
        self._refused: dict[str, str] = {}  # bridges that could not start (ROS refused them): name -> why
        self.scene: Scene | None = None
        self.world: Any = None
        self._load_world = sim.load_world
        self.lock = threading.RLock()
        self._scene_requests = SceneRequests(self.load_scene, self._log_bridges)
        self._mapping_report: dict[str, Any] = {}  # live reload's state (engine/mapping_reload.py)
        self.supervisor = Supervisor(
            self, self.lock, sim.client_factory, StatusPublisher(self.ros.publisher, self.ros_name)
        )

    def start(self) -> None:
        """Start the scene-loader thread and the supervisor's (health, watchdog, status)."""
        self._scene_requests.start()
        self.supervisor.start()

    # --- the supervisor's state and reports -------------------------------------------------
    @property
    def state(self) -> str:
        return self.supervisor.state

    @property
    def reason(self) -> str:
        return self.supervisor.reason

    @property
    def counters(self) -> dict[str, int]:
        return self.supervisor.counters

    def status(self) -> dict[str, Any]:
        """The node's state, its counters and the statistics of every simulator stream."""
        return self.supervisor.status()

    def publish_status(self) -> None:
        self.supervisor.publish_status()

    def sim_lost(self, reason: str) -> None:
        """Mark the link lost: nothing more is sent on it; robots are no longer driven."""
        self.supervisor.sim_lost(reason)

    # --- building ---------------------------------------------------------------------------
    def specs_for(self, scene: Scene | None) -> tuple[BridgeSpec, ...]:
        """The bridges of `scene`, or the node's own (load_scene) without one."""
        return expand(self.mapping, scene, self.node_name, self.namespace, *self._ros_place)

    def bridge_specs(self) -> tuple[BridgeSpec, ...]:
        """The specs of the bridges running now (read under the lock: a reload or a scene load may be
        changing them)."""
        with self.lock:
            return tuple(bridge.spec for bridge in self.bridges.values())

    def start_node_bridges(self) -> tuple[BridgeSpec, ...]:
        """Before any scene: run the node's own bridges, so a scene can be loaded over ROS."""
        with self.lock:
            if self.scene is not None:
                return self.bridge_specs()
            return self.apply(None)

    def apply(
        self, scene: Scene | None, specs: tuple[BridgeSpec, ...] | None = None
    ) -> tuple[BridgeSpec, ...]:
        """Run exactly the bridges of `scene` (its `specs`, when already expanded): stop the old scene's,
        start the new ones."""
        specs = self.specs_for(scene) if specs is None else specs
        with self.lock:
            self._stop_scene_bridges(keep={s.name: s for s in specs})
            if self._freeze_heap:
                thaw_heap()  # the old scene's bridges are garbage now: let the collector see them again
            self.scene = scene
            self.mounts.clear()
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
                bridge = build(spec, self.parts)
                bridge.start()
            except Exception as exc:
                self._refused[spec.name] = f"{type(exc).__name__}: {exc}"
                log.error("bridge %s could not start and stays off: %s", spec.name, self._refused[spec.name])
                continue
            self.bridges[spec.name] = bridge
        self.bridges = {s.name: self.bridges[s.name] for s in specs if s.name in self.bridges}

    def refused_bridges(self) -> dict[str, str]:
        """The bridges of the running mapping that could not start, with why (for /diagnostics, reloads)."""
        with self.lock:
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
    def apply_mapping(self, mapping: MappingDoc) -> BridgeDiff:
        """Run `mapping` instead of the current one, touching only what differs: bridges whose expanded
        spec is unchanged keep running (their publishers, subscribers and simulator subscriptions), removed
        and changed ones stop, new and changed ones start. Without a scene that is the node's own bridges.
        MappingError (nothing changed) when `mapping` does not expand over the running scene."""
        with self.lock:
            specs = expand(mapping, self.scene, self.node_name, self.namespace, *self._ros_place)
            diff = bridge_diff((b.spec for b in self.bridges.values()), specs)
            self.mapping = mapping
            for name in (*diff.removed, *diff.changed):
                try:
                    self.bridges.pop(name).stop()
                except Exception:
                    log.exception("stopping %s failed", name)
            self._start_bridges(specs, {*diff.added, *diff.changed})
            if self._freeze_heap:
                # No full collection here (freeze_heap's would stop every running bridge while it walks the
                # whole heap): the new objects join the frozen heap as they are. The stopped
                # bridges were freed by reference counting as they stopped: they hold no reference cycle
                # (tests/engine/test_freed_on_stop.py; a cycle frozen here would stay for good).
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
        with self.lock:
            self.supervisor.require_link(f"load_scene {scene_file}")
            self._stop_scene_bridges(keep={s.name: s for s in specs})  # the node's own bridges stay
            self.hub.drop_all()
            self.sim.forget_all()
            try:
                self.world = self.world_on(self.client, scene)
            except Exception:
                if self.scene is not None:
                    log.error("loading %s failed; restoring the bridges of %s", scene_file, self.scene.file)
                    self.apply(self.scene)
                raise
            self._forget_old_time()
            self.apply(scene, specs)
        log.info("scene %s (%s) loaded: %d bridges", scene.name, scene_file, len(self.bridges))
        return scene

    def adopt(self, scene: Scene, world: Any = None) -> None:
        """A mission script loaded `scene` itself: its load cleared every subscription, so re-bridge."""
        specs = self.specs_for(scene)
        with self.lock:
            self.supervisor.require_link("adopt")
            self._stop_scene_bridges(keep={s.name: s for s in specs})  # the node's own bridges stay
            self.hub.drop_all()
            self.sim.forget_all()
            self.world = world
            self._forget_old_time()
            self.apply(scene, specs)

    def request_scene(self, scene_file: str) -> None:
        """Queue a scene load (from a ROS callback); it runs on the scene-loader thread (scene_requests.py).
        EngineError when too many wait."""
        self._scene_requests.request(scene_file)

    def _log_bridges(self) -> None:
        log.info("bridges:\n%s", format_table(self.bridge_specs()))

    def _node_action(self, action: str, params: dict) -> None:
        """An engine action a bridge asked for, by the name the converter catalogue gives it."""
        actions: dict[str, Callable[[dict], Any]] = {"load_scene": lambda p: self.request_scene(p["scene"])}
        if action not in actions:
            raise ValueError(f"the engine has no action {action!r}")
        actions[action](params)

    # --- the link: what the supervisor asks of the engine (supervisor.Supervised) ---------------
    def make_link(self, client: Any) -> SimLink:
        """A link on `client` that counts refused frames in this engine's counts (kept across reconnects)."""
        return self._link(client, self.frame_counts)

    def link(self) -> SimLink:
        """The simulator link the bridges use now."""
        return self.sim

    def scene_now(self) -> Scene | None:
        return self.scene

    def world_on(self, client: Any, scene: Scene) -> Any:
        """Load `scene` into the simulator of `client` (validated first); the client's world of it."""
        return self._load_world(client, scene, self.sim_config_path)

    def swap_link(self, link: SimLink, client: Any, world: Any) -> None:
        """Run every bridge over `link` from now on (under the lock: the supervisor's reconnect). The new
        simulator's clock started over: the old one's stamps no longer say what is stale."""
        with self.lock:
            self.client, self.sim, self.parts.sim, self.world = client, link, link, world
            self._start_over()
            self.hub.rebind(link)

    def move_to(self, link: SimLink, client: Any, world: Any) -> SimLink:
        """A reconnect: every bridge runs over `link` on `client`, whose simulator already has the scene
        (`world`); camera mounts moved by commands are forgotten. The old link, for the caller to stop."""
        with self.lock:
            old = self.sim
            self.mounts.clear()
            self.swap_link(link, client, world)
        return old

    def revive_link(self) -> None:
        """The owner of a supplied client says it works again: a new link on the same client."""
        with self.lock:
            self.sim.stop_loop()
            self.swap_link(self.make_link(self.client), self.client, self.world)

    def link_lost(self, abandon: bool) -> None:
        """The simulator is lost: no robot counts as driven any more, and the link is abandoned (its sockets
        closed, for a new client) or, when `abandon` is false, only marked dead (the owner's client)."""
        with self.lock:
            for command in self.commands():
                command.moving = False
            if abandon:
                self.sim.abandon()
            else:
                self.sim.mark_dead()

    def commands(self) -> list[RosToSim]:
        """The running ROS -> simulator bridges (robots' commands and their watchdogs)."""
        return [bridge for bridge in list(self.bridges.values()) if isinstance(bridge, RosToSim)]

    def bridge_count(self) -> int:
        return len(self.bridges)

    def newest_arrival(self) -> float:
        """When the newest topic frame arrived (monotonic; 0 before any)."""
        return self.hub.newest_arrival()

    def report(self) -> dict[str, Any]:
        """The engine's part of the status: the scene, refused frames, sim time, collections, every
        simulator stream's statistics, the bridges' errors and the mapping's reload state."""
        errors = {name: b.stats.errors for name, b in list(self.bridges.items()) if b.stats.errors}
        mapping = self._mapping_report
        return {
            "scene": self.scene.file if self.scene else None,
            "bad_frames": self.frame_counts.bad,
            "oversized_frames": self.frame_counts.oversized,
            "callback_errors": self.frame_counts.callback_errors,
            "sim_time_jumps_back": self.sim_time.jumps_back,
            "sim_time_last_jump_back_s": round(self.sim_time.last_jump_s, 3),
            "gc_max_ms": self.gc_pauses.take_peak_ms(),
            "gc_frozen": self.gc_frozen,  # objects kept out of full collections (freeze_heap)
            "streams": self.hub.statistics(),
            "bridge_errors": errors,
            **({"mapping": mapping} if mapping else {}),
        }

    @property
    def mapping_report(self) -> dict[str, Any]:
        """What live reload last said about the mapping (empty without live reload)."""
        return self._mapping_report

    def report_mapping(self, report: dict[str, Any]) -> None:
        """Live reload's state of the mapping, for the status topic and /diagnostics (mapping_reload.py)."""
        self._mapping_report = report

    # --- a new simulator session ------------------------------------------------------------
    def _forget_old_time(self) -> None:
        """A scene was loaded: its clock starts from zero. The old scene's transforms go from the node's tf
        buffer; kept, tf refused the new scene's as data from the past, and a goal in a robot's frame was
        placed from where the robot had been. (Another scene's topics differ, so the time watch, which
        compares each stream with itself, sees no jump back.)"""
        self.ros.forget_tf()

    def _time_went_back(self, jump_s: float) -> None:
        """The time watch saw the simulator's clock go back (a restart, or a scene loaded again): tf and
        the lazy streams' stale filters start over. Runs on the receive thread: takes no engine lock."""
        self._start_over()
        self.ros.forget_tf()
        log.info("simulation time went back %.3f s: tf buffer cleared, stale filters reset", jump_s)

    def _start_over(self) -> None:
        """Forget the old session's stamps: the streams' newest, and each stale filter's wait."""
        self.hub.forget_stamps()
        for bridge in list(self.bridges.values()):
            if isinstance(bridge, SimToRos):
                bridge.new_session()

    # --- shutdown --------------------------------------------------------------
    def shutdown(self, timeout: float = SHUTDOWN_TIMEOUT_S, client_topics: bool = False) -> bool:
        """Stop every bridge (robots with a running velocity command are stopped) and the link, within
        `timeout` seconds whatever the simulator does: the server is told to unsubscribe in one request,
        which gets what is left of the budget (at most UNSUBSCRIBE_TIMEOUT_S). With `client_topics` the
        client's own subscriptions go too (its owner closes it next). False if the simulator did not
        answer."""
        end = time.monotonic() + timeout
        self._scene_requests.stop()
        self.supervisor.stop()
        self.sim.begin_close()  # unsubscribes are collected, sent once below
        locked = self.lock.acquire(timeout=max(0.0, (end - time.monotonic()) / 2))
        try:
            for name, bridge in list(self.bridges.items()):
                try:
                    bridge.stop()
                except Exception:
                    log.exception("stopping %s failed", name)
            self.bridges.clear()
        finally:
            if locked:
                self.lock.release()
        time.sleep(0.1)  # let the last stop commands leave
        budget = min(UNSUBSCRIBE_TIMEOUT_S, max(0.1, end - time.monotonic() - 0.5))
        answered = self.sim.close(timeout=budget, client_topics=client_topics)
        self.hub.drop_all()
        self.ros.close()
        self.supervisor.close()
        self.gc_pauses.close()
        return answered


def _scene_independent(spec: BridgeSpec) -> bool:
    return "scene_name" not in spec.variables
