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

The settings are in settings.py, the start-up thread and the signal handler in startup.py; the mapping
and the start scene are prepared by mapping/pipeline.py, expanded once for the node's final name.
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
from typing import TYPE_CHECKING, Any

from airsim_mapper.cli.errors import FlavourError, SettingError
from airsim_mapper.cli.flavour import FLAVOURS, choose, requested
from airsim_mapper.cli.limits import raise_open_files, shortfall
from airsim_mapper.cli.settings import (
    SETTINGS,
    SWITCHES_ONLY,
    given_settings,
    resolve_settings,
    unread_parameters,
    values,
)
from airsim_mapper.cli.startup import StartUp, Stopper, connect
from airsim_mapper.common.errors import ConfigError
from airsim_mapper.common.logs import ros_logger, wait_for_rosout
from airsim_mapper.mapping.expand import namespace_variables
from airsim_mapper.mapping.names import resolve_namespace, ros_namespace

if TYPE_CHECKING:
    from airsim_mapper.mapping.pipeline import Prepared

__all__ = ["SETTINGS", "SettingError", "connect", "given_settings", "main", "parse_args", "resolve_settings"]
__all__ += ["run", "values"]

log = ros_logger("airsim_mapper.node")
WAITING_FOR_SCENE = "no --scene: waiting for a scene file name on"  # logged with the topic, once waiting


