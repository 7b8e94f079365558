"""projectairsim_node: the bridge as a ROS node (python, rosrun and roslaunch).

Switches as the Project AirSim ROS bridge documentation gives them (--address, --nodename,
--simconfigpath, --servicesport, --topicsport), plus --mapping, --scene and --namespace; each is also a
private parameter (`_scene:=...` with rosrun, `<param>` in a launch file), and the command line wins (the
log says where each value came from). Without a scene the node runs load_scene and waits for one. An
invalid mapping or scene stops the node with the validate-mapping errors and exit code 1, before anything
connects. A simulator that is not running yet is waited for (one log line per attempt; backoff 0.5 s, then
2 s, then 5 s); one that restarts later is reconnected to and the last scene reloaded, without restarting
the node.

A port that accepts the connection but never answers is not waited for: after about 10 s the node
exits with status 1 and says so. Start-up (connecting, loading the scene) runs on a thread of its own, so
the main thread always sees a signal.

SIGINT or SIGTERM stops the node within --shutdown-timeout seconds whatever the simulator does (past
that it exits with status 1 and says so); a second signal exits at once.
"""

from __future__ import annotations

import argparse
import contextlib
import logging
import os
import signal
import sys
import threading
import time
from collections.abc import Callable
from dataclasses import dataclass
from functools import partial
from pathlib import Path
from typing import TYPE_CHECKING, Any

from airsim_mapper.engine.health import Backoff, SimSilent, SimUnreachable, open_client
from airsim_mapper.mapping.errors import ConfigError
from airsim_mapper.mapping.names import resolve_namespace
from airsim_mapper.ros_log import ros_logger

if TYPE_CHECKING:
    from airsim_mapper.mapping.model import BridgeSpec
    from airsim_mapper.scene import Scene

log = ros_logger("airsim_mapper.node")


@dataclass(frozen=True)
class Setting:
    """A node switch that is also a private parameter (`--mapping` and `~mapping`)."""

    name: str
    default: Any
    help: str
    kind: type = str


DEFAULT_SIM_CONFIG = "sim_config/"
SETTINGS = (
    Setting("address", "127.0.0.1", "host running Project AirSim"),
    Setting("topicsport", 8989, "Project AirSim pub-sub port", int),
    Setting("servicesport", 8990, "Project AirSim services port", int),
    Setting(
        "simconfigpath",
        DEFAULT_SIM_CONFIG,
        "directory holding the scene configs (./sim_config/, else the package's own)",
    ),
    Setting("mapping", "default", "mapping YAML file, or a shipped mapping's name"),
    Setting("scene", "", "scene config file to load at start (without one: wait for load_scene)"),
    Setting("namespace", "", "topic namespace and frame prefix, resolved in the node's ROS namespace"),
)
COMMAND_LINE, DEFAULT = "command line", "default"


class SettingError(ValueError):
    """A private parameter holds a value of the wrong type."""

    def __init__(self, name: str, value: Any, kind: type) -> None:
        super().__init__(f"parameter ~{name}: {value!r} is not a valid {kind.__name__}")


@dataclass(frozen=True)
class Resolved:
    """One setting's value and where it came from ("command line", "parameter ~x" or "default")."""

    value: Any
    source: str


def resolve_settings(
    given: dict[str, Any], get_param: Callable[[str], Any] | None = None
) -> dict[str, Resolved]:
    """Each setting from the command line (a value in `given` that is not None), else from its private
    parameter (`get_param("~name")`, KeyError when unset), else its default."""
    resolved: dict[str, Resolved] = {}
    for setting in SETTINGS:
        if given.get(setting.name) is not None:
            resolved[setting.name] = Resolved(given[setting.name], COMMAND_LINE)
            continue
        try:
            value = get_param(f"~{setting.name}") if get_param is not None else None
        except KeyError:
            value = None
        if value is None:
            resolved[setting.name] = Resolved(setting.default, DEFAULT)
            continue
        try:
            value = setting.kind(value)
        except (TypeError, ValueError):
            raise SettingError(setting.name, value, setting.kind) from None
        resolved[setting.name] = Resolved(value, f"parameter ~{setting.name}")
    return _sim_config_fallback(resolved)


def given_settings(args: argparse.Namespace) -> dict[str, Any]:
    """Each setting as the command line gives it (None where it says nothing), for `resolve_settings`."""
    return {setting.name: getattr(args, setting.name) for setting in SETTINGS}


def values(resolved: dict[str, Resolved]) -> dict[str, Any]:
    """The values of resolved settings, by name."""
    return {name: setting.value for name, setting in resolved.items()}


