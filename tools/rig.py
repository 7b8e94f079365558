"""The one process rig of the demo, the bench, the soak, the screenshot and the tests.

A `Rig` starts real processes on this machine, a private roscore, the headless server, the bridge node or a
mission script, each in a session of its own with its output in a log file under the rig's work directory.
It waits for ports and topics, and stops whole process trees: roslaunch puts its nodes in sessions of their
own and the server's render worker has one too, so stopping a child also kills any descendant that outlived
it.

Ports come from below the kernel's ephemeral range: a port that `bind(0)` hands out comes from that range,
and between choosing it and the child binding it, any outgoing connection on the machine may take it.
"""

from __future__ import annotations

import contextlib
import os
import random
import shutil
import signal
import socket
import subprocess
import sys
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

ROOT = Path(__file__).resolve().parent.parent
NODE_SCRIPT = ROOT / "scripts" / "projectairsim_node.py"
SIM_CONFIG = ROOT / "sim_config"
LOOPBACK = "127.0.0.1"
FALLBACK_EPHEMERAL_START = 32768
LOWEST_PORT = 20000


class RigError(RuntimeError):
    """A process the rig started did not come up, or exited early (the message names it and its log)."""


def free_port() -> int:
    """A TCP port free on the loopback interface now, outside the ephemeral range when possible."""
    top = _ephemeral_start()
    for _ in range(200) if top - LOWEST_PORT > 1000 else ():
        port = random.randrange(LOWEST_PORT, top)
        with socket.socket() as sock:
            try:
                sock.bind((LOOPBACK, port))
            except OSError:
                continue
            return port
    with socket.socket() as sock:
        sock.bind((LOOPBACK, 0))
        return sock.getsockname()[1]


def _ephemeral_start() -> int:
    try:
        return int(Path("/proc/sys/net/ipv4/ip_local_port_range").read_text().split()[0])
    except (OSError, ValueError, IndexError):
        return FALLBACK_EPHEMERAL_START


def port_open(port: int, address: str = LOOPBACK) -> bool:
    """True when something accepts TCP connections on `address:port`."""
    with socket.socket() as sock:
        sock.settimeout(0.2)
        return sock.connect_ex((address, port)) == 0


def wait_until(
    predicate: Callable[[], bool],
    timeout: float,
    what: str = "condition",
    interval: float = 0.05,
    error: type[Exception] = RigError,
) -> None:
    """Poll `predicate` until it is true; raise `error` ("timed out after N s waiting for <what>") if not."""
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        if predicate():
            return
        time.sleep(interval)
    raise error(f"timed out after {timeout:.0f} s waiting for {what}")


def stat_fields(stat: str) -> list[str]:
    """Fields 3 onwards of a /proc/<pid>/stat line (after the command name, which may hold spaces and ')')."""
    return stat[stat.rindex(")") + 2 :].split()


def descendants(pids: set[int]) -> set[int]:
    """Every live descendant of `pids`, read from /proc."""
    parents: dict[int, int] = {}
    for entry in Path("/proc").iterdir():
        if entry.name.isdigit():
            with contextlib.suppress(OSError, ValueError, IndexError):
                parents[int(entry.name)] = int(stat_fields((entry / "stat").read_text())[1])
    found: set[int] = set()
    frontier = set(pids)
    while frontier:
        frontier = {pid for pid, ppid in parents.items() if ppid in frontier and pid not in found}
        found |= frontier
    return found


def kill_tree(tree: set[int]) -> None:
    """SIGKILL the processes of `tree` and any descendants they have now."""
    for pid in tree | descendants(tree):
        with contextlib.suppress(ProcessLookupError, PermissionError):
            os.kill(pid, signal.SIGKILL)


def _signal_group(pgid: int, sig: int) -> None:
    with contextlib.suppress(ProcessLookupError, PermissionError):
        os.killpg(pgid, sig)


