"""/proc samples of the benchmark's processes: CPU seconds, minor page faults and resident memory, and the
cores used and faults taken between two."""

from __future__ import annotations

import contextlib
import os
import time
from dataclasses import dataclass

CLOCK_TICKS = os.sysconf("SC_CLK_TCK")
PAGE_BYTES = os.sysconf("SC_PAGE_SIZE")
# A measurement window is quiet when a hypervisor took less than this share of the machine's CPU time
# during it: 80 ms of the 16 s two cores give in an 8 s window. Quiet windows lose far less; past this
# both the latency and the processes' own CPU time move (docs/performance.md).
QUIET_STOLEN_SHARE = 0.005


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


def threads_cpu_s(pid: int) -> float:
    """CPU seconds so far of the process's live threads, to the nanosecond (the first field of each
    `/proc/<pid>/task/*/schedstat`): finer than stat(5)'s clock ticks, for a process that is mostly idle,
    but without the threads that have exited."""
    total = 0
    for tid in os.listdir(f"/proc/{pid}/task"):
        # a thread that exited meanwhile is skipped
        with contextlib.suppress(OSError), open(f"/proc/{pid}/task/{tid}/schedstat") as handle:
            total += int(handle.read().split()[0])
    return total / 1e9


def cpu_share(start: CpuSample, end: CpuSample) -> float:
    """Cores used between two samples (1.0 = one core busy all the time)."""
    return (end.cpu_s - start.cpu_s) / max(end.wall - start.wall, 1e-9)


def fault_rate(start: CpuSample, end: CpuSample) -> float:
    """Minor page faults per second between two samples."""
    return (end.minor_faults - start.minor_faults) / max(end.wall - start.wall, 1e-9)


@dataclass(frozen=True)
class HostSample:
    """The machine's CPU time so far, every core together, in clock ticks: all of it, and the part a
    hypervisor ran other guests in (steal)."""

    total: int
    stolen: int


def host_sample(stat: str | None = None) -> HostSample:
    """From the first line of /proc/stat (or `stat`, its text): user, nice, system, idle, iowait, irq,
    softirq and steal make the total (guest time is already in user and nice); steal is 0 where the
    kernel does not count it."""
    if stat is None:
        with open("/proc/stat") as handle:
            stat = handle.readline()
    values = [int(v) for v in stat.splitlines()[0].split()[1:9]]
    return HostSample(sum(values), values[7] if len(values) > 7 else 0)


def stolen_share(start: HostSample, end: HostSample) -> float:
    """The share of the machine's CPU time between two samples that the hypervisor took (0.0 to 1.0)."""
    return (end.stolen - start.stolen) / max(end.total - start.total, 1)


def p99(ordered: list[float]) -> float:
    """The 99th percentile of sorted values, as the bench reads it: the value at index 0.99 n."""
    return ordered[min(len(ordered) - 1, int(len(ordered) * 0.99))]


def wake_delays_ms(seconds: float = 2.0, period_s: float = 0.001) -> dict[str, float]:
    """How late a `period_s` sleep wakes on this host right now: the median, p99 and largest overshoot
    over `seconds` of back-to-back sleeps, in ms. On an idle machine this is the host's own scheduling
    delay, a lower bound on every latency the bench measures."""
    late: list[float] = []
    end = time.monotonic() + seconds
    while time.monotonic() < end:
        start = time.perf_counter()
        time.sleep(period_s)
        late.append((time.perf_counter() - start - period_s) * 1e3)
    ordered = sorted(late)
    return {
        "p50": ordered[len(ordered) // 2],
        "p99": p99(ordered),
        "max": ordered[-1],
    }