def _sim_config_fallback(resolved: dict[str, Resolved]) -> dict[str, Resolved]:
    """The default sim_config/ is the working directory's; where there is none, the package's own."""
    from airsim_mapper.resources import package_sim_config

    current = resolved["simconfigpath"]
    if current.source != DEFAULT or Path(current.value).is_dir():
        return resolved
    shipped = package_sim_config()
    if shipped is None:
        return resolved
    why = f"default: ./{DEFAULT_SIM_CONFIG} does not exist here, so the package's own"
    return {**resolved, "simconfigpath": Resolved(str(shipped), why)}


def parse_args(argv: list[str]) -> argparse.Namespace:
    from airsim_mapper.engine.engine import SHUTDOWN_TIMEOUT_S
    from airsim_mapper.engine.sim_link import MAX_FRAME_MB
    from airsim_mapper.resources import shipped_mappings

    parser = argparse.ArgumentParser(
        description=__doc__.splitlines()[0],
        epilog="Each switch but --nodename, --no-watch, --shutdown-timeout and --max-frame-mb is also a "
        "private parameter (~address, ~mapping, ...); the command line wins over the parameter, the "
        "parameter over the default.",
    )
    parser.add_argument(
        "--nodename",
        default=None,
        help='node name (default: "projectairsim", made unique with rospy\'s anonymous flag)',
    )
    shipped = ", ".join(shipped_mappings())
    for setting in SETTINGS:
        extra = f"; shipped: {shipped}" if setting.name == "mapping" else ""
        parser.add_argument(
            f"--{setting.name}",
            type=setting.kind,
            default=None,
            help=f"{setting.help} (default {setting.default!r}{extra})",
        )
    parser.add_argument(
        "--no-watch",
        action="store_true",
        help="do not reload the mapping when its files change (~reload_mapping still does)",
    )
    parser.add_argument(
        "--shutdown-timeout",
        type=float,
        default=SHUTDOWN_TIMEOUT_S,
        help=f"seconds a SIGINT/SIGTERM may take to stop the node (default {SHUTDOWN_TIMEOUT_S:g})",
    )
    parser.add_argument(
        "--max-frame-mb",
        type=float,
        default=MAX_FRAME_MB,
        help=f"larger simulator frames are dropped, counted as oversized_frames (default {MAX_FRAME_MB:g})",
    )
    args = parser.parse_args(argv)
    if not args.shutdown_timeout > 0:
        parser.error(f"--shutdown-timeout must be positive, got {args.shutdown_timeout}")
    if not 0 < args.max_frame_mb < float("inf"):
        parser.error(f"--max-frame-mb must be a positive number, got {args.max_frame_mb}")
    return args


class Stopper:
    """The node's signal handler: the first signal asks the main loop to stop and arms a deadline after
    which the process exits anyway (status 1); a second signal exits at once (status 128 + signal)."""

    def __init__(self, timeout: float) -> None:
        self.timeout = timeout
        self.signals: list[int] = []

    def __call__(self, number: int, _frame: Any) -> None:
        if self.signals:
            _say_and_exit(f"second signal ({signal.Signals(number).name}): exiting at once", 128 + number)
        self.signals.append(number)
        deadline = threading.Timer(self.timeout, self._overdue)
        deadline.daemon = True
        deadline.start()

    def _overdue(self) -> None:
        _say_and_exit(f"shutdown took longer than {self.timeout:g} s (--shutdown-timeout): exiting", 1)

    def __bool__(self) -> bool:
        return bool(self.signals)


def _say_and_exit(message: str, status: int) -> None:
    """Exit now, without running more Python: the message goes straight to stderr."""
    with contextlib.suppress(OSError):
        os.write(2, f"[projectairsim_node] {message}\n".encode())
    os._exit(status)


def connect(
    address: str,
    topicsport: int,
    servicesport: int,
    is_shutdown: Callable[[], bool],
    sleep: Callable[[float], Any] | None = None,
) -> Any:
    """Connect to the simulator, retrying with backoff while nothing listens, until it answers or ROS shuts
    down (then None). SimSilent (the ports are held but nothing answers) is raised, not retried."""
    sleep = sleep or time.sleep
    backoff = Backoff()
    while not is_shutdown():
        try:
            client = open_client(address, topicsport, servicesport)
        except SimSilent:
            raise
        except SimUnreachable as exc:
            delay = backoff.next_delay()
            log.warning("%s; waiting for it: attempt %d, next in %.1f s", exc, backoff.attempt, delay)
            sleep(delay)
            continue
        if backoff.attempt:
            log.info("simulator at %s:%d/%d answered", address, topicsport, servicesport)
        return client
    return None


