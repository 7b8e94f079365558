"""Local processes for the demo, the soak, the bench, the screenshot and the tests: ports, starting, waiting,
stopping.

`free_port` picks from below the kernel's ephemeral range. A port that `bind(0)` hands out comes from that
range, and between choosing it and the child binding it, any outgoing connection on the machine may take
it as its local port ("Address in use"; seen once in CI).
"""

from __future__ import annotations

import contextlib
import os
import random
import signal
import socket
import subprocess
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

FALLBACK_EPHEMERAL_START = 32768
LOWEST_PORT = 20000


def _ephemeral_start() -> int:
    try:
        return int(Path("/proc/sys/net/ipv4/ip_local_port_range").read_text().split()[0])
    except (OSError, ValueError, IndexError):
        return FALLBACK_EPHEMERAL_START


def free_port() -> int:
    """A TCP port free on the loopback interface now, outside the ephemeral range when possible."""
    top = _ephemeral_start()
    for _ in range(200) if top - LOWEST_PORT > 1000 else ():
        port = random.randrange(LOWEST_PORT, top)
        with socket.socket() as sock:
            try:
                sock.bind(("127.0.0.1", port))
            except OSError:
                continue
            return port
    with socket.socket() as sock:
        sock.bind(("127.0.0.1", 0))
        return sock.getsockname()[1]


def wait_until(
    predicate: Callable[[], bool],
    timeout: float,
    what: str,
    interval: float = 0.05,
    error: type[Exception] = TimeoutError,
) -> None:
    """Poll `predicate` until it is true; raise `error` ("timed out after N s waiting for <what>") if not."""
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        if predicate():
            return
        time.sleep(interval)
    raise error(f"timed out after {timeout:.0f} s waiting for {what}")


def start_group(
    argv: Sequence[str], log_path: Path, env: dict[str, str], cwd: Path | str, **kwargs: Any
) -> subprocess.Popen:
    """Start `argv` in its own process group (so `stop_group` reaches its children), output to `log_path`."""
    with open(log_path, "wb") as log:
        return subprocess.Popen(
            list(argv),
            stdout=log,
            stderr=subprocess.STDOUT,
            stdin=subprocess.DEVNULL,
            env=env,
            cwd=str(cwd),
            start_new_session=True,
            **kwargs,
        )


def stat_fields(stat: str) -> list[str]:
    """Fields 3 onwards of a /proc/<pid>/stat line (after the command name, which may hold spaces and ')')."""
    return stat[stat.rindex(")") + 2 :].split()


def descendants(pids: set[int]) -> set[int]:
    """Every live descendant of `pids`, read from /proc (roslaunch puts its nodes in their own sessions)."""
    parents: dict[int, int] = {}
    for entry in Path("/proc").iterdir():
        if entry.name.isdigit():
            with contextlib.suppress(OSError, ValueError, IndexError):
                stat = (entry / "stat").read_text()
                parents[int(entry.name)] = int(stat_fields(stat)[1])  # field 4: the parent pid
    found: set[int] = set()
    frontier = set(pids)
    while frontier:
        frontier = {pid for pid, ppid in parents.items() if ppid in frontier and pid not in found}
        found |= frontier
    return found


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


def kill_tree(tree: set[int]) -> None:
    """SIGKILL the processes of `tree` and any descendants they have now."""
    for pid in tree | descendants(tree):
        with contextlib.suppress(ProcessLookupError, PermissionError):
            os.kill(pid, signal.SIGKILL)


def stop_group(popen: subprocess.Popen, grace_s: float = 10.0) -> None:
    """SIGINT to the child's group, wait up to `grace_s`, then SIGKILL whatever of the group is left,
    and every descendant that had moved to a group of its own (a roslaunch node whose roslaunch did not
    stop it in time would otherwise outlive it)."""
    tree = descendants({popen.pid})
    if popen.poll() is None:
        with contextlib.suppress(ProcessLookupError):
            os.killpg(popen.pid, signal.SIGINT)
        try:
            popen.wait(timeout=grace_s)
        except subprocess.TimeoutExpired:
            with contextlib.suppress(ProcessLookupError):
                os.killpg(popen.pid, signal.SIGKILL)
            popen.wait(timeout=10)
    with contextlib.suppress(ProcessLookupError, PermissionError):
        os.killpg(popen.pid, signal.SIGKILL)
    kill_tree(tree)
