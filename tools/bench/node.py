"""The bridge as the benchmark runs it: exactly as users start it.

`--as node` (default) runs the shipped node (`airsim_mapper.cli.node.main`); `--as mission` runs a mission
script as `scripts/hello_ros.py` builds it: the client, then `World`, then the wrapper, which takes over
the client's receive thread. Comparison baselines, not shipped paths: `--decode client` sends every frame
through msgpack, as the bare client decodes it; `--receive copy` receives with pynng's `recv` (two copies
of each frame); `--malloc glibc` leaves glibc's adaptive malloc thresholds. `--profile OUT.prof` cProfiles
every thread.

    python -m tools.bench.node [--as node|mission] [--decode bridge|client] [--receive view|copy]
        [--malloc fixed|glibc] [--profile OUT.prof] <node arguments>
"""

from __future__ import annotations

import signal
import sys
import threading

from airsim_mapper import wrapper
from airsim_mapper.cli import node
from airsim_mapper.engine import receive
from tools.bench.profiling import dump_profiles, profile_all_threads


def _option(args: list[str], name: str, default: str | None) -> str | None:
    if name not in args:
        return default
    index = args.index(name)
    value = args[index + 1]
    del args[index : index + 2]
    return value


def mission(argv: list[str]) -> int:
    """World first, then the wrapper on the same client, until SIGINT/SIGTERM (scripts/hello_ros.py)."""
    import rospy
    from projectairsim import ProjectAirSimClient, World

    from airsim_mapper.wrapper import ProjectAirSimWrapper

    args = node.parse_args(argv)
    settings = node.values(node.resolve_settings(node.given_settings(args)))
    rospy.init_node(args.nodename or "bench_mission", disable_signals=True)
    stop = threading.Event()
    for sig in (signal.SIGINT, signal.SIGTERM):
        signal.signal(sig, lambda *_: stop.set())
    client = ProjectAirSimClient(settings["address"], settings["topicsport"], settings["servicesport"])
    client.connect()
    config = settings["simconfigpath"]
    world = World(client, settings["scene"], sim_config_path=config.rstrip("/") + "/")
    bridge = ProjectAirSimWrapper(client, sim_config_path=config, tune_process=True)
    bridge.update_topics(world)
    stop.wait()
    rospy.signal_shutdown("benchmark done")
    client.disconnect()
    return 0


def main(argv: list[str] | None = None) -> int:
    args = list(sys.argv[1:] if argv is None else argv)
    runner = _option(args, "--as", "node")
    decode = _option(args, "--decode", "bridge")
    profile_path = _option(args, "--profile", None)
    if decode == "client":
        receive.FAST_MIN_BYTES = sys.maxsize  # the baseline: no frame is large enough for the fast path
    if _option(args, "--receive", "view") == "copy":  # comparison: pynng's own recv, which copies twice
        receive.receive_frame = lambda sock, block=True: sock.recv(block=block)
    if _option(args, "--malloc", "fixed") == "glibc":  # comparison: glibc's adaptive malloc thresholds
        wrapper.keep_frame_buffers = lambda: False
    profiles = profile_all_threads() if profile_path else []
    try:
        return mission(args) if runner == "mission" else node.main([sys.argv[0], *args])
    finally:
        if profile_path:
            dump_profiles(profiles, profile_path)


if __name__ == "__main__":
    sys.exit(main())
