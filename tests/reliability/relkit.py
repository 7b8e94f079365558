"""Helpers for the reliability tests: servers and nodes on fixed ports, probe nodes, process counters.

The pytest process never joins a ROS graph here (some tests restart the master): ROS is observed through
probe subprocesses (probe.py) and the simulator through a services-only client.
"""

from __future__ import annotations

import json
import math
import os
import time
from dataclasses import dataclass
from pathlib import Path

from harness import ROOT, Launcher, Process, free_port, wait_until
from simharness import ADDRESS, port_open

NODE_SCRIPT = ROOT / "scripts" / "projectairsim_node.py"
PROJECT_SIM_CONFIG = ROOT / "sim_config"
PROBE = Path(__file__).resolve().parent / "probe.py"
SCENE = "scene_drone_sensors.jsonc"
ROBOT = "/airsim_node/Drone1"
SIM_ROBOT = "/Sim/SceneDroneSensors/robots/Drone1"


@dataclass(frozen=True)
class Ports:
    topics: int
    services: int

    @classmethod
    def free(cls) -> Ports:
        topics = free_port()
        services = free_port()
        while services == topics:
            services = free_port()
        return cls(topics, services)


def start_server(launcher: Launcher, ports: Ports, wait: bool = True) -> Process:
    """The headless server on the given ports (so a restarted one is found at the same address)."""
    argv = ["-m", "airsim_mapper.simserver", "--address", ADDRESS]
    argv += ["--topicsport", str(ports.topics), "--servicesport", str(ports.services)]
    process = launcher.python("simserver", argv)
    if wait:
        wait_until(
            lambda: port_open(ADDRESS, ports.topics) and port_open(ADDRESS, ports.services),
            30,
            what="the simulator's ports",
        )
    return process


def start_node(
    launcher: Launcher,
    ports: Ports,
    *args: str,
    node_name: str = "rel",
    sim_config: Path = PROJECT_SIM_CONFIG,
) -> Process:
    argv = [str(NODE_SCRIPT), "--topicsport", str(ports.topics), "--servicesport", str(ports.services)]
    argv += ["--simconfigpath", str(sim_config), "--nodename", node_name, *args]
    return launcher.python(f"node_{node_name}", argv)


def probe(launcher: Launcher, name: str, *args: str) -> Process:
    return launcher.python(f"probe_{name}", [str(PROBE), *args])


def wait_output(process: Process, text: str, timeout: float, start: int = 0) -> None:
    """Wait until `text` appears in the process's output after character `start`."""

    def seen() -> bool:
        if not process.alive() and text not in process.output()[start:]:
            raise AssertionError(f"{process.name} exited before printing {text!r}:\n{process.output()}")
        return text in process.output()[start:]

    wait_until(seen, timeout, interval=0.05, what=f"{text!r} from {process.name}")


def stamps(process: Process, tag: str = "MSG") -> list[float]:
    """The wall-clock receive times a `probe.py watch` printed."""
    return [float(line.split()[1]) for line in process.output().splitlines() if line.startswith(tag + " ")]


def statuses(process: Process) -> list[dict]:
    """The status messages a `probe.py status` printed, in order."""
    prefix = "STATUS "
    return [
        json.loads(line[len(prefix) :]) for line in process.output().splitlines() if line.startswith(prefix)
    ]


def task_and_fd_counts(pid: int) -> tuple[int, int]:
    return len(os.listdir(f"/proc/{pid}/task")), len(os.listdir(f"/proc/{pid}/fd"))


class SimView:
    """A services-only client for reading the robot's ground truth and sending setup commands."""

    def __init__(self, ports: Ports) -> None:
        from projectairsim import ProjectAirSimClient

        self.client = ProjectAirSimClient(ADDRESS, ports.topics, ports.services)
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


def restart_master(launcher: Launcher, master) -> Process:
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