@dataclass(frozen=True)
class Prepared:
    """The mapping, and the start scene as read and expanded for a node name and namespace: the node
    reads the scene and expands the mapping for its final name once, and hands the result on."""

    settings: tuple[Any, ...]  # the CONFIG_SETTINGS values it was made from
    node_name: str
    namespace: str
    mapping: Any
    scene: Scene | None = None
    specs: tuple[BridgeSpec, ...] | None = None


CONFIG_SETTINGS = ("mapping", "scene", "simconfigpath")


def prepare(
    settings: dict[str, Any], node_name: str, namespace: str, known: Prepared | None = None
) -> Prepared:
    """Load the mapping and, with a scene, read it and expand the mapping over it (ConfigError or OSError
    when that cannot be done). What `known` holds for the same settings is reused, not read again."""
    from airsim_mapper.mapping.expand import expand
    from airsim_mapper.mapping.loader import load_mapping
    from airsim_mapper.scene import read_scene

    basis = tuple(settings[name] for name in CONFIG_SETTINGS)
    same = known is not None and known.settings == basis
    mapping = known.mapping if same else load_mapping(settings["mapping"])
    if not settings["scene"]:
        return Prepared(basis, node_name, namespace, mapping)
    scene = known.scene if same else read_scene(settings["simconfigpath"], settings["scene"])
    if same and (known.node_name, known.namespace) == (node_name, namespace):
        specs = known.specs
    else:
        specs = expand(mapping, scene, node_name, namespace)
    return Prepared(basis, node_name, namespace, mapping, scene, specs)


def config_problem(
    settings: dict[str, Any], node_name: str, namespace: str, known: Prepared | None = None
) -> tuple[Prepared | None, str | None]:
    """(prepared, None), or (None, what to print) when the mapping or scene is invalid."""
    try:
        return prepare(settings, node_name, namespace, known), None
    except ConfigError as exc:
        return None, str(exc)
    except OSError as exc:
        return None, f"{settings['mapping']}: {exc.strerror or exc}"


def serve_reload(engine: Any, spec: str, mapping: Any, watch: bool) -> Any:
    """Live reload: the `~reload_mapping` service (std_srvs/Trigger) and, with `watch`, the file watcher."""
    import rospy
    from std_srvs.srv import Trigger, TriggerResponse

    from airsim_mapper.engine.mapping_reload import MappingReloader

    reloader = MappingReloader(engine, spec, mapping)

    def on_request(_request: Any) -> Any:
        outcome = reloader.reload("~reload_mapping")
        return TriggerResponse(success=outcome.ok, message=outcome.message)

    rospy.Service("~reload_mapping", Trigger, on_request)
    if watch:
        reloader.start()
        log.info("watching %s for changes (--no-watch turns this off)", ", ".join(reloader.files))
    return reloader


