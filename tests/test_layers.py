"""The package's layers, checked by reading every import (module level and inside functions) with `ast`.

The layers, top to bottom (`LAYERS`): cli; wrapper; engine; mapping; convert and simserver, peers that
never import each other; common/, the shared leaves. A module imports only its own layer (its own group of
it) or a lower one. Every module of the package is in exactly one layer. Besides:
- mapping/ runs without ROS: nothing they import, directly or through other modules of the
  package, is rospy, genpy, a message package or another ROS library;
- convert/ does not import rospy (message classes and genpy.Time only);
- nothing in the package imports the tools;
- the package's imports have no circle, those under `if TYPE_CHECKING:` included;
- from outside a subpackage (cli, convert, engine, mapping, and each room of simserver), only what its
  `__all__` names is imported: its modules named there, or the names it exports (the engine's classes,
  imported from `airsim_mapper.engine`).
The headless server (simserver) has rooms in the same way (`ROOMS`): its top modules; robot; sensors;
scene; render; world and wire, peers; motion; errors, the base of every room. A simserver module imports
only its own room or a lower one, and every simserver module is in exactly one room.
Each rule has a self-test: an import injected against it is reported.
"""

from __future__ import annotations

import ast
import importlib
import itertools
from collections.abc import Iterable
from functools import cache
from pathlib import Path

import pytest

PACKAGE = Path(__file__).resolve().parent.parent / "airsim_mapper"
# Top to bottom; each layer a tuple of groups (peers), each group the module prefixes it holds.
Layers = tuple[tuple[tuple[str, ...], ...], ...]
LAYERS: Layers = (
    (("airsim_mapper.cli",),),
    (("airsim_mapper.wrapper",),),
    (("airsim_mapper.engine",),),
    (("airsim_mapper.mapping",),),
    (("airsim_mapper.convert",), ("airsim_mapper.simserver",)),
    (("airsim_mapper.common",),),
)
PACKAGE_ROOT = "airsim_mapper"  # its __init__ holds the version only: below every layer
SIM = "airsim_mapper.simserver"  # its __init__ holds a docstring only: below every room
# The rooms of the headless server, top to bottom, in the shape of LAYERS.
ROOMS: Layers = (
    ((f"{SIM}.__main__", f"{SIM}.cli", f"{SIM}.server", f"{SIM}.session"),),
    ((f"{SIM}.robot",),),
    ((f"{SIM}.sensors",),),
    ((f"{SIM}.scene",),),
    ((f"{SIM}.render",),),
    ((f"{SIM}.world",), (f"{SIM}.wire",)),
    ((f"{SIM}.motion",),),
    ((f"{SIM}.errors",),),
)
ROS_LIBRARIES = frozenset({"rospy", "genpy", "roslib", "rosgraph", "tf2_ros", "tf2_py", "message_filters"})


def module_name(path: Path) -> str:
    parts = path.relative_to(PACKAGE.parent).with_suffix("").parts
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


def _type_checking(node: ast.AST) -> bool:
    test = getattr(node, "test", None)
    return isinstance(node, ast.If) and (
        (isinstance(test, ast.Name) and test.id == "TYPE_CHECKING")
        or (isinstance(test, ast.Attribute) and test.attr == "TYPE_CHECKING")
    )


def imported(source: str, module: str, run_time_only: bool = False) -> set[str]:
    """Every module `source` imports, relative imports made absolute (`from a import b` counts a and a.b);
    with `run_time_only`, not those under `if TYPE_CHECKING:`."""
    found: set[str] = set()
    todo: list[ast.AST] = [ast.parse(source)]
    while todo:
        node = todo.pop()
        if run_time_only and _type_checking(node):
            todo.extend(node.orelse)
            continue
        todo.extend(ast.iter_child_nodes(node))
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
def parsed_package(run_time_only: bool = False) -> dict[str, frozenset[str]]:
    """Module -> the modules it imports, for every module of the package (read once per run)."""
    return {
        module_name(path): frozenset(
            imported(path.read_text(encoding="utf-8"), module_name(path), run_time_only)
        )
        for path in PACKAGE.rglob("*.py")
    }


