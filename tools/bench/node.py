"""The bridge node as the benchmark runs it: `projectairsim_node` with fast frames (default: views).

Modes: `views` (large bin values such as image pixels stay memoryviews of the received frame, so the
receive thread copies nothing and a frame dropped by its stream is never copied at all), `on` (pixels
sliced into bytes on the receive thread), `off` (the client's own msgpack path).

Until the engine installs fast frames itself, this entry point does what that wiring does: it installs the
proxy on the client's topics socket right after connecting (heavy = every callback on the topic is one of
the engine's stream slots) and resolves placeholders in `Stream.offer`. Both steps are idempotent, so this
also runs unchanged once the engine does it.

    python -m tools.bench.node [--fast-frames on|views|off] [--profile OUT.prof]
        [--switch-interval-ms MS] <node arguments>
"""

from __future__ import annotations

import contextlib
import cProfile
import pstats
import sys
import threading
from collections.abc import Callable
from typing import Any

from airsim_mapper.cli import node
from airsim_mapper.engine import streams
from tools.bench import recv_proxy as fast_frames


def only_streams(client: Any) -> Callable[[str], bool]:
    """True for a topic whose callbacks are all engine stream slots (so no mission script sees it)."""

    def heavy(topic: str) -> bool:
        entry = client.subs.get(topic)
        callbacks = entry["callbacks"] if entry else ()
        return bool(callbacks) and all(
            isinstance(getattr(cb, "__self__", None), streams.Stream) for cb in callbacks
        )

    return heavy


def enable_fast_frames(views: bool = False) -> None:
    connect = node.connect
    holder: dict[str, fast_frames.FastFrames] = {}

    def connect_fast(*args: Any, **kwargs: Any) -> Any:
        client = connect(*args, **kwargs)
        if client is not None:
            holder["fast"] = fast_frames.install(client, only_streams(client), views=views)
        return client

    offer = streams.Stream.offer

    def offer_resolved(self: streams.Stream, topic_info: Any, message: Any) -> None:
        fast = holder.get("fast")
        if fast is not None:
            try:
                message = fast.resolve(message)
            except fast_frames.ExpiredFrameError:
                return
        offer(self, topic_info, message)

    node.connect = connect_fast
    streams.Stream.offer = offer_resolved


def profile_all_threads() -> list[cProfile.Profile]:
    """cProfile every thread started from now on (each thread enables its own profiler on first call)."""
    profiles: list[cProfile.Profile] = []

    def start(_frame: Any, _event: str, _arg: Any) -> None:
        profile = cProfile.Profile()
        profiles.append(profile)
        profile.enable()

    threading.setprofile(start)
    main_profile = cProfile.Profile()
    profiles.append(main_profile)
    main_profile.enable()
    return profiles


def dump_profiles(profiles: list[cProfile.Profile], path: str) -> None:
    for profile in profiles:
        profile.disable()
    stats = pstats.Stats(profiles[0])
    for profile in profiles[1:]:
        with contextlib.suppress(TypeError):  # a profiler that never saw a call has no stats
            stats.add(profile)
    stats.dump_stats(path)


def _option(args: list[str], name: str, default: str | None) -> str | None:
    if name not in args:
        return default
    index = args.index(name)
    value = args[index + 1]
    del args[index : index + 2]
    return value


def main(argv: list[str] | None = None) -> int:
    args = list(sys.argv[1:] if argv is None else argv)
    mode = _option(args, "--fast-frames", "views")
    profile_path = _option(args, "--profile", None)
    switch_ms = _option(args, "--switch-interval-ms", None)
    if switch_ms is not None:
        sys.setswitchinterval(float(switch_ms) / 1e3)
    profiles = profile_all_threads() if profile_path else []
    if mode in ("on", "views"):
        enable_fast_frames(views=mode == "views")
    try:
        return node.main([sys.argv[0], *args])
    finally:
        if profile_path:
            dump_profiles(profiles, profile_path)


if __name__ == "__main__":
    sys.exit(main())
