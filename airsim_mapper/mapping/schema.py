"""The mapping JSON Schema (package data: resources.SCHEMA_PATH) and readable, located error messages."""

from __future__ import annotations

import json
from collections.abc import Iterator
from functools import cache
from typing import Any

import jsonschema

from airsim_mapper.common.resources import SCHEMA_PATH
from airsim_mapper.mapping.errors import Problem
from airsim_mapper.mapping.names import did_you_mean
from airsim_mapper.mapping.origins import local_path, located
from airsim_mapper.mapping.yamlmarks import Marks


@cache
def schema() -> dict[str, Any]:
    """The mapping schema, read once."""
    return json.loads(SCHEMA_PATH.read_text(encoding="utf-8"))


@cache
def validator() -> jsonschema.Draft202012Validator:
    """A validator for the mapping schema, built once."""
    return jsonschema.Draft202012Validator(schema())


def where(path: tuple[Any, ...], data: Any, shown: tuple[Any, ...] | None = None) -> str:
    """A readable location: `rules[2] 'camera_image'.queue_size`, numbered as `shown` (the same path as the
    file it was written in numbers it) when given."""
    text = ""
    node = data
    for part, label in zip(path, shown or path):
        if isinstance(part, int):
            text += f"[{label}]"
            node = node[part] if isinstance(node, list) and part < len(node) else None
            if len(text) and isinstance(node, dict) and isinstance(node.get("name"), str):
                text += f" '{node['name']}'"
        else:
            text += f".{part}" if text else str(part)
            node = node.get(part) if isinstance(node, dict) else None
    return text or "top level"


def _brief(value: Any) -> str:
    text = json.dumps(value, default=str)
    return text if len(text) <= 40 else text[:37] + "..."


BOUNDS = {  # a number's bound, in words
    "minimum": "at least",
    "maximum": "at most",
    "exclusiveMinimum": "greater than",
    "exclusiveMaximum": "less than",
}


def _messages(err: jsonschema.ValidationError, data: Any, marks: Marks) -> Iterator[tuple[tuple, str]]:
    path = tuple(err.absolute_path)
    loc = where(path, data, local_path(marks, path))
    if err.validator == "additionalProperties" and isinstance(err.instance, dict):
        known = err.schema.get("properties", {})
        for key in err.instance:
            if key not in known:
                yield (*path, key), f"unknown key '{key}' in {loc}{did_you_mean(key, known)}"
    elif err.validator == "required":
        yield path, f"{loc}: {err.message.replace('is a required property', 'is required')}"
    elif err.validator == "enum":
        choices = err.validator_value
        hint = did_you_mean(err.instance, choices) or f" (one of: {', '.join(map(str, choices))})"
        yield path, f"{loc}: {_brief(err.instance)} is not allowed{hint}"
    elif err.validator == "type":
        expected = (
            err.validator_value if isinstance(err.validator_value, str) else " or ".join(err.validator_value)
        )
        yield path, f"{loc}: expected {expected}, got {_brief(err.instance)}"
    elif err.validator == "const":
        yield path, f"{loc}: must be {_brief(err.validator_value)}, got {_brief(err.instance)}"
    elif err.validator == "pattern":
        yield path, f"{loc}: {_brief(err.instance)} does not match {err.validator_value}"
    elif err.validator in BOUNDS:
        bound = f"{BOUNDS[err.validator]} {err.validator_value}"
        yield path, f"{loc}: must be {bound}, got {_brief(err.instance)}"
    else:
        yield path, f"{loc}: {err.message}"


def _is_converter(path: tuple[Any, ...]) -> bool:
    return len(path) == 3 and path[0] == "rules" and path[2] == "converter"


def schema_problems(data: Any, marks: Marks, file: str) -> list[tuple[tuple[Any, ...], Problem]]:
    """Every schema violation of `data` with its path, located at its key or value in the file."""
    problems = []
    for err in validator().iter_errors(data):
        if err.validator == "enum" and _is_converter(tuple(err.absolute_path)):
            continue  # checks.py reports it, with a did-you-mean, and checks the rest of the rule
        for path, message in _messages(err, data, marks):
            at_key = err.validator == "additionalProperties"
            problems.append((path, located(marks, path, file, message, at_key)))
    return problems
