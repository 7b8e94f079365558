"""One source for every YAML name: the schema defines each option once ($defs) and refers to it from
`defaults` and from each rule; its enums equal the code's tables; the loader's keys are the model's fields."""

from __future__ import annotations

from dataclasses import fields
from typing import Any

import pytest

from airsim_mapper.convert import catalog
from airsim_mapper.convert.context import CONVENTIONS, STAMPS
from airsim_mapper.mapping import loader
from airsim_mapper.mapping.model import DOMAIN_VARIABLES, ROS_TO_SIM, SIM_TO_ROS, Limits, Options
from airsim_mapper.mapping.schema import schema

DEFS = schema()["$defs"]
RULE = schema()["properties"]["rules"]["items"]["properties"]
DEFAULTS = schema()["properties"]["defaults"]["properties"]
OPTIONS = tuple(field.name for field in fields(Options))


@pytest.mark.parametrize(
    ("name", "table"),
    [
        ("for_each", tuple(DOMAIN_VARIABLES)),
        ("direction", (SIM_TO_ROS, ROS_TO_SIM)),
        ("convention", CONVENTIONS),
        ("stamp", STAMPS),
        ("converter", tuple(catalog.CONVERTERS)),
    ],
)
def test_the_schemas_enums_equal_the_codes_tables(name, table):
    enum = tuple(DEFS[name]["enum"])
    missing = [value for value in table if value not in enum]
    extra = [value for value in enum if value not in table]
    regenerate = "; `python -m tools.catalogue` regenerates the converter and for_each enums"
    assert not missing, f"the schema's {name} enum lacks {missing}{regenerate}"
    assert not extra, f"the schema's {name} enum has {extra}, which the code does not{regenerate}"
    assert enum == table, f"the schema's {name} enum is not in the code's order{regenerate}"


def test_every_option_is_defined_once_and_referred_to_from_defaults_and_rules():
    for name in (*OPTIONS, "convention"):
        assert DEFAULTS[name] == RULE[name] == {"$ref": f"#/$defs/{name}"}
    assert set(DEFAULTS) == {*OPTIONS, "convention"}
    assert set(DEFS["limits"]["properties"]) == {field.name for field in fields(Limits)}


def test_the_loaders_keys_are_the_models_fields():
    assert tuple(name for name in OPTIONS if name != "limits") == loader.OPTION_KEYS
    assert tuple(field.name for field in fields(Limits)) == loader.LIMIT_KEYS


def properties(node: Any, path: str = ""):
    """(path, schema) of every property the schema declares."""
    if isinstance(node, dict):
        for key, value in (node.get("properties") or {}).items():
            yield f"{path}.{key}", value
        for key, value in node.items():
            yield from properties(value, f"{path}/{key}")
    elif isinstance(node, list):
        for index, value in enumerate(node):
            yield from properties(value, f"{path}[{index}]")


def test_every_key_has_a_description():
    missing = [
        path for path, value in properties(schema()) if "$ref" not in value and not value.get("description")
    ]
    assert missing == []
    assert all(value.get("description") for value in DEFS.values())
    for key in ("extends", "remove", "variables"):
        assert schema()["properties"][key]["description"]
    for key in ("after", "match"):
        assert RULE[key]["description"]
