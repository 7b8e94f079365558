"""Load a mapping YAML file: parse safely with line marks, validate against the schema, build the rules,
then check their meaning (converters, ROS types, template variables, ROS names, duplicates).

Every problem is collected and reported at once in one MappingError, each as `FILE:LINE:COL: message`.
"""

from __future__ import annotations

from dataclasses import fields
from pathlib import Path
from types import MappingProxyType
from typing import Any

from airsim_mapper.common.files import ConfigFileError, read_config_text
from airsim_mapper.common.image_types import DOCUMENTED_IMAGE_TYPES
from airsim_mapper.common.resources import mapping_path
from airsim_mapper.mapping.checks import check_rules
from airsim_mapper.mapping.errors import MappingError, Problem
from airsim_mapper.mapping.extends import is_bare_name, resolve, shipped_hint
from airsim_mapper.mapping.match import selections_of
from airsim_mapper.mapping.model import (
    DOMAIN_VARIABLES,
    Limits,
    MappingDoc,
    Options,
    PositionBox,
    Rule,
    TfSpec,
)
from airsim_mapper.mapping.origins import Origins, file_of, located
from airsim_mapper.mapping.qos import qos_of
from airsim_mapper.mapping.reserved import literal_problem
from airsim_mapper.mapping.schema import schema_problems
from airsim_mapper.mapping.variables import apply_variables
from airsim_mapper.mapping.yamlmarks import YamlLimits, load_marked

DEFAULT_IMAGE_TYPES: dict[int, str] = dict(DOCUMENTED_IMAGE_TYPES)
OPTION_KEYS = tuple(field.name for field in fields(Options) if field.name != "limits")
LIMIT_KEYS = tuple(field.name for field in fields(Limits))
# The keys whose mistake leaves a rule publishing its `ros` for every item of its for_each: all but
# `enabled` and `match`.
PUBLISHING_KEYS = frozenset(
    {"name", "for_each", "direction", "converter", "sim", "ros", "type", "frame_id", "tf", "convention"}
    | {"params", "limits", *OPTION_KEYS}
) - {"enabled"}


def load_mapping(path: str | Path, limits: YamlLimits | None = None) -> MappingDoc:
    """Read, validate and build the mapping in `path` (a file, or a shipped mapping's name: see
    resources.mapping_path); raise MappingError with every problem found.

    `limits` bounds the file's size and its alias expansion (generous defaults)."""
    spec, path = str(path), mapping_path(path)
    file = str(path)
    limits = limits or YamlLimits()
    try:
        text = read_config_text(path, limit=limits.max_bytes)
    except ConfigFileError as err:
        message = err.about("mapping file")
        if err.unreadable and is_bare_name(spec) and not path.exists():  # `enuu`: a shipped name mistyped?
            message += shipped_hint(spec)
        raise MappingError.single(file, message, err.line, err.column, unreadable=err.unreadable) from None
    return load_mapping_text(text, file, limits)


