"""cProfile over every thread of a bridge process, and the node run under it.

`python -m tools.bench.profiling OUT.prof <node arguments>` runs the shipped node (either flavour: the one
the interpreter imports) with every thread profiled, the stats of all of them written to OUT.prof at exit.
"""

from __future__ import annotations

import contextlib
import cProfile
import pstats
import sys
import threading
from typing import Any


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


def main(argv: list[str] | None = None) -> int:
    from airsim_mapper.cli import node

    path, *args = sys.argv[1:] if argv is None else argv
    profiles = profile_all_threads()
    try:
        return node.main([sys.argv[0], *args])
    finally:
        dump_profiles(profiles, path)


if __name__ == "__main__":
    sys.exit(main())