def package_graph(run_time_only: bool = False) -> dict[str, set[str]]:
    """A copy of the package's import graph that a test may change."""
    return {module: set(targets) for module, targets in parsed_package(run_time_only).items()}


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


def place(name: str, layers: Layers = LAYERS) -> tuple[int, int] | None:
    """(layer, group) of a package module (a module imported as `pkg.name` counts as `pkg`'s); None for
    the package root and for anything outside the package (with ROOMS: the simserver's root and anything
    outside the simserver)."""
    for rank, groups in enumerate(layers):
        for group, prefixes in enumerate(groups):
            if in_layer(name, *prefixes):
                return rank, group
    return None


def layer_problems(graph: dict[str, set[str]], layers: Layers = LAYERS) -> list[str]:
    """Imports of a higher layer, or of a peer group of the same layer."""
    problems = []
    for module, targets in graph.items():
        home = place(module, layers)
        for target in targets:
            there = place(target, layers)
            if home is None or there is None or there == home:
                continue
            if there[0] <= home[0]:  # upward, or a peer's
                problems.append(f"{module} imports {target}")
    return sorted(problems)


def ros_free_problems(graph: dict[str, set[str]]) -> list[str]:
    roots = [name for name in graph if in_layer(name, "airsim_mapper.mapping")]
    return sorted(
        f"{module} imports {target}"
        for module in reachable(graph, roots)
        for target in graph[module]
        if is_ros(target)
    )


def convert_problems(graph: dict[str, set[str]]) -> list[str]:
    return sorted(
        f"{module} imports {target}"
        for module, targets in graph.items()
        if in_layer(module, "airsim_mapper.convert")
        for target in targets
        if in_layer(target, "rospy")
    )


def tools_problems(graph: dict[str, set[str]]) -> list[str]:
    return sorted(f"{module} imports {t}" for module, ts in graph.items() for t in ts if in_layer(t, "tools"))


def circles(graph: dict[str, set[str]]) -> list[str]:
    """Each import circle among the package's modules, as `a -> b -> a` (Tarjan's strongly connected
    components of more than one module, or one importing itself)."""
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    found: list[str] = []

    def visit(name: str) -> None:
        index[name] = low[name] = len(index)
        stack.append(name)
        for target in sorted(t for t in graph[name] if t in graph):
            if target not in index:
                visit(target)
                low[name] = min(low[name], low[target])
            elif target in stack:
                low[name] = min(low[name], index[target])
        if low[name] == index[name]:
            component = []
            while True:
                member = stack.pop()
                component.append(member)
                if member == name:
                    break
            if len(component) > 1 or name in graph[name]:
                found.append(" -> ".join([*sorted(component), sorted(component)[0]]))

    for name in sorted(graph):
        if name not in index:
            visit(name)
    return sorted(found)


def room_problems(graph: dict[str, set[str]]) -> list[str]:
    """Imports of a higher room of the simserver, or of a peer room."""
    return layer_problems(graph, ROOMS)


RULES = {
    "a module imports only its own layer or a lower one": layer_problems,
    "a simserver module imports only its own room or a lower one": room_problems,
    "mapping and scene run without ROS": ros_free_problems,
    "convert does not import rospy": convert_problems,
    "the package never imports the tools": tools_problems,
}


@pytest.mark.parametrize("rule", RULES)
def test_the_package_keeps_its_layers(rule: str) -> None:
    assert RULES[rule](package_graph()) == []


def test_every_module_is_in_exactly_one_layer() -> None:
    unplaced = [name for name in parsed_package() if name != PACKAGE_ROOT and place(name) is None]
    assert unplaced == [], "add these modules to a layer of LAYERS"
    prefixes = [prefix for groups in LAYERS for group in groups for prefix in group]
    assert len(prefixes) == len(set(prefixes))


