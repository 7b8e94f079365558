"""ROS graph name rules (as rosgraph.names.is_legal_name, restricted to ASCII), in pure Python."""

from __future__ import annotations

import re

_LEGAL = re.compile(r"[~/A-Za-z][A-Za-z0-9_/]*")


def ros_name_problem(name: str) -> str | None:
    """Why `name` is not a legal ROS topic or service name, or None when it is."""
    if not name:
        return "it is empty"
    if not _LEGAL.fullmatch(name):
        return "it must start with a letter, '/' or '~' and contain only letters, digits, '_' and '/'"
    if "//" in name:
        return "it contains '//'"
    if name.endswith("/"):
        return "it ends with '/'"
    return None


def resolve_namespace(namespace: str, node_namespace: str = "/") -> str:
    """A node's `--namespace` resolved like a ROS name inside the node's own ROS namespace: absolute
    (`/sim1`) as given, relative (`sim1`) below the node's namespace, empty as the node's namespace itself.
    The result is "" for the root, else `/a/b` (the <namespace> template variable)."""
    name = namespace.strip()
    full = name if name.startswith("/") else f"{node_namespace}/{name}"
    parts = [part for part in full.split("/") if part]
    return "/" + "/".join(parts) if parts else ""