def parse_args(argv: list[str]) -> argparse.Namespace:
    from airsim_mapper.common.resources import shipped_mappings
    from airsim_mapper.engine import MAX_FRAME_MB, SHUTDOWN_TIMEOUT_S

    *others, last = (f"--{switch}" for switch in SWITCHES_ONLY)
    switches_only = f"{', '.join(others)} and {last}"
    parser = argparse.ArgumentParser(
        description=__doc__.splitlines()[0],
        epilog=f"Each switch but {switches_only} is also a private parameter (~address, ~mapping, ...); "
        "the command line wins over the parameter, the parameter over the default.",
    )
    parser.add_argument(
        "--nodename",
        default=None,
        help='node name (default: "projectairsim", made unique as rospy\'s anonymous flag does)',
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
    parser.add_argument(
        "--ros",
        choices=sorted(FLAVOURS),
        default=None,
        help="the ROS to run on: 1 (rospy, .venv) or 2 (rclpy, .venv-ros2); default: the one importable",
    )
    args = parser.parse_args(argv)
    if not args.shutdown_timeout > 0:
        parser.error(f"--shutdown-timeout must be positive, got {args.shutdown_timeout}")
    if not 0 < args.max_frame_mb < float("inf"):
        parser.error(f"--max-frame-mb must be a positive number, got {args.max_frame_mb}")
    return args


DEFAULT_NODE_NAME = "projectairsim"
MASTER_POLL_S = 0.5  # how often a node started before its master asks again
MASTER_CONNECT_S = 1.0  # each time, how long a TCP connect to the master may take
STOP_CHECK_S = 1.0  # the main loop also checks for a stop this often, should a wake-up be missed


def node_identity(nodename: str | None, argv: list[str]) -> tuple[str, str]:
    """The node's name and ROS namespace as rospy will make them, known before `rospy.init_node`: a
    `__name:=` remapping, else --nodename, else "projectairsim" made unique the way rospy's anonymous flag
    does (so the mapping is expanded once, for the final name); the namespace from `__ns:=` or
    ROS_NAMESPACE."""
    import rosgraph.names

    mappings = rosgraph.names.load_mappings(argv)
    if "__name" in mappings:
        name = mappings["__name"]
    elif nodename:
        name = nodename
    else:
        name = f"{DEFAULT_NODE_NAME}_{os.getpid()}_{int(time.time() * 1000)}"  # rospy's anonymous name
    return name, rosgraph.names.get_ros_namespace(argv=argv)


def wait_for_master(period_s: float = MASTER_POLL_S) -> None:
    """Return once the ROS master answers, saying once on stderr that the node waits for it (as rospy's
    init_node would, but before anything is registered: a signal meanwhile exits at once)."""
    import rosgraph

    uri = rosgraph.get_master_uri()
    master = rosgraph.Master(f"/{DEFAULT_NODE_NAME}_waiting")
    said = False
    while not (listening(uri, MASTER_CONNECT_S) and master.is_online()):
        if not said:
            print(f"waiting for the ROS master at {uri}", file=sys.stderr, flush=True)
            said = True
        time.sleep(period_s)


def listening(uri: str, timeout: float) -> bool:
    """Whether something accepts TCP connections at `uri`'s host and port within `timeout` seconds (an
    XML-RPC call to a host that does not answer would wait for the system's connect timeout)."""
    from urllib.parse import urlsplit

    from airsim_mapper.common.ports import accepts_connections

    try:
        parts = urlsplit(uri)
        host, number = parts.hostname or "localhost", parts.port or 11311
    except ValueError:  # a port that is no number
        return False
    return accepts_connections(host, number, timeout)


def prepare_node(
    settings: dict[str, Any],
    node_name: str,
    namespace: str,
    known: Prepared | None = None,
    node_namespace: str = "",
    ros: int = 1,
) -> Prepared:
    """The node's mapping and start scene (mapping/pipeline.py's `prepare` on the node's settings; names
    checked against the rules of ROS `ros`)."""
    from airsim_mapper.mapping.pipeline import prepare

    sources = (settings["mapping"], settings["scene"], settings["simconfigpath"])
    return prepare(*sources, node_name, namespace, known, node_namespace, ros)


def config_problem(
    settings: dict[str, Any],
    node_name: str,
    namespace: str,
    known: Prepared | None = None,
    node_namespace: str = "",
    ros: int = 1,
) -> tuple[Prepared | None, str | None]:
    """(prepared, None), or (None, what to print) when the mapping or scene is invalid."""
    try:
        return prepare_node(settings, node_name, namespace, known, node_namespace, ros), None
    except ConfigError as exc:
        return None, str(exc)
    except OSError as exc:
        return None, f"{settings['mapping']}: {exc.strerror or exc}"


def serve_reload(engine: Any, spec: str, mapping: Any, watch: bool) -> Any:
    """Live reload: the `~reload_mapping` service (std_srvs/Trigger) and, with `watch`, the file watcher."""
    import rospy
    from std_srvs.srv import Trigger, TriggerResponse

    from airsim_mapper.engine import MappingReloader

    reloader = MappingReloader(engine, spec, mapping)

    def on_request(_request: Any) -> Any:
        outcome = reloader.reload("~reload_mapping")
        return TriggerResponse(success=outcome.ok, message=outcome.message)

    rospy.Service("~reload_mapping", Trigger, on_request)
    if watch:
        reloader.start()
        log.info("watching %s for changes (--no-watch turns this off)", ", ".join(reloader.files))
    return reloader


def main(argv: list[str] | None = None, early_signals: list[int] | None = None) -> int:
    """The node; `early_signals` are those the script noted while it was importing this module."""
    # First of all: until the node registers, a signal exits at once (reading the scene may take seconds on
    # a busy machine), and from then on it only raises the flag that every step below checks. Before, one
    # in the first second (imports, the mapping, init_node) ended in a traceback or the default action.
    stop = Stopper(0.0, at_once=True)  # its deadline, --shutdown-timeout, is read before it can matter
    stop.install()
    for number in early_signals or ():
        stop(number, None)
    files_before, files = raise_open_files()
    argv = sys.argv if argv is None else argv
    try:
        if choose(requested(argv[1:])) == "2":
            from airsim_mapper.cli import node_ros2

            return node_ros2.main(argv, stop, parse_args, config_problem)
    except FlavourError as exc:
        print(f"airsim-mapper-node: {exc}", file=sys.stderr)
        return 1
    import rospy

    args = parse_args(rospy.myargv(argv)[1:])
    stop.timeout = args.shutdown_timeout
    from airsim_mapper.cli.validate import format_table

    node_name, node_namespace = node_identity(args.nodename, sys.argv)  # rospy reads sys.argv's remappings
    given = given_settings(args)
    # The command line's values are checked before anything connects (the master may not be up).
    early_settings = values(resolve_settings(given))
    early_namespace = resolve_namespace(early_settings["namespace"], node_namespace)
    early, problem = config_problem(early_settings, node_name, early_namespace, None, node_namespace)
    if problem:
        print(problem, file=sys.stderr)
        return 1

    # rospy.init_node would wait for a master that is not up yet with the node half made, where a signal
    # can only be served by the stop deadline; waited for here, a signal still exits at once.
    wait_for_master()
    # rospy runs its shutdown hooks inside its signal handler, on whatever the main thread was doing: a
    # SIGINT during a service registration ran the engine's shutdown while the registration lock was held,
    # and the node hung (seen in CI). Here the handler only raises a flag; the hooks run from the loop below.
    stop.at_once = False  # rospy.init_node registers the node: a signal from now on shuts it down in order
    rospy.init_node(node_name, disable_signals=True)
    wait_for_rosout(stopping=lambda: bool(stop))  # so that the settings and the bridge table reach rosout.log
    try:
        resolved = resolve_settings(given, rospy.get_param)  # KeyError when unset
    except SettingError as exc:
        print(str(exc), file=sys.stderr)
        rospy.signal_shutdown("invalid parameter")
        return 1
    for name, setting in resolved.items():
        log.info("setting %s = %r (%s)", name, setting.value, setting.source)
    for warning in unread_parameters(rospy.get_param_names(), rospy.get_name()):
        log.warning(warning)
    settings = values(resolved)
    # Parameters may have changed the settings (then the mapping is prepared again); the name is rospy's.
    name = rospy.get_name().rsplit("/", 1)[-1]
    namespace = resolve_namespace(settings["namespace"], rospy.get_namespace())
    prepared, problem = config_problem(settings, name, namespace, early, ros_namespace(rospy.get_name()))
    if stop:
        rospy.signal_shutdown(f"signal {stop.signals[0]}")
        return 0
    if problem:
        print(problem, file=sys.stderr)
        rospy.signal_shutdown("invalid configuration")
        return 1
    if files != files_before:
        log.info("open files: the soft limit raised from %d to the hard limit, %d", files_before, files)
    if prepared.specs is not None and (shortage := shortfall(len(prepared.specs), files)):
        log.warning(shortage)

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
        names = namespace_variables(wrapper.namespace)
        if names["namespace"]:
            log.info(
                "namespace %r: topics under it, frames prefixed %r", names["namespace"], names["frame_prefix"]
            )
        else:
            log.info("no namespace: topics and frames as the mapping names them")
        if not settings["scene"]:
            topics = [b.ros for b in wrapper.bridges if b.converter == "load_scene"]
            waiting_on = " or ".join(topics) or "(the mapping has no load_scene rule)"
            log.info("%s %s", WAITING_FOR_SCENE, waiting_on)
        reloader = serve_reload(
            wrapper.engine, settings["mapping"], prepared.mapping, watch=not args.no_watch
        )
    rospy.on_shutdown(stop.wake)  # `rosnode kill`, or a shutdown requested from another thread
    while not stopping():
        stop.wait(STOP_CHECK_S)
    reason = signal.Signals(stop.signals[0]).name if stop else "shutdown requested"
    log.info("stopping (%s)", reason)
    if reloader is not None:
        reloader.stop()
    rospy.signal_shutdown(reason)
    return 0


def run(early_signals: list[int] | None = None) -> None:
    """The script's entry: main(), then leave without interpreter finalisation.

    pynng's atexit hook calls nng_fini, and nng aborts ("panic: pthread_mutex_lock") when a client thread
    still holds a request, which is what a simulator frozen at shutdown leaves behind. By the time main
    returns, ROS is shut down and the bridges are stopped; the logs are flushed and the process exits with
    main's status directly.
    """
    code = main(early_signals=early_signals)
    logging.shutdown()
    for stream in (sys.stdout, sys.stderr):
        with contextlib.suppress(Exception):
            stream.flush()
    os._exit(code)


if __name__ == "__main__":
    run()
