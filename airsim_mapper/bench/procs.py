"""Processes of the end-to-end benchmark: a private roscore, children in their own sessions, /proc samples."""

from __future__ import annotations

import os
import shutil
import socket
import subprocess
import sys
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from pathlib import Path

from airsim_mapper import localproc
from airsim_mapper.localproc import free_port, start_group, stop_group

CLOCK_TICKS = os.sysconf("SC_CLK_TCK")
PAGE_BYTES = os.sysconf("SC_PAGE_SIZE")


class BenchError(RuntimeError):
    """The benchmark could not start or finish one of its runs."""


def wait_until(predicate: Callable[[], bool], timeout: float, what: str, interval: float = 0.05) -> None:
    localproc.wait_until(predicate, timeout, what, interval, BenchError)


@dataclass(frozen=True)
class CpuSample:
    """CPU seconds (user + system) and resident memory of one process at one moment."""

    wall: float
    cpu_s: float
    rss_mb: float


def sample(pid: int) -> CpuSample:
    """utime + stime from /proc/<pid>/stat and the resident set size from /proc/<pid>/statm."""
    with open(f"/proc/{pid}/stat") as handle:
        fields = handle.read().rsplit(")", 1)[1].split()
    with open(f"/proc/{pid}/statm") as handle:
        resident_pages = int(handle.read().split()[1])
    cpu = (int(fields[11]) + int(fields[12])) / CLOCK_TICKS  # fields 14 and 15 of stat(5)
    return CpuSample(time.monotonic(), cpu, resident_pages * PAGE_BYTES / 2**20)


def cpu_share(start: CpuSample, end: CpuSample) -> float:
    """Cores used between two samples (1.0 = one core busy all the time)."""
    return (end.cpu_s - start.cpu_s) / max(end.wall - start.wall, 1e-9)


@dataclass
class Child:
    name: str
    popen: subprocess.Popen
    log_path: Path

    @property
    def pid(self) -> int:
        return self.popen.pid

    def alive(self) -> bool:
        return self.popen.poll() is None

    def output(self) -> str:
        try:
            return self.log_path.read_text(errors="replace")[-4000:]
        except FileNotFoundError:
            return ""

    def stop(self, timeout: float = 10.0) -> None:
        """SIGINT to the child's own process group, then SIGKILL if it does not exit."""
        stop_group(self.popen, timeout)


@dataclass
class Processes:
    """Starts the benchmark's children; `stop_all` ends every one of them (by pid, newest first)."""

    workdir: Path
    env: dict[str, str]
    children: list[Child] = field(default_factory=list)

    def start(self, name: str, argv: Sequence[str]) -> Child:
        log_path = self.workdir / f"{name}.{len(self.children)}.log"
        child = Child(name, start_group(argv, log_path, self.env, Path.cwd()), log_path)
        self.children.append(child)
        return child

    def python(self, name: str, module: str, *args: str) -> Child:
        return self.start(name, [sys.executable, "-u", "-m", module, *args])

    def stop(self, child: Child) -> None:
        child.stop()
        if child in self.children:
            self.children.remove(child)

    def stop_all(self) -> None:
        for child in reversed(self.children):
            child.stop()
        self.children.clear()


def start_roscore(procs: Processes, timeout: float = 30.0) -> Child:
    """A private master on a free port; `procs.env` is pointed at it."""
    if shutil.which("roscore", path=procs.env.get("PATH")) is None:
        raise BenchError("roscore is not installed: run `make setup`")
    port = free_port()
    procs.env.update(
        ROS_MASTER_URI=f"http://localhost:{port}",
        ROS_HOSTNAME="localhost",
        ROS_LOG_DIR=str(procs.workdir / "ros_log"),
        ROS_HOME=str(procs.workdir / "ros_home"),
        PYTHONUNBUFFERED="1",
    )
    procs.env.pop("ROS_IP", None)
    child = procs.start("roscore", ["roscore", "-p", str(port)])

    def up() -> bool:
        if not child.alive():
            raise BenchError(f"roscore exited early:\n{child.output()}")
        import rosgraph

        try:
            return rosgraph.Master("/bench", master_uri=procs.env["ROS_MASTER_URI"]).getPid() is not None
        except Exception:
            return False

    wait_until(up, timeout, f"roscore on port {port}")
    return child


def port_open(port: int) -> bool:
    with socket.socket() as sock:
        sock.settimeout(0.2)
        return sock.connect_ex(("127.0.0.1", port)) == 0
