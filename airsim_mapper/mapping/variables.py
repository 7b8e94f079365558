"""Mapping-level `variables:` named templates, e.g. `robot_frame: <frame_prefix><robot_name>/base_link`.

A rule uses one as `<robot_frame>` in any template (sim, ros, frame_id, tf, params). A variable's text may use
the domain variables and other mapping variables; loading substitutes them into the rules' templates, so the
usual checks then see the domain variables each rule really uses (a variable that uses <camera_name> fits
only rules whose for_each has a camera).
"""

from __future__ import annotations

import copy
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any

from airsim_mapper.mapping import template
from airsim_mapper.mapping.errors import Problem
from airsim_mapper.mapping.model import DOMAIN_VARIABLES
from airsim_mapper.mapping.names import did_you_mean
from airsim_mapper.mapping.origins import located
from airsim_mapper.mapping.yamlmarks import Marks

DOMAIN_NAMES = tuple(dict.fromkeys(name for names in DOMAIN_VARIABLES.values() for name in names))
RULE_TEMPLATE_KEYS = ("sim", "ros", "frame_id", "tf", "params")


def _problem(marks: Marks, file: str, path: tuple[Any, ...], message: str, at_key: bool = False) -> Problem:
    return located(marks, path, file, message, at_key)


def resolve_variables(
    variables: Mapping[str, str], marks: Marks, file: str
) -> tuple[dict[str, str], list[Problem]]:
    """Each well-formed variable's text with the mapping variables in it substituted (domain variables
    stay), and a problem for every bad one: a domain variable's name, a stray bracket, an unknown variable,
    a cycle."""
    problems: list[Problem] = []
    good: dict[str, str] = {}
    for name, text in variables.items():
        path = ("variables", name)
        if name in DOMAIN_NAMES:
            message = f"variables: '{name}' is a domain variable; give the mapping variable another name"
            problems.append(_problem(marks, file, path, message, at_key=True))
        elif template.malformed(text):
            message = f"variables: {name} '{text}': {template.malformed(text)}"
            problems.append(_problem(marks, file, path, message))
        else:
            good[name] = text
    for name, text in list(good.items()):
        unknown = [used for used in template.variables(text) if used not in (*DOMAIN_NAMES, *variables)]
        for used in unknown:
            hint = did_you_mean(used, (*DOMAIN_NAMES, *variables))
            message = f"variables: {name} uses <{used}>, neither a domain nor a mapping variable{hint}"
            problems.append(_problem(marks, file, ("variables", name), message))
        if unknown:
            del good[name]
    resolution = _Resolution(good, marks, file, problems)
    for name in good:
        resolution.expand(name, ())
    return resolution.resolved, problems


@dataclass
class _Resolution:
    """The mapping variables resolved so far. (A class rather than a recursive closure: a closure that
    calls itself is a reference cycle, which kept each reload's marks in the node's frozen heap.)"""

    good: dict[str, str]
    marks: Marks
    file: str
    problems: list[Problem]
    resolved: dict[str, str] = field(default_factory=dict)
    looped: set[str] = field(default_factory=set)

    def expand(self, name: str, stack: tuple[str, ...]) -> str | None:
        if name in self.resolved:
            return self.resolved[name]
        if name in stack:
            members = stack[stack.index(name) :]
            if not self.looped.intersection(members):  # one report per loop
                self.looped.update(members)
                loop = " -> ".join((*members, name))
                message = f"variables: {name} refers to itself ({loop})"
                self.problems.append(_problem(self.marks, self.file, ("variables", name), message))
            return None
        text = self.good[name]
        for used in template.variables(text):
            if used in self.good:
                inner = self.expand(used, (*stack, name))
                if inner is None:
                    return None
                text = text.replace(f"<{used}>", inner)
        self.resolved[name] = text
        return text


def substitute(text: str, resolved: Mapping[str, str]) -> str:
    """`text` with every mapping variable replaced by its resolved text (other placeholders kept)."""
    return template.PLACEHOLDER.sub(lambda m: resolved.get(m.group(1), m.group(0)), text)


def apply_variables(data: dict[str, Any], marks: Marks, file: str) -> tuple[dict[str, Any], list[Problem]]:
    """`data` with its `variables` substituted into every rule's templates, and the variables' problems."""
    variables = data.get("variables") or {}
    if not variables:
        return data, []
    resolved, problems = resolve_variables(variables, marks, file)
    result = copy.deepcopy(data)
    for rule in result.get("rules") or []:
        if isinstance(rule, dict):
            for key in RULE_TEMPLATE_KEYS:
                if key in rule:
                    rule[key] = _substituted(rule[key], resolved)
    return result, problems


def _substituted(value: Any, resolved: Mapping[str, str]) -> Any:
    if isinstance(value, str):
        return substitute(value, resolved)
    if isinstance(value, dict):
        return {key: _substituted(item, resolved) for key, item in value.items()}
    if isinstance(value, list):
        return [_substituted(item, resolved) for item in value]
    return value