def load_mapping_text(text: str, file: str = "<string>", limits: YamlLimits | None = None) -> MappingDoc:
    """Validate and build a mapping from YAML text; `file` names it in messages."""
    data, marks = load_marked(text, file, limits)
    if not isinstance(data, dict):
        kind = "a list" if isinstance(data, list) else f"the scalar {data!r}"
        raise MappingError.single(file, f"the top level must be a mapping of keys (found {kind})", 1, 1)
    merged: list[Problem] = []  # the mistakes of an extending file's own rules, told with the rest
    data, marks = resolve(data, Origins.of(marks, file), limits=limits, sink=merged)
    schema_found = schema_problems(data, marks, file)
    problems = [*merged, *(problem for _, problem in schema_found)]
    bad_rules = {path[1] for path, _ in schema_found if len(path) > 1 and path[0] == "rules"}
    if any(len(path) < 2 or path[0] != "rules" for path, _ in schema_found):
        raise MappingError(sorted(problems))  # the document's frame is broken: rules cannot be built
    data, unusable = apply_variables(data, marks, file)
    problems += unusable
    defaults_raw = data.get("defaults", {})
    defaults = _options(defaults_raw, Options())
    convention = defaults_raw.get("convention", "ned")
    rules = [
        _rule(
            raw,
            defaults,
            convention,
            marks.value(("rules", index))[0],
            file_of(marks, ("rules", index), file),
            _place(marks, ("rules", index, "ros"), file) if "ros" in raw else None,
        )
        for index, raw in enumerate(data["rules"])
        if index not in bad_rules
    ]
    indexes = [index for index in range(len(data["rules"])) if index not in bad_rules]
    refused: list[tuple[Rule, int]] = []  # built from their other keys, so that one run shows every mistake
    for index in sorted(bad_rules):
        bad_keys = {path[2] for path, _ in schema_found if len(path) > 2 and path[:2] == ("rules", index)}
        line, origin = marks.value(("rules", index))[0], file_of(marks, ("rules", index), file)
        partial = _partial_rule(data["rules"][index], bad_keys, defaults, convention, line, origin)
        if partial is not None:
            refused.append((partial, index))
    semantic, rules = check_rules(rules, indexes, data, marks, file, refused)
    problems += semantic
    for rule, index in zip(rules, indexes):
        why = literal_problem(rule.ros) if rule.options.enabled else ""
        if why:
            problems.append(located(marks, ("rules", index, "ros"), file, f"rule '{rule.name}': {why}"))
    if problems:
        raise MappingError(sorted(set(problems)))
    image_types = data.get("image_types")
    table = {int(k): v for k, v in image_types.items()} if image_types else dict(DEFAULT_IMAGE_TYPES)
    return MappingDoc(
        version=data["version"],
        image_types=MappingProxyType(dict(sorted(table.items()))),
        defaults=defaults,
        rules=tuple(rules),
        source=file,
        files=getattr(marks, "chain", ()) or (file,),
    )


def _place(marks: Any, path: tuple[Any, ...], file: str) -> tuple[str, int, int]:
    """The file, line and column of the value at `path`."""
    return (file_of(marks, path, file), *marks.value(path))


def _options(raw: dict[str, Any], base: Options) -> Options:
    values = {key: raw.get(key, getattr(base, key)) for key in OPTION_KEYS}
    limits_raw = dict(raw.get("limits") or {})
    box = limits_raw.get("position_box")
    if isinstance(box, dict):
        limits_raw["position_box"] = PositionBox(tuple(box["min"]), tuple(box["max"]))
    limits = Limits(**{key: limits_raw.get(key, getattr(base.limits, key)) for key in LIMIT_KEYS})
    values["queue_size"] = int(values["queue_size"])
    if "qos" in raw:
        values["qos"] = qos_of(raw["qos"])
    return Options(**values, limits=limits)


def _partial_rule(
    raw: Any, bad_keys: set[Any], defaults: Options, convention: str, line: int, file: str
) -> Rule | None:
    """A rule with schema problems, without its bad keys: enough to check its templates, or None when its
    name or for_each is not usable."""
    if not isinstance(raw, dict):
        return None
    keep = {key: value for key, value in raw.items() if key not in bad_keys}
    if not isinstance(keep.get("name"), str) or keep.get("for_each") not in DOMAIN_VARIABLES:
        return None
    if not bad_keys <= PUBLISHING_KEYS:  # a bad `enabled` or `match`, or a misspelt key that may be either:
        keep["enabled"] = False  # whether it publishes its `ros` is unknown, so no duplicate is claimed
    keep.setdefault("direction", "")
    keep.setdefault("converter", "")
    try:
        return _rule(keep, defaults, convention, line, file)
    except (KeyError, TypeError, ValueError, AttributeError):  # another key it needs is unusable
        return None


def _rule(
    raw: dict[str, Any],
    defaults: Options,
    convention: str,
    line: int,
    file: str,
    ros_place: tuple[str, int, int] | None = None,
) -> Rule:
    tf = raw.get("tf")
    return Rule(
        name=raw["name"],
        domain=raw["for_each"],
        direction=raw["direction"],
        sim=raw.get("sim"),
        ros=raw.get("ros"),
        ros_type=raw.get("type"),
        converter=raw["converter"],
        frame_id=raw.get("frame_id"),
        tf=TfSpec(tf["parent"], tf["child"], bool(tf.get("static", False))) if tf else None,
        convention=raw.get("convention", convention),
        options=_options(raw, defaults),
        params=MappingProxyType(dict(raw.get("params") or {})),
        line=line,
        match=selections_of(raw.get("match")),
        file=file,
        ros_place=ros_place,
    )
