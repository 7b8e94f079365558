"""Test harness: a private roscore per test and subprocesses that are always cleaned up.

Everything here starts real processes: a real ROS master, nodes run with the venv's interpreter. Each
process runs in its own process group, so teardown stops it and everything it started.
"""

from __future__ import annotations

import contextlib
import os
import shutil
import signal
import subprocess
import sys
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path

from airsim_mapper import localproc
from airsim_mapper.localproc import free_port

ROOT = Path(__file__).resolve().parent.parent
SHARED = ROOT.parent / "shared"
SIM_CONFIG = SHARED / "sim_config"
VENV_BIN = Path(sys.executable).parent


class HarnessError(RuntimeError):
    """The harness could not start what a test needs."""


def wait_until(predicate, timeout: float, interval: float = 0.05, what: str = "condition") -> None:
    """Poll `predicate` until it returns true, or raise HarnessError after `timeout` seconds."""
    localproc.wait_until(predicate, timeout, what, interval, HarnessError)


@dataclass
class Process:
    """A subprocess in its own process group, with its output captured to a log file."""

    name: str
    popen: subprocess.Popen
    log_path: Path

    def output(self) -> str:
        try:
            return self.log_path.read_text(errors="replace")
        except FileNotFoundError:
            return ""

    def alive(self) -> bool:
        return self.popen.poll() is None

    def wait(self, timeout: float) -> int:
        return self.popen.wait(timeout=timeout)

    def stop(self, sig: int = signal.SIGINT, timeout: float = 10.0) -> int:
        """Signal the whole process group, wait, and escalate to SIGKILL if needed; descendants in groups
        of their own (roslaunch's nodes) are killed too."""
        tree = localproc.descendants({self.popen.pid})
        if self.popen.poll() is None:
            _signal_group(self.popen.pid, sig)
            try:
                self.popen.wait(timeout=timeout)
            except subprocess.TimeoutExpired:
                # Python children run with -X faulthandler: SIGABRT dumps every thread's stack to the log.
                _signal_group(self.popen.pid, signal.SIGABRT)
                try:
                    self.popen.wait(timeout=3)
                except subprocess.TimeoutExpired:
                    _signal_group(self.popen.pid, signal.SIGKILL)
                    self.popen.wait(timeout=5)
        # Children that outlived the leader still belong to the group.
        _signal_group(self.popen.pid, signal.SIGKILL)
        localproc.kill_tree(tree)
        return self.popen.returncode


def _signal_group(pgid: int, sig: int) -> None:
    with contextlib.suppress(ProcessLookupError, PermissionError):
        os.killpg(pgid, sig)


@dataclass
class Launcher:
    """Starts processes for one test and stops every one of them at teardown."""

    workdir: Path
    env: dict[str, str]
    processes: list[Process] = field(default_factory=list)

    def start(
        self, name: str, argv: Sequence[str], env: dict[str, str] | None = None, cwd: Path | None = None
    ) -> Process:
        log_path = self.workdir / f"{name}.{len(self.processes)}.log"
        log = open(log_path, "wb")  # noqa: SIM115 - closed by the child's exit; the parent keeps no handle
        try:
            popen = subprocess.Popen(
                list(argv),
                stdout=log,
                stderr=subprocess.STDOUT,
                stdin=subprocess.DEVNULL,
                env={**self.env, **(env or {})},
                cwd=str(cwd or ROOT),
                start_new_session=True,
            )
        finally:
            log.close()
        proc = Process(name, popen, log_path)
        self.processes.append(proc)
        return proc

    def python(self, name: str, script_and_args: Sequence[str], **kwargs) -> Process:
        """Run a Python script or `-m module` with the venv's interpreter."""
        return self.start(name, [sys.executable, "-u", "-X", "faulthandler", *script_and_args], **kwargs)

    def stop_all(self) -> None:
        for proc in reversed(self.processes):
            proc.stop()

    def dump_logs(self) -> str:
        parts = []
        for proc in self.processes:
            parts.append(f"----- {proc.name} (exit {proc.popen.returncode}) -----\n{proc.output()}")
        return "\n".join(parts)


@dataclass
class RosMaster:
    """A private roscore: its URI and the environment that points ROS tools at it."""

    port: int
    uri: str
    env: dict[str, str]
    process: Process

    def pid(self) -> int | None:
        import rosgraph

        try:
            return rosgraph.Master("/harness", master_uri=self.uri).getPid()
        except Exception:
            return None


def ros_environment(workdir: Path, port: int) -> dict[str, str]:
    env = dict(os.environ)
    env.update(
        ROS_MASTER_URI=f"http://localhost:{port}",
        ROS_HOSTNAME="localhost",
        ROS_LOG_DIR=str(workdir / "ros_log"),
        ROS_HOME=str(workdir / "ros_home"),
        ROS_PACKAGE_PATH=f"{ROOT.parent}:/usr/share",
        PATH=f"{VENV_BIN}{os.pathsep}{env.get('PATH', '')}",
        PYTHONUNBUFFERED="1",
    )
    env.pop("ROS_IP", None)
    return env


def start_master(launcher: Launcher, timeout: float = 30.0) -> RosMaster:
    """Start roscore on a free port and wait until the master answers."""
    if shutil.which("roscore", path=launcher.env.get("PATH")) is None:
        raise HarnessError("roscore is not installed: run `make setup` (Debian package ros-core)")
    port = free_port()
    env = ros_environment(launcher.workdir, port)
    launcher.env = env
    proc = launcher.start("roscore", ["roscore", "-p", str(port)], env=env)
    master = RosMaster(port, env["ROS_MASTER_URI"], env, proc)

    def up() -> bool:
        if not proc.alive():
            raise HarnessError(f"roscore exited early:\n{proc.output()}")
        return master.pid() is not None

    wait_until(up, timeout, what=f"roscore on port {port}")
    return master