def test_every_simserver_module_is_in_exactly_one_room() -> None:
    unplaced = [
        name for name in parsed_package() if in_layer(name, SIM) and name != SIM and not place(name, ROOMS)
    ]
    assert unplaced == [], "add these modules to a room of ROOMS"
    prefixes = [prefix for groups in ROOMS for group in groups for prefix in group]
    assert len(prefixes) == len(set(prefixes))


@pytest.mark.parametrize("run_time_only", [True, False], ids=["run-time imports", "type-checking ones too"])
def test_the_imports_have_no_circle(run_time_only: bool) -> None:
    assert circles(package_graph(run_time_only=run_time_only)) == []


def representative(rank: int, group: int, layers: Layers = LAYERS) -> str:
    """A module of the package in that layer's group (the first by name)."""
    return min(name for name in parsed_package() if place(name, layers) == (rank, group))


def forbidden(layers: Layers) -> list[tuple[tuple[int, int], tuple[int, int]]]:
    """Each (lower, higher or peer) pair of groups: an import from the first of the second is forbidden."""
    groups = [(rank, group) for rank, groups in enumerate(layers) for group in range(len(groups))]
    return [(low, high) for low, high in itertools.permutations(groups, 2) if high[0] <= low[0]]


FORBIDDEN = forbidden(LAYERS)


@pytest.mark.parametrize(("low", "high"), FORBIDDEN, ids=lambda g: f"{LAYERS[g[0]][g[1]][0]}")
def test_an_import_of_a_higher_layer_or_a_peer_is_reported_for_each_pair(low, high) -> None:
    graph = package_graph()
    module, target = representative(*low), representative(*high)
    graph[module] = graph[module] | imported(f"def later():\n    import {target}", module)
    assert f"{module} imports {target}" in layer_problems(graph)


@pytest.mark.parametrize(
    ("low", "high"), forbidden(ROOMS), ids=lambda g: ROOMS[g[0]][g[1]][0].removeprefix(f"{SIM}.")
)
def test_an_import_of_a_higher_room_or_a_peer_is_reported_for_each_pair(low, high) -> None:
    graph = package_graph()
    module, target = representative(*low, ROOMS), representative(*high, ROOMS)
    graph[module] = graph[module] | imported(f"def later():\n    import {target}", module)
    assert f"{module} imports {target}" in room_problems(graph)


def test_an_import_of_a_lower_layer_or_of_its_own_group_is_allowed() -> None:
    graph = package_graph()
    graph["airsim_mapper.engine.hub"] |= {"airsim_mapper.convert.frames", "airsim_mapper.engine.streams"}
    graph[f"{SIM}.robot.robots"] |= {f"{SIM}.wire.outbox", f"{SIM}.robot.camera_services", f"{SIM}.errors"}
    assert layer_problems(graph) == []
    assert room_problems(graph) == []


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
            "convert does not import rospy",
            "airsim_mapper.convert.pose",
            "def later():\n    import rospy",
            "airsim_mapper.convert.pose imports rospy",
        ),
        (
            "the package never imports the tools",
            "airsim_mapper.engine.core",
            "import tools.rig",
            "airsim_mapper.engine.core imports tools.rig",
        ),
    ],
)
def test_each_rule_reports_a_forbidden_import(rule: str, module: str, source: str, problem: str) -> None:
    graph = package_graph()
    graph[module] = graph[module] | imported(source, module)
    if rule == "mapping and scene run without ROS":  # a forbidden import two modules away
        graph["airsim_mapper.convert.catalog"] = graph["airsim_mapper.convert.catalog"] | {"std_msgs.msg"}
    assert problem in RULES[rule](graph)


