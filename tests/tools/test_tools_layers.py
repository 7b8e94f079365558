"""The tools' layers, checked by reading every import of `tools/` (module level and inside functions) with the
helpers of tests/test_layers.py.

- the tools' modules form no import circle;
- a tool subpackage (bench, soak, screenshot, demo) imports of the tools only its own modules and the shared
  top-level modules (`tools/rig.py`, ...), never another subpackage;
- a shared top-level module imports no tool subpackage: they sit below every subpackage;
- of the package, the tools import public names only (none that starts with an underscore). The bench
  measures the package's inner paths (frame parsing, decoding, publishing) on purpose, so the tools are not
  held to a subpackage's `__all__`.
That the package never imports the tools is checked in tests/test_layers.py. Each rule has a self-test: an
import injected against it is reported.
"""

from __future__ import annotations

from functools import cache
from pathlib import Path

import pytest
from test_layers import circles, imported, in_layer, module_name

TOOLS = Path(__file__).resolve().parents[2] / "tools"
SUBPACKAGES = tuple(sorted(f"tools.{path.parent.name}" for path in TOOLS.glob("*/__init__.py")))


@cache
def parsed_tools() -> dict[str, frozenset[str]]:
    """Module -> every module it imports, function-local imports included, for each module of tools/."""
    return {
        module_name(path): frozenset(imported(path.read_text(encoding="utf-8"), module_name(path)))
        for path in TOOLS.rglob("*.py")
    }


def tools_graph() -> dict[str, set[str]]:
    """A copy of the tools' import graph that a test may change."""
    return {module: set(targets) for module, targets in parsed_tools().items()}


def subpackage(name: str) -> str | None:
    """The tool subpackage a module belongs to; None for `tools` itself and its top-level modules."""
    return next((package for package in SUBPACKAGES if in_layer(name, package)), None)


def circle_problems(graph: dict[str, set[str]]) -> list[str]:
    return circles(graph)


def subpackage_problems(graph: dict[str, set[str]]) -> list[str]:
    """Imports of another subpackage's modules, from a subpackage or from a top-level module."""
    return sorted(
        f"{module} imports {target}"
        for module, targets in graph.items()
        for target in targets
        if (there := subpackage(target)) is not None and there != subpackage(module)
    )


def private_problems(graph: dict[str, set[str]]) -> list[str]:
    """Imports of the package's names that start with an underscore."""
    return sorted(
        f"{module} imports {target}"
        for module, targets in graph.items()
        for target in targets
        if in_layer(target, "airsim_mapper") and any(part.startswith("_") for part in target.split("."))
    )


RULES = {
    "the tools' modules form no import circle": circle_problems,
    "a subpackage imports its own modules and the shared top-level ones only": subpackage_problems,
    "the tools import the package's public names only": private_problems,
}


def test_the_tools_are_read_whole() -> None:
    assert set(SUBPACKAGES) == {"tools.bench", "tools.demo", "tools.screenshot", "tools.soak"}
    assert {"tools.rig", "tools.bench.results", "tools.soak.soak"} <= set(parsed_tools())


@pytest.mark.parametrize("rule", RULES)
def test_the_tools_keep_their_layers(rule: str) -> None:
    assert RULES[rule](tools_graph()) == []


@pytest.mark.parametrize(
    ("rule", "module", "source", "problem"),
    [
        (
            "the tools' modules form no import circle",
            "tools.bench.results",
            "def later():\n    from tools.bench import tables",
            "tools.bench.results -> tools.bench.tables -> tools.bench.results",
        ),
        (
            "a subpackage imports its own modules and the shared top-level ones only",
            "tools.bench.costs",
            "def later():\n    from tools.soak.probes import Wakes",
            "tools.bench.costs imports tools.soak.probes",
        ),
        (
            "a subpackage imports its own modules and the shared top-level ones only",
            "tools.rig",
            "from tools.bench import scenes",
            "tools.rig imports tools.bench.scenes",
        ),
        (
            "the tools import the package's public names only",
            "tools.screenshot.stack",
            "from airsim_mapper.simserver.render.gl_renderer import _cube",
            "tools.screenshot.stack imports airsim_mapper.simserver.render.gl_renderer._cube",
        ),
    ],
)
def test_each_rule_reports_a_forbidden_import(rule: str, module: str, source: str, problem: str) -> None:
    graph = tools_graph()
    graph[module] |= imported(source, module)
    assert problem in RULES[rule](graph)


def test_imports_of_the_own_subpackage_a_top_level_module_and_the_package_are_allowed() -> None:
    graph = tools_graph()
    source = "from tools import rig\nfrom tools.soak import cpu\nfrom airsim_mapper.engine import sim_link"
    graph["tools.soak.gaps"] |= imported(source, "tools.soak.gaps")
    assert [rule for rule, problems in RULES.items() if problems(graph)] == []
