"""ROS 2's name rules, in pure Python: what rcl accepts as a topic or service name as written, what rmw
accepts once it is expanded to a full name, and its rules for node names and namespaces.

ROS 2 refuses some names ROS1 takes: a token that starts with a digit anywhere (`/cam/0`), `~x` (ROS 2
writes `~/x`), names longer than rmw's limits. A mapping that drives both flavours keeps to what both take.
Each check returns why a name is refused, or None.
"""

from __future__ import annotations

import re

from airsim_mapper.mapping import template
from airsim_mapper.mapping.errors import Problem
from airsim_mapper.mapping.model import MappingDoc

TOPIC_MAX_LENGTH = 255 - 8  # rmw: the implementation's 255, less 8 kept for the middleware's prefixes
NAMESPACE_MAX_LENGTH = TOPIC_MAX_LENGTH - 2
NODE_NAME_MAX_LENGTH = 255
SAMPLE_VALUE = "x1"  # stands for every template variable when a rule's names are checked without a scene
_WORD = re.compile(r"[A-Za-z0-9_]")
SUBSTITUTIONS = ("node", "ns", "namespace")  # what rcl's expansion puts in for {node}, {ns}, {namespace}


def _at(name: str, index: int, why: str) -> str:
    return f"{why} (at character {index + 1} of '{name}')"


def topic_problem(name: str) -> str | None:
    """Why rcl refuses `name` as a topic or service name as written (relative, private `~/x` and `{node}`
    substitutions allowed), or None."""
    if not name:
        return "it is empty"
    if name[0].isdigit():
        return _at(name, 0, "a token starts with a digit")
    if name.endswith("/"):
        return _at(name, len(name) - 1, "it ends with '/'")
    opened = -1  # index of the open '{', or -1
    for i, char in enumerate(name):
        if _WORD.fullmatch(char):
            if char.isdigit() and opened >= 0 and i == opened + 1:
                return _at(name, i, "a {substitution} starts with a digit")
        elif char == "/" and opened >= 0:
            return _at(name, i, "a {substitution} contains '/'")
        elif char == "~" and i != 0:
            return _at(name, i, "'~' is allowed only as the first character")
        elif char == "{":
            if opened >= 0:
                return _at(name, i, "'{' inside a {substitution}")
            opened = i
        elif char == "}":
            if opened < 0:
                return _at(name, i, "'}' without its '{'")
            opened = -1
        elif char not in "/~":
            return _at(name, i, f"{char!r} is not allowed (letters, digits, '_', '/', '~' and {{}})")
    if opened >= 0:
        return _at(name, opened, "'{' without its '}'")
    for i, char in enumerate(name[:-1]):
        if char == "/" and name[i + 1].isdigit():
            return _at(name, i + 1, "a token starts with a digit")
        if char != "/" and i == 1 and name[0] == "~":
            return _at(name, 1, "'~' must be followed by '/'")
    return None


def full_topic_problem(name: str) -> str | None:
    """Why rmw refuses `name` as a fully expanded topic or service name, or None."""
    if not name:
        return "it is empty"
    if not name.startswith("/"):
        return _at(name, 0, "a full name must start with '/'")
    if name.endswith("/"):
        return _at(name, len(name) - 1, "it ends with '/'")
    for i, char in enumerate(name):
        if char != "/" and not _WORD.fullmatch(char):
            return _at(name, i, f"{char!r} is not allowed (letters, digits, '_' and '/')")
    for i, char in enumerate(name[:-1]):
        if char == "/" and name[i + 1] == "/":
            return _at(name, i + 1, "it contains '//'")
        if char == "/" and name[i + 1].isdigit():
            return _at(name, i + 1, "a token starts with a digit")
    if len(name) > TOPIC_MAX_LENGTH:
        return f"it is {len(name)} characters long, more than ROS 2's {TOPIC_MAX_LENGTH}"
    return None


def node_name_problem(name: str) -> str | None:
    """Why rmw refuses `name` as a node name (no namespace in it), or None."""
    if not name:
        return "it is empty"
    for i, char in enumerate(name):
        if not _WORD.fullmatch(char):
            return _at(name, i, f"{char!r} is not allowed (letters, digits and '_')")
    if name[0].isdigit():
        return _at(name, 0, "it starts with a digit")
    if len(name) > NODE_NAME_MAX_LENGTH:
        return f"it is {len(name)} characters long, more than ROS 2's {NODE_NAME_MAX_LENGTH}"
    return None


def namespace_problem(namespace: str) -> str | None:
    """Why rmw refuses `namespace` as a node's namespace ("/" or "/a/b"), or None."""
    if namespace == "/":
        return None
    why = full_topic_problem(namespace)
    if why is not None and "characters long" not in why:
        return why
    if len(namespace) > NAMESPACE_MAX_LENGTH:
        return f"it is {len(namespace)} characters long, more than ROS 2's {NAMESPACE_MAX_LENGTH}"
    return None


def expand_name(name: str, node_name: str, node_namespace: str = "") -> str:
    """A name rcl accepts, expanded as rcl expands it for the node `node_name` in `node_namespace` ("" or
    "/" for the root, else `/a/b`): `~` is the node's full name, {node} its name, {ns} and {namespace} its
    namespace; a relative name goes below the namespace."""
    namespace = node_namespace.rstrip("/")
    private = f"{namespace}/{node_name}"
    values = dict(zip(SUBSTITUTIONS, (node_name, namespace or "/", namespace or "/")))
    text = re.sub(r"\{(\w+)\}", lambda m: values.get(m.group(1), m.group(0)), name)
    if text.startswith("~"):
        text = private + text[1:]
    return text if text.startswith("/") else f"{namespace}/{text}"


def ros2_name_problem(name: str, node_name: str, node_namespace: str = "") -> str | None:
    """Why ROS 2 refuses `name` for the node `node_name` in `node_namespace`: as written, for a
    substitution rcl does not know, or once expanded; None when it takes it."""
    why = topic_problem(name)
    if why is not None:
        return why
    unknown = [found for found in re.findall(r"\{(\w+)\}", name) if found not in SUBSTITUTIONS]
    if unknown:
        return f"{{{unknown[0]}}} is not a substitution ROS 2 knows ({', '.join(SUBSTITUTIONS)})"
    full = expand_name(name, node_name, node_namespace)
    why = full_topic_problem(full)
    return None if why is None else f"its full name '{full}' is refused: {why}"


def rule_problems(mapping: MappingDoc) -> list[Problem]:
    """Each enabled rule whose `ros` ROS 2 refuses whatever its template variables are (each stands for
    `x1`, <namespace> for nothing), located at the rule's `ros` value."""
    problems = []
    for rule in mapping.rules:
        if rule.ros is None or not rule.options.enabled:
            continue
        sample = template.PLACEHOLDER.sub(
            lambda m: "" if m.group(1) in ("namespace", "frame_prefix") else SAMPLE_VALUE, rule.ros
        )
        why = topic_problem(sample)
        if why is not None:
            at = rule.ros_place or (rule.file or mapping.source, rule.line, 1)
            problems.append(Problem(*at, f"rule '{rule.name}': ros '{rule.ros}' is refused by ROS 2: {why}"))
    return problems