def stop_group(popen: subprocess.Popen, grace_s: float = 10.0, sig: int = signal.SIGINT) -> int:
    """`sig` to the child's group, then SIGABRT after `grace_s` (Python children started with
    `-X faulthandler` dump every thread's stack to their log), then SIGKILL to whatever of the group is
    left and to every descendant that had moved to a session of its own. Returns the exit code."""
    tree = descendants({popen.pid})
    if popen.poll() is None:
        _signal_group(popen.pid, sig)
        try:
            popen.wait(timeout=grace_s)
        except subprocess.TimeoutExpired:
            _signal_group(popen.pid, signal.SIGABRT)
            try:
                popen.wait(timeout=3.0)
            except subprocess.TimeoutExpired:
                _signal_group(popen.pid, signal.SIGKILL)
                popen.wait(timeout=5.0)
    _signal_group(popen.pid, signal.SIGKILL)
    kill_tree(tree)
    return popen.returncode


@dataclass
class Child:
    """One started process (the leader of its own session) and the file its output goes to."""

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
            return self.log_path.read_text(errors="replace")
        except FileNotFoundError:
            return ""

    def wait(self, timeout: float) -> int:
        return self.popen.wait(timeout=timeout)

    def stop(self, sig: int = signal.SIGINT, timeout: float = 10.0) -> int:
        return stop_group(self.popen, timeout, sig)

    def check_alive(self) -> None:
        """Raise RigError with the end of the log if the process has exited."""
        if not self.alive():
            tail = self.output()[-4000:]
            raise RigError(f"{self.name} exited with {self.popen.returncode}; {self.log_path}:\n{tail}")


@dataclass(frozen=True)
class SimPorts:
    """The headless server's two ports."""

    topics: int
    services: int

    @classmethod
    def free(cls) -> SimPorts:
        topics = free_port()
        services = free_port()
        while services == topics:
            services = free_port()
        return cls(topics, services)

    def args(self) -> list[str]:
        return ["--topicsport", str(self.topics), "--servicesport", str(self.services)]


@dataclass(frozen=True)
class SimServer:
    """A running headless server: its process and ports."""

    process: Child
    ports: SimPorts
    address: str = LOOPBACK

    @property
    def topics_port(self) -> int:
        return self.ports.topics

    @property
    def services_port(self) -> int:
        return self.ports.services

    def client(self):
        """A connected `projectairsim` client (the caller disconnects it)."""
        from projectairsim import ProjectAirSimClient

        client = ProjectAirSimClient(self.address, self.ports.topics, self.ports.services)
        client.connect()
        return client

    def services_client(self):
        """A services-only client, for when a bridge holds the single topics connection."""
        from projectairsim import ProjectAirSimClient

        client = ProjectAirSimClient(self.address, self.ports.topics, self.ports.services)
        client.connect_services()
        return client


@dataclass
class RosMaster:
    """A private roscore started by a rig."""

    port: int
    uri: str
    env: dict[str, str]
    process: Child

    def pid(self) -> int | None:
        """The master's pid as the master reports it; None while it does not answer."""
        return master_pid(self.uri)


def master_pid(uri: str) -> int | None:
    import rosgraph

    try:
        return rosgraph.Master("/rig", master_uri=uri).getPid()
    except Exception:
        return None


def ros_environment(base: dict[str, str], workdir: Path, master_port: int) -> dict[str, str]:
    """`base` pointed at a private master on `master_port`, with ROS's files kept under `workdir`."""
    env = dict(base)
    env.update(
        ROS_MASTER_URI=f"http://localhost:{master_port}",
        ROS_HOSTNAME="localhost",
        ROS_LOG_DIR=str(workdir / "ros_log"),
        ROS_HOME=str(workdir / "ros_home"),
        ROS_PACKAGE_PATH=f"{ROOT}{os.pathsep}/usr/share",
    )
    env.pop("ROS_IP", None)
    return env


def published_topics(uri: str) -> dict[str, str]:
    """Topic -> type of everything published on the master at `uri` (no ROS node needed)."""
    import rosgraph

    return dict(rosgraph.Master("/rig", master_uri=uri).getPublishedTopics(""))


