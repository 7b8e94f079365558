"""The node's open-file budget: the soft limit raised to the hard one at start, and a warning before a
scene starts when its bridges could need more files than that.

A topic costs no open file by itself (the tuned process watches rospy's connections with poll(2)); each
ROS peer of a bridge, a subscriber of a published topic or a publisher of a subscribed one, costs one
socket. So the need is the node's own files plus about one per bridge.
"""

from __future__ import annotations

import resource

OWN_FILES = 64  # the node's own: the master's and its XML-RPC sockets, the simulator's, logs, pipes
FILES_PER_BRIDGE = 1  # its first ROS peer's connection


def raise_open_files() -> tuple[int, int]:
    """Raise the soft RLIMIT_NOFILE to the hard limit; (before, after). Unchanged where it cannot be."""
    soft, hard = resource.getrlimit(resource.RLIMIT_NOFILE)
    if hard != resource.RLIM_INFINITY and soft < hard:
        try:
            resource.setrlimit(resource.RLIMIT_NOFILE, (hard, hard))
        except (ValueError, OSError):
            return soft, soft
        return soft, hard
    return soft, soft


def files_needed(bridges: int) -> int:
    """The open files a node running `bridges` bridges may need, each with one ROS peer."""
    return OWN_FILES + FILES_PER_BRIDGE * bridges


def shortfall(bridges: int, limit: int) -> str:
    """A warning when `bridges` may need more open files than `limit` allows, else ""."""
    needed = files_needed(bridges)
    if limit == resource.RLIM_INFINITY or needed <= limit:
        return ""
    return (
        f"the scene has {bridges} bridges: with a ROS peer each, the node needs about {needed} open files, "
        f"and its limit is {limit} (the hard limit of `ulimit -n`); raise it (ulimit -Hn, or LimitNOFILE= "
        "in a systemd unit), or the bridges past the limit will fail to connect"
    )
