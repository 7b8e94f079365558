"""Thread settings shared by the bridge and the headless server: one BLAS thread, a short GIL interval.

`tune_threads()` applies both unless `AIRSIM_MAPPER_NO_TUNING` is set (for side-by-side comparisons in
the soak). The bridge adds a rospy setting on top (`engine/process_tuning.py`).

One BLAS thread: numpy's OpenBLAS otherwise spins its idle workers on `sched_yield`.

The headless server multiplies ray directions by rotations for every camera, lidar and radar frame. Each
product large enough to use OpenBLAS's thread pool leaves its workers spinning afterwards, as system time
in the server that starves the bridge on a small machine (docs/reliability.md has the measurements). The
products here are small (N x 3 by 3 x 3): one thread is as fast, and spins nothing. The limit is set at
run time in numpy's own bundled library, so it works whatever was imported first and leaves other BLAS
users alone.

A 0.5 ms switch interval: a thread that blocks (a socket send, a sleep) gives up the GIL, and while a
CPU-bound thread runs it gets it back only after a switch interval, 5 ms by default. The server's
simulation thread and the bridge's receive loop block once per message, so the default would hold them
to about 200 messages a second.
"""

from __future__ import annotations

import ctypes
import os
import sys
from pathlib import Path

SWITCH_INTERVAL_S = 0.0005

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


# mallopt(3) parameters and the values the bridge sets: buffers up to the largest frame the link takes by
# default (--max-frame-mb 64) stay on the heap, and the heap keeps up to 128 MB of free top.
M_TRIM_THRESHOLD, M_MMAP_THRESHOLD = -1, -3
MMAP_THRESHOLD_BYTES = 64 * 1024 * 1024
TRIM_THRESHOLD_BYTES = 128 * 1024 * 1024


def keep_frame_buffers() -> bool:
    """Keep large frame buffers in the heap instead of returning them to the kernel after each frame.

    With its default, adaptive thresholds glibc gives a freed multi-megabyte buffer back (munmap, or
    `madvise(MADV_DONTNEED)` when it trims a thread's heap) and the next frame faults every page of it
    back in: a few thousand page faults per 1080p frame, a third of the bridge's CPU at 30 Hz
    (docs/performance.md). Fixed thresholds keep buffers up to 64 MB on the heap and the heap's free top
    up to 128 MB; both apply to every thread of the process from now on. False where there is no glibc
    `mallopt` (another C library), or when AIRSIM_MAPPER_NO_TUNING is set.
    """
    if os.environ.get("AIRSIM_MAPPER_NO_TUNING"):
        return False
    mallopt = getattr(ctypes.CDLL(None), "mallopt", None)
    if mallopt is None:
        return False
    mallopt.argtypes, mallopt.restype = (ctypes.c_int, ctypes.c_int), ctypes.c_int
    return bool(
        mallopt(M_MMAP_THRESHOLD, MMAP_THRESHOLD_BYTES) and mallopt(M_TRIM_THRESHOLD, TRIM_THRESHOLD_BYTES)
    )


def tune_threads(switch_interval_s: float = SWITCH_INTERVAL_S) -> bool:
    """One BLAS thread and a switch interval of at most `switch_interval_s`; False if tuning is off."""
    if os.environ.get("AIRSIM_MAPPER_NO_TUNING"):
        return False
    limit_blas_threads(1)
    sys.setswitchinterval(min(sys.getswitchinterval(), switch_interval_s))
    return True
