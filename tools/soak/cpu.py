"""CPU accounting of the soak's processes from /proc: CPU time, nice value and a short name per process."""

from __future__ import annotations

import os
from dataclasses import dataclass
from pathlib import Path

from tools.rig import stat_fields


@dataclass(frozen=True)
class CpuMark:
    """The CPU time (user + system, seconds) and nice value of one process at one moment."""

    name: str
    seconds: float
    nice: int


def cpu_mark(name: str, pid: int, proc: Path = Path("/proc")) -> CpuMark | None:
    """`pid`'s CPU time so far and its nice value; None if it has gone."""
    try:
        fields = stat_fields((proc / str(pid) / "stat").read_text())
    except (OSError, ValueError):
        return None
    ticks = int(fields[11]) + int(fields[12])  # utime and stime: fields 14 and 15
    return CpuMark(name, ticks / os.sysconf("SC_CLK_TCK"), int(fields[16]))  # nice: field 19


def command_name(pid: int, proc: Path = Path("/proc")) -> str:
    """A short name for `pid`: the module of `python -m MODULE`, else the program's or script's file name."""
    try:
        argv = (proc / str(pid) / "cmdline").read_bytes().decode(errors="replace").split("\0")
    except OSError:
        return str(pid)
    argv = [arg for arg in argv if arg]
    if "-m" in argv[:-1]:
        return argv[argv.index("-m") + 1]
    if len(argv) > 1 and Path(argv[0]).name.startswith("python"):
        return Path(argv[1]).name
    return Path(argv[0]).name if argv else str(pid)


def cpu_shares(before: list[CpuMark], after: list[CpuMark], seconds: float) -> list[tuple[str, float, int]]:
    """(name, % of one core, nice) of each process marked at both moments, busiest first."""
    start = {mark.name: mark.seconds for mark in before}
    shares = [
        (mark.name, 100.0 * (mark.seconds - start[mark.name]) / max(seconds, 1e-9), mark.nice)
        for mark in after
        if mark.name in start
    ]
    return sorted(shares, key=lambda share: -share[1])