@dataclass
class Rig:
    """Starts processes for one job and stops every one of them (newest first) when it ends."""

    workdir: Path
    env: dict[str, str] = field(default_factory=lambda: dict(os.environ))
    cwd: Path = ROOT
    children: list[Child] = field(default_factory=list)
    master: RosMaster | None = None

    def __post_init__(self) -> None:
        self.workdir.mkdir(parents=True, exist_ok=True)
        venv_bin = str(Path(sys.executable).parent)
        if not self.env.get("PATH", "").startswith(venv_bin):
            self.env["PATH"] = f"{venv_bin}{os.pathsep}{self.env.get('PATH', '')}"
        self.env["PYTHONUNBUFFERED"] = "1"

    def __enter__(self) -> Rig:
        return self

    def __exit__(self, *exc: object) -> None:
        self.stop_all()

    def start(
        self,
        name: str,
        argv: Sequence[str],
        env: dict[str, str] | None = None,
        cwd: Path | None = None,
        **popen_kwargs: Any,
    ) -> Child:
        """Start `argv` in a session of its own, output to `<workdir>/<name>.<n>.log`."""
        log_path = self.workdir / f"{name}.{len(self.children)}.log"
        with open(log_path, "wb") as log:
            popen = subprocess.Popen(
                list(argv),
                stdout=log,
                stderr=subprocess.STDOUT,
                stdin=subprocess.DEVNULL,
                env={**self.env, **(env or {})},
                cwd=str(cwd or self.cwd),
                start_new_session=True,
                **popen_kwargs,
            )
        child = Child(name, popen, log_path)
        self.children.append(child)
        return child

    def python(self, name: str, args: Sequence[str], **kwargs: Any) -> Child:
        """Run a Python script or `-m module` with this interpreter (faulthandler on, unbuffered)."""
        return self.start(name, [sys.executable, "-u", "-X", "faulthandler", *args], **kwargs)

    def roscore(self, timeout: float = 60.0) -> RosMaster:
        """A private master on a free port; the rig's environment points every later child at it."""
        if shutil.which("roscore", path=self.env.get("PATH")) is None:
            raise RigError("roscore is not installed: run `make setup` (Debian package ros-core)")
        port = free_port()
        self.env = ros_environment(self.env, self.workdir, port)
        process = self.start("roscore", ["roscore", "-p", str(port)])
        master = RosMaster(port, self.env["ROS_MASTER_URI"], self.env, process)

        def up() -> bool:
            process.check_alive()
            return master.pid() is not None

        wait_until(up, timeout, f"roscore on port {port}")
        self.master = master
        return master

    def simserver(
        self, *args: str, ports: SimPorts | None = None, wait: bool = True, timeout: float = 30.0
    ) -> SimServer:
        """The headless server on loopback (free ports unless given); waits until both ports accept."""
        ports = ports or SimPorts.free()
        argv = ["-m", "airsim_mapper.simserver", "--address", LOOPBACK, *ports.args(), *args]
        process = self.python("simserver", argv)
        if wait:
            self.wait_ports(process, (ports.topics, ports.services), timeout)
        return SimServer(process, ports)

    def node(
        self, ports: SimPorts, *args: str, node_name: str = "projectairsim", sim_config: Path = SIM_CONFIG
    ) -> Child:
        """The bridge node, as `rosrun projectairsim_ros projectairsim_node.py` starts it."""
        argv = [str(NODE_SCRIPT), *ports.args(), "--simconfigpath", str(sim_config)]
        return self.python(f"node_{node_name}", [*argv, "--nodename", node_name, *args])

    def wait_ports(self, child: Child, ports: Sequence[int], timeout: float = 30.0) -> None:
        """Wait until every port accepts connections; fail at once if `child` exits."""

        def up() -> bool:
            child.check_alive()
            return all(port_open(port) for port in ports)

        wait_until(up, timeout, f"{child.name} on ports {'/'.join(map(str, ports))}")

    def wait_topics(self, topics: Sequence[str], child: Child | None = None, timeout: float = 60.0) -> None:
        """Wait until every topic is published on the rig's master; fail at once if `child` exits."""
        uri = self.env["ROS_MASTER_URI"]

        def up() -> bool:
            if child is not None:
                child.check_alive()
            return set(topics) <= published_topics(uri).keys()

        wait_until(up, timeout, f"topics {', '.join(topics)}", interval=0.2)

    def stop(self, child: Child, timeout: float = 10.0) -> int:
        code = child.stop(timeout=timeout)
        with contextlib.suppress(ValueError):
            self.children.remove(child)
        return code

    def stop_all(self, timeout: float = 10.0) -> None:
        """Stop every child, newest first (their logs stay readable through `dump_logs`)."""
        for child in reversed(self.children):
            child.stop(timeout=timeout)

    def dump_logs(self) -> str:
        return "\n".join(
            f"----- {child.name} (exit {child.popen.returncode}) -----\n{child.output()}"
            for child in self.children
        )
