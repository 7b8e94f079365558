"""Bridge integration helpers: rigs of (headless server + bridge node) on the session's master."""

from __future__ import annotations

from dataclasses import dataclass

from harness import Child, Rig, SimServer, wait_until


@dataclass
class Stack:
    """A headless server and a bridge node attached to the session's master."""

    launcher: Rig
    sim: SimServer
    node: Child | None
    node_name: str

    def start_node(self, *args: str, node_name: str = "bridge", wait_for: str | None = None) -> Child:
        self.node_name = node_name
        self.node = self.launcher.node(self.sim.ports, *args, node_name=node_name)
        if wait_for:
            wait_topic(wait_for, self.node)
        return self.node

    def services_client(self):
        """A services-only client (the bridge holds the single topics connection)."""
        return self.sim.services_client()


def published_topics() -> dict[str, str]:
    import rospy

    return dict(rospy.get_published_topics())


def wait_topic(topic: str, node: Child | None = None, timeout: float = 60.0) -> None:
    def up() -> bool:
        if node is not None and not node.alive():
            raise AssertionError(f"the bridge node exited:\n{node.output()}")
        return topic in published_topics()

    wait_until(up, timeout, interval=0.2, what=f"topic {topic}")


def wait_gone(topic: str, timeout: float = 30.0) -> None:
    wait_until(lambda: topic not in published_topics(), timeout, interval=0.2, what=f"{topic} to go away")