def main(argv: list[str] | None = None) -> int:
    import rospy

    args = parse_args(rospy.myargv(argv if argv is not None else sys.argv)[1:])
    from airsim_mapper.cli.validate import format_table

    node_name = args.nodename or "projectairsim"
    given = given_settings(args)
    # The command line's values are checked before anything connects (the master may not be up).
    early_settings = values(resolve_settings(given))
    early, problem = config_problem(early_settings, node_name, resolve_namespace(early_settings["namespace"]))
    if problem:
        print(problem, file=sys.stderr)
        return 1

    # rospy runs its shutdown hooks inside its signal handler, on whatever the main thread was doing: a
    # SIGINT during a service registration ran the engine's shutdown while the registration lock was held,
    # and the node hung (seen in CI). Here the handler only raises a flag; the hooks run from the loop below.
    rospy.init_node(node_name, anonymous=args.nodename is None, disable_signals=True)
    try:
        resolved = resolve_settings(given, rospy.get_param)  # KeyError when unset
    except SettingError as exc:
        print(str(exc), file=sys.stderr)
        rospy.signal_shutdown("invalid parameter")
        return 1
    for name, setting in resolved.items():
        log.info("setting %s = %r (%s)", name, setting.value, setting.source)
    settings = values(resolved)
    # Parameters may have changed the settings, and the node's final name and namespace are known now.
    name = rospy.get_name().rsplit("/", 1)[-1]
    namespace = resolve_namespace(settings["namespace"], rospy.get_namespace())
    prepared, problem = config_problem(settings, name, namespace, early)
    if problem:
        print(problem, file=sys.stderr)
        rospy.signal_shutdown("invalid configuration")
        return 1
    stop = Stopper(args.shutdown_timeout)
    for sig in (signal.SIGINT, signal.SIGTERM):
        signal.signal(sig, stop)

    def stopping() -> bool:
        return bool(stop) or rospy.is_shutdown()

    from airsim_mapper.wrapper import redirect_client_log

    redirect_client_log()
    startup = StartUp(args, settings, prepared, stopping)
    worker = threading.Thread(target=startup.run, name="start-up", daemon=True)
    worker.start()
    while not stopping() and worker.is_alive():
        time.sleep(0.1)
    if startup.failure and not stopping():
        print(startup.failure, file=sys.stderr)
        rospy.signal_shutdown("start-up failed")
        return 1
    wrapper, reloader = startup.wrapper, None
    if wrapper is not None:
        log.info("bridges:\n%s", format_table(wrapper.bridges))
        log.info("namespace %r (topics under it, frames prefixed with it)", wrapper.namespace or "/")
        if not settings["scene"]:
            topics = [b.ros for b in wrapper.bridges if b.converter == "load_scene"]
            waiting_on = " or ".join(topics) or "(the mapping has no load_scene rule)"
            log.info("no --scene: waiting for a scene file name on %s", waiting_on)
        reloader = serve_reload(
            wrapper.engine, settings["mapping"], prepared.mapping, watch=not args.no_watch
        )
    while not stopping():
        time.sleep(0.1)
    if reloader is not None:
        reloader.stop()
    rospy.signal_shutdown(f"signal {stop.signals[0]}" if stop else "shutdown requested")
    return 0


class StartUp:
    """The node's start-up on a thread of its own: connect, make the wrapper, load the start scene.

    The main thread only waits for it, so a signal is seen at once even while a connect or a scene load
    is blocked in the simulator client. `failure` is the message to print (exit status 1)."""

    def __init__(
        self,
        args: argparse.Namespace,
        settings: dict[str, Any],
        prepared: Prepared,
        stopping: Callable[[], bool],
    ) -> None:
        self.args, self.settings, self.prepared, self.stopping = args, settings, prepared, stopping
        self.wrapper: Any = None
        self.failure = ""

    def run(self) -> None:
        try:
            self.failure = self._run()
        except Exception as exc:  # never leave the main thread waiting: say what happened
            self.failure = f"start-up failed: {type(exc).__name__}: {exc}"

    def _run(self) -> str:
        from airsim_mapper.wrapper import ProjectAirSimWrapper

        args, settings, prepared = self.args, self.settings, self.prepared
        address, topicsport, servicesport = (settings[k] for k in ("address", "topicsport", "servicesport"))
        try:
            client = connect(address, topicsport, servicesport, self.stopping)
        except SimSilent as exc:
            return str(exc)
        if client is None:
            return ""  # stopped while waiting for the simulator
        self.wrapper = ProjectAirSimWrapper(
            client,
            sim_config_path=settings["simconfigpath"],
            mapping=prepared.mapping,
            node_name=prepared.node_name,
            namespace=prepared.namespace,
            disconnect_on_shutdown=True,  # this node made the client
            client_factory=partial(open_client, address, topicsport, servicesport),
            shutdown_timeout=max(0.5, args.shutdown_timeout - 1.5),  # rospy's own unregistering comes after
            max_frame_mb=args.max_frame_mb,
            tune_process=True,  # this process is the bridge's own
        )
        if prepared.scene is None:
            return ""
        try:
            self.wrapper.load_scene(prepared.scene, prepared.specs)
        except ConfigError as exc:
            return str(exc)
        except Exception as exc:  # the simulator refused the scene: say why, without a traceback
            return f"{settings['scene']}: the simulator could not load it: {type(exc).__name__}: {exc}"
        return ""


def run() -> None:
    """The script's entry: main(), then leave without interpreter finalisation.

    pynng's atexit hook calls nng_fini, and nng aborts ("panic: pthread_mutex_lock") when a client thread
    still holds a request, which is what a simulator frozen at shutdown leaves behind. By the time main
    returns, ROS is shut down and the bridges are stopped; the logs are flushed and the process exits with
    main's status directly.
    """
    code = main()
    logging.shutdown()
    for stream in (sys.stdout, sys.stderr):
        with contextlib.suppress(Exception):
            stream.flush()
    os._exit(code)


if __name__ == "__main__":
    run()
