"""Per-rule `match:`: which scene elements a rule expands over, chosen by its template variables.

`match: {robot_name: "Scout*", camera_name: [FrontCam, Belly], image_type: "!depth_*"}` keeps an element
when every listed variable matches: a value is a shell-style glob (`*`, `?`, `[abc]`, case-sensitive) or a
list of them; plain patterns are "any of", patterns with a leading `!` are "none of". A list of such maps
keeps an element that any of them keeps: `[{camera_name: "!Chase"}, {image_type: "!depth_*"}]` drops only
the Chase camera's depth images.
"""

from __future__ import annotations

from collections.abc import Iterator, Mapping, Sequence
from dataclasses import dataclass
from fnmatch import fnmatchcase
from types import MappingProxyType
from typing import Any

from airsim_mapper.mapping.model import DOMAIN_VARIABLES
from airsim_mapper.mapping.names import did_you_mean

NEGATION = "!"


@dataclass(frozen=True)
class Selector:
    """The patterns of one variable: a value is kept when it matches one of `include` (or `include` is
    empty) and none of `exclude`."""

    include: tuple[str, ...]
    exclude: tuple[str, ...]

    @classmethod
    def of(cls, patterns: Sequence[str]) -> Selector:
        include = tuple(p for p in patterns if not p.startswith(NEGATION))
        exclude = tuple(p[len(NEGATION) :] for p in patterns if p.startswith(NEGATION))
        return cls(include, exclude)

    def accepts(self, value: str) -> bool:
        if self.include and not any(fnmatchcase(value, p) for p in self.include):
            return False
        return not any(fnmatchcase(value, p) for p in self.exclude)


def patterns_of(value: str | Sequence[str]) -> tuple[str, ...]:
    """A `match` entry's patterns: one string or a list of them."""
    return (value,) if isinstance(value, str) else tuple(value)


Selection = Mapping[str, Sequence[str]]


def selections_of(raw: Any) -> tuple[Selection, ...]:
    """A rule's `match` (a map or a list of maps, validated by the schema) as selections of patterns."""
    if not raw:
        return ()
    listed = raw if isinstance(raw, list) else [raw]
    return tuple(MappingProxyType({k: patterns_of(v) for k, v in one.items()}) for one in listed)


def selects(selection: Selection, variables: Mapping[str, str]) -> bool:
    """Whether an element with `variables` passes every selector of `selection`."""
    return all(Selector.of(patterns).accepts(variables.get(name, "")) for name, patterns in selection.items())


def matches(match: Sequence[Selection], variables: Mapping[str, str]) -> bool:
    """Whether any selection of `match` keeps an element with `variables` (an empty match keeps all)."""
    return not match or any(selects(selection, variables) for selection in match)


def describe(match: Sequence[Selection]) -> str:
    """`robot_name: Scout*, camera_name: A B | image_type: !depth_*` for messages."""
    return " | ".join(
        ", ".join(f"{key}: {' '.join(values)}" for key, values in selection.items()) for selection in match
    )


def pattern_problem(pattern: str) -> str | None:
    """Why `pattern` is not a usable glob, or None."""
    body = pattern[len(NEGATION) :] if pattern.startswith(NEGATION) else pattern
    if not body:
        return "an empty pattern matches nothing (write '*' for anything)"
    if body.startswith(NEGATION):
        return "a double '!' (one leading '!' means 'none of')"
    at = 0
    while at < len(body):
        if body[at] == "[":
            end = at + 1 + (body[at + 1 : at + 2] == "!")
            end += body[end : end + 1] == "]"  # a ']' first in a class is literal
            close = body.find("]", end)
            if close < 0:
                return f"an unclosed '[' at character {at + 1}"
            at = close
        at += 1
    return None


def match_problems(raw: Any, domain: str) -> Iterator[tuple[tuple[Any, ...], bool, str]]:
    """(path below `match`, whether to point at the key, message) for each problem of a rule's `match` as
    written (a map or a list of maps, validated by the schema): a variable its domain lacks (with a
    did-you-mean) or a bad pattern."""
    if isinstance(raw, dict):
        yield from _selection_problems(raw, domain)
    elif isinstance(raw, list):
        for index, selection in enumerate(raw):
            for path, at_key, message in _selection_problems(selection, domain):
                yield (index, *path), at_key, message


def _selection_problems(
    selection: Mapping[str, Any], domain: str
) -> Iterator[tuple[tuple[Any, ...], bool, str]]:
    allowed = DOMAIN_VARIABLES.get(domain, ())
    for name, value in selection.items():
        if name not in allowed:
            hint = did_you_mean(name, allowed) or f" (for_each {domain} has: {', '.join(allowed)})"
            yield (name,), True, f"match: <{name}> is not a variable of for_each {domain}{hint}"
            continue
        listed = not isinstance(value, str)
        for index, pattern in enumerate(patterns_of(value)):
            why = pattern_problem(pattern)
            if why:
                yield ((name, index) if listed else (name,)), False, f"match.{name} '{pattern}': {why}"
