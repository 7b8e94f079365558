"""ROS graph name rules (as rosgraph.names.is_legal_name, restricted to ASCII), in pure Python, and the
did-you-mean every name check gives."""

from __future__ import annotations

import difflib
import re
from typing import Any

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


def resolve_name(name: str, node_name: str, node_namespace: str = "") -> str:
    """A legal ROS name as rospy resolves it for the node `node_name` in `node_namespace` ("" for the root,
    else `/a/b`), before remappings: absolute as written, private (`~x`) below the node, relative (`x`)
    in the node's namespace."""
    namespace = node_namespace.rstrip("/")
    if name.startswith("/"):
        return name
    if name.startswith("~"):
        return f"{namespace}/{node_name.strip('/')}/{name[1:].lstrip('/')}"
    return f"{namespace}/{name}"


def ros_namespace(ros_name: str) -> str:
    """The namespace ("" for the root, else `/a/b`) of a node's full ROS name (`/a/b/node`)."""
    return ros_name.rsplit("/", 1)[0] if ros_name.startswith("/") else ""


def did_you_mean(word: str, choices: Any) -> str:
    """` (did you mean 'x'?)` for the closest choice, or '' when none is close."""
    close = difflib.get_close_matches(str(word), [str(c) for c in choices], n=1, cutoff=0.8)
    return f" (did you mean '{close[0]}'?)" if close else ""
