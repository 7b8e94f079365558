"""One BLAS thread per process: numpy's OpenBLAS otherwise spins its idle workers on `sched_yield`.

The headless server multiplies ray directions by rotations for every camera, lidar and radar frame. Each
product large enough to use OpenBLAS's thread pool leaves its workers spinning afterwards; on a two-core
machine `make soak` measured 17,000 `sched_yield` calls a second and 82 % of a core in system time in the
server, which starved the bridge and stretched pose gaps to 200-300 ms. The products here are small
(N x 3 by 3 x 3): one thread is as fast, and spins nothing. The limit is set at run time in numpy's own
bundled library, so it works whatever was imported first and leaves other BLAS users alone.
"""

from __future__ import annotations

import ctypes
from pathlib import Path

SETTERS = ("openblas_set_num_threads64_", "openblas_set_num_threads", "scipy_openblas_set_num_threads64_")
GETTERS = ("openblas_get_num_threads64_", "openblas_get_num_threads", "scipy_openblas_get_num_threads64_")


def _openblas_libraries() -> list[str]:
    """Paths of the OpenBLAS libraries mapped into this process (numpy loads its own on import)."""
    import numpy  # noqa: F401  (loads numpy's BLAS)

    try:
        maps = Path("/proc/self/maps").read_text().splitlines()
    except OSError:
        return []
    return sorted({line.split()[-1] for line in maps if "openblas" in line.lower() and ".so" in line})


def _call_first(library: str, names: tuple[str, ...], *args: int) -> int | None:
    lib = ctypes.CDLL(library)
    for name in names:
        function = getattr(lib, name, None)
        if function is not None:
            result = function(*args)
            return int(result) if result is not None else 0
    return None


def limit_blas_threads(threads: int = 1) -> int:
    """Limit every OpenBLAS of this process to `threads`; returns how many libraries were limited."""
    done = 0
    for library in _openblas_libraries():
        if _call_first(library, SETTERS, threads) is not None:
            done += 1
    return done


def blas_threads() -> list[int]:
    """The thread count of each OpenBLAS in this process (for tests and diagnostics)."""
    counts = (_call_first(library, GETTERS) for library in _openblas_libraries())
    return [count for count in counts if count is not None]
