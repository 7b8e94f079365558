"""Name templates: `<variable>` placeholders, e.g. `/airsim_node/<robot_name>/actual_pose`.

A placeholder is `<` + a lower-case identifier + `>`. Any other `<` or `>` is malformed.
"""

from __future__ import annotations

import re
from collections.abc import Iterator, Mapping
from typing import Any

from airsim_mapper.mapping.errors import MappingError, Problem

PLACEHOLDER = re.compile(r"<([a-z][a-z0-9_]*)>")


class TemplateError(MappingError, ValueError):
    """A template names a variable that has no value (the checks refuse such a mapping first)."""

    def __init__(self, message: str) -> None:
        super().__init__([Problem("<template>", 0, 0, message)])


def variables(template: str) -> tuple[str, ...]:
    """The placeholder names of `template`, in order of first appearance."""
    return tuple(dict.fromkeys(PLACEHOLDER.findall(template)))


def malformed(template: str) -> str | None:
    """A description of the first stray `<` or `>`, or None when the template is well formed."""
    rest = PLACEHOLDER.sub("", template)
    for char in "<>":
        if char in rest:
            return f"stray '{char}' (placeholders are written <name>, lower case)"
    return None


def render(template: str, values: Mapping[str, str]) -> str:
    """Substitute every placeholder; raise TemplateError for a variable without a value."""

    def one(match: re.Match[str]) -> str:
        name = match.group(1)
        if name not in values:
            raise TemplateError(f"template variable <{name}> has no value")
        return values[name]

    return PLACEHOLDER.sub(one, template)


def templates_in(value: Any, path: tuple[Any, ...] = ()) -> Iterator[tuple[tuple[Any, ...], str]]:
    """(path, text) of every string inside `value` (maps and lists, e.g. a rule's params) that holds a
    placeholder: those strings are templates; any other string is plain text."""
    if isinstance(value, str):
        if PLACEHOLDER.search(value):
            yield path, value
    elif isinstance(value, Mapping):
        for key, item in value.items():
            yield from templates_in(item, (*path, key))
    elif isinstance(value, (list, tuple)):
        for index, item in enumerate(value):
            yield from templates_in(item, (*path, index))


def render_all(value: Any, values: Mapping[str, str]) -> Any:
    """`value` with every template string inside it (see `templates_in`) rendered; maps become dicts."""
    if isinstance(value, str):
        return render(value, values) if PLACEHOLDER.search(value) else value
    if isinstance(value, Mapping):
        return {key: render_all(item, values) for key, item in value.items()}
    if isinstance(value, (list, tuple)):
        return [render_all(item, values) for item in value]
    return value
