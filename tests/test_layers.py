"""The package's layers, checked by reading every import (module level and inside functions) with `ast`.

- mapping/ and scene.py run without ROS: nothing they import, directly or through other modules of the
  package, is rospy, genpy, a message package or another ROS library;
- convert/ imports neither the engine, nor the mapping layer, nor rospy;
- simserver/ imports only itself and the shared leaf modules;
- nothing in the package imports the tools.
"""

from __future__ import annotations

import ast
from collections.abc import Iterable
from functools import cache
from pathlib import Path

import pytest

PACKAGE = Path(__file__).resolve().parent.parent / "airsim_mapper"
LEAVES = frozenset(
    {
        "airsim_mapper.errors",
        "airsim_mapper.geometry",
        "airsim_mapper.image_types",
        "airsim_mapper.logs",
        "airsim_mapper.ports",
        "airsim_mapper.ros_types",
        "airsim_mapper.tuning",
    }
)
ROS_LIBRARIES = frozenset({"rospy", "genpy", "roslib", "rosgraph", "tf2_ros", "tf2_py", "message_filters"})


def module_name(path: Path) -> str:
    parts = path.relative_to(PACKAGE.parent).with_suffix("").parts
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


def imported(source: str, module: str) -> set[str]:
    """Every module `source` imports, relative imports made absolute (`from a import b` counts a and a.b)."""
    found: set[str] = set()
    for node in ast.walk(ast.parse(source)):
        if isinstance(node, ast.Import):
            found.update(alias.name for alias in node.names)
        elif isinstance(node, ast.ImportFrom):
            base = node.module or ""
            if node.level:
                anchor = module.split(".")[: -node.level]
                base = ".".join([*anchor, base] if base else anchor)
            found.add(base)
            found.update(f"{base}.{alias.name}" for alias in node.names)
    return found


@cache
def parsed_package() -> dict[str, frozenset[str]]:
    """Module -> the modules it imports, for every module of the package (read once per run)."""
    return {
        module_name(path): frozenset(imported(path.read_text(encoding="utf-8"), module_name(path)))
        for path in PACKAGE.rglob("*.py")
    }


def package_graph() -> dict[str, set[str]]:
    """A copy of the package's import graph that a test may change."""
    return {module: set(targets) for module, targets in parsed_package().items()}


def reachable(graph: dict[str, set[str]], start: Iterable[str]) -> set[str]:
    """`start` and every package module they import, transitively."""
    seen: set[str] = set()
    todo = [name for name in start if name in graph]
    while todo:
        name = todo.pop()
        if name not in seen:
            seen.add(name)
            todo.extend(target for target in graph[name] if target in graph)
    return seen


def is_ros(name: str) -> bool:
    top = name.split(".")[0]
    return top in ROS_LIBRARIES or top.endswith("_msgs") or top.endswith("_srvs")


def in_layer(name: str, *layers: str) -> bool:
    return any(name == layer or name.startswith(f"{layer}.") for layer in layers)


def ros_free_problems(graph: dict[str, set[str]]) -> list[str]:
    roots = [name for name in graph if in_layer(name, "airsim_mapper.mapping", "airsim_mapper.scene")]
    return sorted(
        f"{module} imports {target}"
        for module in reachable(graph, roots)
        for target in graph[module]
        if is_ros(target)
    )


def convert_problems(graph: dict[str, set[str]]) -> list[str]:
    forbidden = ("airsim_mapper.engine", "airsim_mapper.mapping", "rospy")
    return sorted(
        f"{module} imports {target}"
        for module, targets in graph.items()
        if in_layer(module, "airsim_mapper.convert")
        for target in targets
        if in_layer(target, *forbidden)
    )


def simserver_problems(graph: dict[str, set[str]]) -> list[str]:
    return sorted(
        f"{module} imports {target}"
        for module, targets in graph.items()
        if in_layer(module, "airsim_mapper.simserver")
        for target in targets
        if in_layer(target, "airsim_mapper")
        and not in_layer(target, "airsim_mapper.simserver", *LEAVES)
        and target != "airsim_mapper"
    )


def tools_problems(graph: dict[str, set[str]]) -> list[str]:
    return sorted(f"{module} imports {t}" for module, ts in graph.items() for t in ts if in_layer(t, "tools"))


RULES = {
    "mapping and scene run without ROS": ros_free_problems,
    "convert stands apart from engine, mapping and rospy": convert_problems,
    "simserver uses only itself and the leaf modules": simserver_problems,
    "the package never imports the tools": tools_problems,
}


@pytest.mark.parametrize("rule", RULES)
def test_the_package_keeps_its_layers(rule: str) -> None:
    assert RULES[rule](package_graph()) == []


@pytest.mark.parametrize(
    ("rule", "module", "source", "problem"),
    [
        (
            "mapping and scene run without ROS",
            "airsim_mapper.mapping.expand",
            "from airsim_mapper.convert import catalog",
            "airsim_mapper.convert.catalog imports std_msgs.msg",
        ),
        (
            "convert stands apart from engine, mapping and rospy",
            "airsim_mapper.convert.pose",
            "def later():\n    from ..mapping import template",
            "airsim_mapper.convert.pose imports airsim_mapper.mapping",
        ),
        (
            "simserver uses only itself and the leaf modules",
            "airsim_mapper.simserver.world",
            "from airsim_mapper.convert.frames import ned_to_enu",
            "airsim_mapper.simserver.world imports airsim_mapper.convert.frames",
        ),
        (
            "the package never imports the tools",
            "airsim_mapper.engine.engine",
            "import tools.rig",
            "airsim_mapper.engine.engine imports tools.rig",
        ),
    ],
)
def test_each_rule_reports_a_forbidden_import(rule: str, module: str, source: str, problem: str) -> None:
    graph = package_graph()
    graph[module] = graph[module] | imported(source, module)
    if rule == "mapping and scene run without ROS":  # a forbidden import two modules away
        graph["airsim_mapper.convert.catalog"] = graph["airsim_mapper.convert.catalog"] | {"std_msgs.msg"}
    assert problem in RULES[rule](graph)
