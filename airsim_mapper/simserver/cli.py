"""`airsim-mapper-sim`: run the headless Project AirSim-compatible server until SIGINT/SIGTERM."""

from __future__ import annotations

import argparse
import logging
import os
import signal
import sys
import threading
from collections.abc import Sequence

from airsim_mapper.common.ports import SERVICES_PORT, TOPICS_PORT, port
from airsim_mapper.common.tuning import tune_threads
from airsim_mapper.simserver.render import rendering
from airsim_mapper.simserver.render.render_worker import RENDER_NICE
from airsim_mapper.simserver.server import ServerOptions, SimServer


def parse_args(argv: Sequence[str] | None = None) -> argparse.Namespace:
    parser = argparse.ArgumentParser(
        prog="airsim-mapper-sim",
        description="Headless simulator server speaking the protocol of the projectairsim 1.1.0 client.",
    )
    parser.add_argument(
        "--address",
        default="127.0.0.1",
        help="bind address (default 127.0.0.1; another address is reachable from the network with no "
        "authentication, and the server warns)",
    )
    parser.add_argument(
        "--topicsport", type=port, default=TOPICS_PORT, help=f"topics (Pair0) port, default {TOPICS_PORT}"
    )
    parser.add_argument(
        "--servicesport",
        type=port,
        default=SERVICES_PORT,
        help=f"services (Rep0) port, default {SERVICES_PORT}",
    )
    parser.add_argument(
        "--world", default=None, help="world file (JSON or YAML); default: the built-in world"
    )
    parser.add_argument("--pose-rate", type=float, default=100.0, help="actual_pose publish rate in Hz")
    parser.add_argument(
        "--render-nice",
        type=int,
        default=RENDER_NICE,
        help=f"render cameras in a child process this much nicer than the server (default {RENDER_NICE})",
    )
    parser.add_argument(
        "--render-in-process",
        action="store_true",
        help="render cameras on the server's camera thread instead of a child process",
    )
    parser.add_argument(
        "--renderer",
        choices=rendering.RENDERERS,
        default=None,
        help=f"camera renderer: gl (OpenGL on headless EGL; the default) or raycast (the numpy reference, "
        f"much slower); default: ${rendering.RENDERER_ENV}, else gl. Without an OpenGL context gl falls back "
        "to raycast and says so once",
    )
    parser.add_argument(
        "--log-level", default="INFO", choices=["DEBUG", "INFO", "WARNING", "ERROR"], help="logging level"
    )
    return parser.parse_args(argv)


def main(argv: Sequence[str] | None = None) -> int:
    args = parse_args(argv)
    tune_threads()  # the sensor thread renders while the simulation thread must tick on time
    logging.basicConfig(level=args.log_level, format="%(asctime)s %(levelname)s %(name)s: %(message)s")
    log = logging.getLogger("airsim_mapper.simserver")
    if args.pose_rate <= 0:
        log.error("--pose-rate must be positive, got %s", args.pose_rate)
        return 2
    if args.renderer is not None:  # the render worker inherits the environment
        os.environ[rendering.RENDERER_ENV] = args.renderer
        rendering.select_renderer(args.renderer)
    options = ServerOptions(
        address=args.address,
        topics_port=args.topicsport,
        services_port=args.servicesport,
        world_path=args.world,
        pose_rate_hz=args.pose_rate,
        render_nice=None if args.render_in_process else args.render_nice,
    )
    try:
        server = SimServer(options)
    except Exception as exc:  # a bad world file or a busy port: say so and exit non-zero
        log.error("cannot start: %s", exc)
        return 1
    stop = threading.Event()
    for sig in (signal.SIGINT, signal.SIGTERM):
        signal.signal(sig, lambda *_: stop.set())
    server.start()
    print(f"airsim-mapper-sim ready: topics {args.topicsport}, services {args.servicesport}", flush=True)
    while not stop.wait(0.5):
        pass
    log.info("stopping")
    server.stop()
    log.info("stopped")
    return 0


if __name__ == "__main__":
    sys.exit(main())