def test_a_circle_is_reported_and_type_checking_imports_are_not_run_time_ones() -> None:
    graph = package_graph(run_time_only=True)
    graph["airsim_mapper.engine.hub"] |= {"airsim_mapper.engine.core"}
    assert any(c.startswith("airsim_mapper.engine.") and "engine.hub" in c for c in circles(graph))
    source = "from typing import TYPE_CHECKING\nif TYPE_CHECKING:\n    from a import b\nelse:\n    import c\n"
    assert imported(source, "m", run_time_only=True) == {"typing", "typing.TYPE_CHECKING", "c"}
    assert {"a", "a.b", "c"} <= imported(source, "m")


FACES = (
    "airsim_mapper.cli",
    "airsim_mapper.convert",
    "airsim_mapper.engine",
    "airsim_mapper.mapping",
    *(room for groups in ROOMS[1:-1] for group in groups for room in group),
)


def face(package: str) -> frozenset[str]:
    """What a subpackage's `__init__` names in `__all__`: its modules, or the names it exports."""
    source = (PACKAGE.parent / package.replace(".", "/") / "__init__.py").read_text(encoding="utf-8")
    for node in ast.parse(source).body:
        if isinstance(node, ast.Assign) and any(getattr(t, "id", "") == "__all__" for t in node.targets):
            return frozenset(ast.literal_eval(node.value))
    return frozenset()


def face_problems(graph: dict[str, set[str]]) -> list[str]:
    """Imports from outside a subpackage of a module its `__all__` does not name."""
    problems = []
    for package in FACES:
        allowed = face(package)
        for module, targets in graph.items():
            if in_layer(module, package):
                continue
            problems.extend(
                f"{module} imports {target}, not in {package}.__all__"
                for target in targets
                if in_layer(target, package)
                and target != package
                and target[len(package) + 1 :].split(".")[0] not in allowed
            )
    return sorted(problems)


@pytest.mark.parametrize("package", FACES)
def test_each_subpackage_names_its_face_and_every_outside_import_uses_it(package: str) -> None:
    names = face(package)
    assert names, f"{package}/__init__.py has no __all__"
    assert face_gaps(package, names) == [], "__all__ names what is neither a module nor exported"
    assert [p for p in face_problems(package_graph()) if f"not in {package}." in p] == []


def face_gaps(package: str, names: frozenset[str]) -> list[str]:
    """The names of `names` that are neither a module of `package` nor a name it exports."""
    modules = {name.rsplit(".", 1)[-1] for name in parsed_package() if name.startswith(f"{package}.")}
    exported = importlib.import_module(package)
    return sorted(name for name in names - modules if not hasattr(exported, name))


def test_a_face_naming_what_its_package_neither_holds_nor_exports_is_reported() -> None:
    engine = "airsim_mapper.engine"
    assert face_gaps(engine, face(engine) | {"Engine", "core", "Nowhere"}) == ["Nowhere"]


@pytest.mark.parametrize(
    ("module", "target", "package"),
    [
        ("airsim_mapper.wrapper", "airsim_mapper.engine.streams", "airsim_mapper.engine"),
        (f"{SIM}.session", f"{SIM}.render.gl_renderer", f"{SIM}.render"),
    ],
)
def test_an_import_behind_a_subpackages_face_is_reported(module: str, target: str, package: str) -> None:
    graph = package_graph()
    graph[module] |= {target}
    assert face_problems(graph) == [f"{module} imports {target}, not in {package}.__all__"]


def test_an_exported_name_is_imported_through_its_subpackage_not_from_its_module() -> None:
    graph = package_graph()
    graph["airsim_mapper.wrapper"] |= imported("from airsim_mapper.engine import Engine", "m")
    assert face_problems(graph) == []
    graph["airsim_mapper.wrapper"] |= imported("from airsim_mapper.engine.core import Engine", "m")
    assert (
        "airsim_mapper.wrapper imports airsim_mapper.engine.core, not in airsim_mapper.engine.__all__"
        in face_problems(graph)
    )
