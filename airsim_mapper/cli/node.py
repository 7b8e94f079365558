"""projectairsim_node: the bridge as a ROS node (python, rosrun and roslaunch).

Switches as the Project AirSim ROS bridge documentation gives them (--address, --nodename,
--simconfigpath, --servicesport, --topicsport), plus --mapping and --scene. An invalid mapping or scene
stops the node with the validate-mapping errors and exit code 1, before anything connects. A simulator
that is not running yet is waited for (one log line per attempt; backoff 0.5 s, then 2 s, then 5 s); one
that restarts later is reconnected to and the last scene reloaded, without restarting the node.

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
from functools import partial
from typing import Any

from airsim_mapper.engine.health import Backoff, SimUnreachable, open_client
from airsim_mapper.mapping.errors import ConfigError

log = logging.getLogger("rosout.airsim_mapper.node")


def parse_args(argv: list[str]) -> argparse.Namespace:
    from airsim_mapper.engine.engine import SHUTDOWN_TIMEOUT_S
    from airsim_mapper.resources import DEFAULT_MAPPING, shipped_mappings

    parser = argparse.ArgumentParser(prog="projectairsim_node.py", description=__doc__.splitlines()[0])
    parser.add_argument("--address", default="127.0.0.1", help="host running Project AirSim")
    parser.add_argument(
        "--nodename",
        default=None,
        help='node name (default: "projectairsim", made unique with rospy\'s anonymous flag)',
    )
    parser.add_argument("--simconfigpath", default="sim_config/", help="directory holding the scene configs")
    parser.add_argument("--servicesport", type=int, default=8990, help="Project AirSim services port")
    parser.add_argument("--topicsport", type=int, default=8989, help="Project AirSim pub-sub port")
    parser.add_argument(
        "--mapping",
        default=str(DEFAULT_MAPPING),
        help=f"mapping YAML file, or a shipped mapping's name ({', '.join(shipped_mappings())})",
    )
    parser.add_argument("--scene", default=None, help="scene config file to load at start")
    parser.add_argument("--namespace", default="", help="value of the <namespace> template variable")
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
    args = parser.parse_args(argv)
    if not args.shutdown_timeout > 0:
        parser.error(f"--shutdown-timeout must be positive, got {args.shutdown_timeout}")
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
    """Connect to the simulator, retrying with backoff until it answers or ROS shuts down (then None)."""
    import time

    sleep = sleep or time.sleep
    backoff = Backoff()
    while not is_shutdown():
        try:
            client = open_client(address, topicsport, servicesport)
        except SimUnreachable as exc:
            delay = backoff.next_delay()
            log.warning("%s; waiting for it: attempt %d, next in %.1f s", exc, backoff.attempt, delay)
            sleep(delay)
            continue
        if backoff.attempt:
            log.info("simulator at %s:%d/%d answered", address, topicsport, servicesport)
        return client
    return None


def serve_reload(engine: Any, spec: str, mapping: Any, watch: bool) -> Any:
    """Live reload: the `~reload_mapping` service (std_srvs/Trigger) and, with `watch`, the file watcher."""
    import rospy
    from std_srvs.srv import Trigger, TriggerResponse

    from airsim_mapper.engine.mapping_reload import MappingReloader

    reloader = MappingReloader(engine, spec, mapping)

    def on_request(_request: Any) -> Any:
        outcome = reloader.reload("~reload_mapping")
        return TriggerResponse(success=outcome.applied, message=outcome.message)

    rospy.Service("~reload_mapping", Trigger, on_request)
    if watch:
        reloader.start()
        log.info("watching %s for changes (--no-watch turns this off)", ", ".join(reloader.files))
    return reloader


def main(argv: list[str] | None = None) -> int:
    import rospy

    args = parse_args(rospy.myargv(argv if argv is not None else sys.argv)[1:])
    from airsim_mapper.cli.validate import format_table
    from airsim_mapper.mapping.expand import expand
    from airsim_mapper.mapping.loader import load_mapping
    from airsim_mapper.scene import read_scene

    node_name = args.nodename or "projectairsim"
    try:
        mapping = load_mapping(args.mapping)
        if args.scene:
            expand(mapping, read_scene(args.simconfigpath, args.scene), node_name, args.namespace)
    except ConfigError as exc:
        print(str(exc), file=sys.stderr)
        return 1
    except OSError as exc:
        print(f"{args.mapping}: {exc.strerror or exc}", file=sys.stderr)
        return 1

    # rospy runs its shutdown hooks inside its signal handler, on whatever the main thread was doing: a
    # SIGINT during a service registration ran the engine's shutdown while the registration lock was held,
    # and the node hung (seen in CI). Here the handler only raises a flag; the hooks run from the loop below.
    rospy.init_node(node_name, anonymous=args.nodename is None, disable_signals=True)
    stop = Stopper(args.shutdown_timeout)
    for sig in (signal.SIGINT, signal.SIGTERM):
        signal.signal(sig, stop)

    def stopping() -> bool:
        return bool(stop) or rospy.is_shutdown()

    from airsim_mapper.wrapper import ProjectAirSimWrapper, redirect_client_log

    redirect_client_log()
    client = connect(args.address, args.topicsport, args.servicesport, stopping)
    if client is None:
        rospy.signal_shutdown("stopped while waiting for the simulator")
        return 0
    wrapper = ProjectAirSimWrapper(
        client,
        sim_config_path=args.simconfigpath,
        mapping=mapping,
        node_name=rospy.get_name().lstrip("/"),
        namespace=args.namespace,
        disconnect_on_shutdown=True,  # this node made the client
        client_factory=partial(open_client, args.address, args.topicsport, args.servicesport),
        shutdown_timeout=max(0.5, args.shutdown_timeout - 1.5),  # rospy's own unregistering comes after
    )
    try:
        if args.scene:
            wrapper.load_scene(args.scene)
    except ConfigError as exc:
        print(str(exc), file=sys.stderr)
        rospy.signal_shutdown("invalid scene")
        return 1
    except Exception as exc:  # the simulator refused the scene: say why, without a traceback
        print(f"{args.scene}: the simulator could not load it: {type(exc).__name__}: {exc}", file=sys.stderr)
        rospy.signal_shutdown("scene not loaded")
        return 1
    log.info("bridges:\n%s", format_table(wrapper.bridges))
    reloader = serve_reload(wrapper.engine, args.mapping, mapping, watch=not args.no_watch)
    while not stopping():
        time.sleep(0.1)
    reloader.stop()
    rospy.signal_shutdown(f"signal {stop.signals[0]}" if stop else "shutdown requested")
    return 0


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
