"""Helpers for the reliability tests: servers and nodes on fixed ports, probe nodes, process counters.

The pytest process never joins a ROS graph here (some tests restart the master): ROS is observed through
probe subprocesses (probe.py) and the simulator through a services-only client.
"""

from __future__ import annotations

import json
import math
import os
import time
from pathlib import Path

from harness import ROOT, Child, Rig, SimPorts, wait_until

from tools.rig import LOOPBACK

PROJECT_SIM_CONFIG = ROOT / "sim_config"
PROBE = Path(__file__).resolve().parent / "probe.py"
SCENE = "scene_drone_sensors.jsonc"
ROBOT = "/airsim_node/Drone1"
SIM_ROBOT = "/Sim/SceneDroneSensors/robots/Drone1"


def start_server(launcher: Rig, ports: SimPorts, wait: bool = True) -> Child:
    """The headless server on the given ports (so a restarted one is found at the same address)."""
    return launcher.simserver(ports=ports, wait=wait).process


def start_node(
    launcher: Rig, ports: SimPorts, *args: str, node_name: str = "rel", sim_config: Path = PROJECT_SIM_CONFIG
) -> Child:
    return launcher.node(ports, *args, node_name=node_name, sim_config=sim_config)


def probe(launcher: Rig, name: str, *args: str) -> Child:
    return launcher.python(f"probe_{name}", [str(PROBE), *args])


def wait_output(process: Child, text: str, timeout: float, start: int = 0) -> None:
    """Wait until `text` appears in the process's output after character `start`."""

    def seen() -> bool:
        if not process.alive() and text not in process.output()[start:]:
            raise AssertionError(f"{process.name} exited before printing {text!r}:\n{process.output()}")
        return text in process.output()[start:]

    wait_until(seen, timeout, interval=0.05, what=f"{text!r} from {process.name}")


def stamps(process: Child, tag: str = "MSG") -> list[float]:
    """The wall-clock receive times a `probe.py watch` printed."""
    return [float(line.split()[1]) for line in process.output().splitlines() if line.startswith(tag + " ")]


def statuses(process: Child) -> list[dict]:
    """The status messages a `probe.py status` printed, in order."""
    prefix = "STATUS "
    return [
        json.loads(line[len(prefix) :]) for line in process.output().splitlines() if line.startswith(prefix)
    ]


def task_and_fd_counts(pid: int) -> tuple[int, int]:
    return len(os.listdir(f"/proc/{pid}/task")), len(os.listdir(f"/proc/{pid}/fd"))


class SimView:
    """A services-only client for reading the robot's ground truth and sending setup commands."""

    def __init__(self, ports: SimPorts) -> None:
        from projectairsim import ProjectAirSimClient

        self.client = ProjectAirSimClient(LOOPBACK, ports.topics, ports.services)
        self.client.connect_services()

    def call(self, method: str, **params) -> object:
        return self.client.request({"method": method, "params": params, "version": 1.0})

    def position(self, robot: str = SIM_ROBOT) -> tuple[float, float, float]:
        pose = self.call(f"{robot}/GetGroundTruthPose")
        t = pose["translation"]
        return (t["x"], t["y"], t["z"])

    def ready(self, robot: str = SIM_ROBOT) -> None:
        for method in ("EnableApiControl", "Arm"):
            assert self.call(f"{robot}/{method}")

    def still(self, seconds: float, robot: str = SIM_ROBOT) -> float:
        """How far the robot moved during `seconds`."""
        start = self.position(robot)
        time.sleep(seconds)
        return math.dist(start, self.position(robot))

    def close(self) -> None:
        self.client.socket_services.close()


def restart_master(launcher: Rig, master) -> Child:
    """Kill the master and start a new one on the same port (the nodes keep running)."""
    import rosgraph

    old_pid = master.pid()
    master.process.stop()
    process = launcher.start("roscore", ["roscore", "-p", str(master.port)], env=master.env)

    def up() -> bool:
        try:
            pid = rosgraph.Master("/relkit", master_uri=master.uri).getPid()
        except Exception:
            return False
        return pid != old_pid

    wait_until(up, 30, what="the restarted master")
    return process


def unshare_available() -> bool:
    """`unshare --pid` works here (root, util-linux): a master can get a fresh PID namespace."""
    import shutil
    import subprocess

    if os.geteuid() != 0 or shutil.which("unshare") is None:
        return False
    probe_run = subprocess.run(
        ["unshare", "--pid", "--fork", "--kill-child", "--mount-proc", "true"],
        capture_output=True,
        timeout=10,
    )
    return probe_run.returncode == 0


def start_namespaced_master(launcher: Rig, port: int, env: dict[str, str]) -> Child:
    """roscore in a PID namespace of its own, as in a container: rosmaster gets the same pid every time."""
    argv = ["unshare", "--pid", "--fork", "--kill-child", "--mount-proc", "roscore", "-p", str(port)]
    return launcher.start("roscore_ns", argv, env=env)


def node_registrations(master_uri: str, node: str) -> tuple[int, int, int]:
    """How many publications, subscriptions and services the master has for `node`."""
    import rosgraph

    publishers, subscribers, services = rosgraph.Master("/relkit", master_uri=master_uri).getSystemState()
    return tuple(sum(node in nodes for _name, nodes in rows) for rows in (publishers, subscribers, services))
