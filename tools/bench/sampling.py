"""/proc samples of the benchmark's processes: CPU seconds, minor page faults and resident memory, and the
cores used and faults taken between two."""

from __future__ import annotations

import os
import time
from dataclasses import dataclass

CLOCK_TICKS = os.sysconf("SC_CLK_TCK")
PAGE_BYTES = os.sysconf("SC_PAGE_SIZE")


@dataclass(frozen=True)
class CpuSample:
    """CPU seconds (user + system), minor page faults so far and resident memory of one process."""

    wall: float
    cpu_s: float
    rss_mb: float
    minor_faults: int = 0


def sample(pid: int) -> CpuSample:
    """utime + stime and minflt from /proc/<pid>/stat, the resident set size from /proc/<pid>/statm."""
    with open(f"/proc/{pid}/stat") as handle:
        fields = handle.read().rsplit(")", 1)[1].split()
    with open(f"/proc/{pid}/statm") as handle:
        resident_pages = int(handle.read().split()[1])
    cpu = (int(fields[11]) + int(fields[12])) / CLOCK_TICKS  # fields 14 and 15 of stat(5)
    faults = int(fields[7])  # field 10 of stat(5): minflt, every thread's
    return CpuSample(time.monotonic(), cpu, resident_pages * PAGE_BYTES / 2**20, faults)


def cpu_share(start: CpuSample, end: CpuSample) -> float:
    """Cores used between two samples (1.0 = one core busy all the time)."""
    return (end.cpu_s - start.cpu_s) / max(end.wall - start.wall, 1e-9)


def fault_rate(start: CpuSample, end: CpuSample) -> float:
    """Minor page faults per second between two samples."""
    return (end.minor_faults - start.minor_faults) / max(end.wall - start.wall, 1e-9)
