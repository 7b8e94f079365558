"""Bridge integration helpers: rigs of (headless server + bridge node) on the session's master."""

from __future__ import annotations

from dataclasses import dataclass

from harness import ROOT, Launcher, Process, wait_until
from simharness import SimServer

NODE_SCRIPT = ROOT / "scripts" / "projectairsim_node.py"
SIM_CONFIG_DIR = ROOT / "sim_config"


@dataclass
class Rig:
    """A headless server and a bridge node attached to the session's master."""

    launcher: Launcher
    sim: SimServer
    node: Process | None
    node_name: str

    def start_node(self, *args: str, node_name: str = "bridge", wait_for: str | None = None) -> Process:
        self.node_name = node_name
        self.node = self.launcher.python(
            f"node_{node_name}",
            [
                str(NODE_SCRIPT),
                "--topicsport",
                str(self.sim.topics_port),
                "--servicesport",
                str(self.sim.services_port),
                "--simconfigpath",
                str(SIM_CONFIG_DIR),
                "--nodename",
                node_name,
                *args,
            ],
        )
        if wait_for:
            wait_topic(wait_for, self.node)
        return self.node

    def services_client(self):
        """A services-only client (the bridge holds the single topics connection)."""
        from projectairsim import ProjectAirSimClient

        client = ProjectAirSimClient(self.sim.address, self.sim.topics_port, self.sim.services_port)
        client.connect_services()
        return client


def published_topics() -> dict[str, str]:
    import rospy

    return dict(rospy.get_published_topics())


def wait_topic(topic: str, node: Process | None = None, timeout: float = 60.0) -> None:
    def up() -> bool:
        if node is not None and not node.alive():
            raise AssertionError(f"the bridge node exited:\n{node.output()}")
        return topic in published_topics()

    wait_until(up, timeout, interval=0.2, what=f"topic {topic}")


def wait_gone(topic: str, timeout: float = 30.0) -> None:
    wait_until(lambda: topic not in published_topics(), timeout, interval=0.2, what=f"{topic} to go away")
