"""Semantic checks of mapping rules, beyond what the schema can say.

- the converter exists (with a did-you-mean) and fits the rule's direction and ROS type;
- the ROS type is a genpy-generated message or service of a ROS message package, and imports (the leaf
  `airsim_mapper.common.ros_types` decides: a mapping never makes Python import an arbitrary module);
- the sides a converter needs are present; a rule without a ROS name broadcasts tf;
- templates are well formed and use only the variables of the rule's domain;
- ROS names the templates generate are legal; no two rules produce the same ROS name; rule names are unique.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Sequence
from typing import Any

from airsim_mapper.common.ros_types import ros_type_kind, ros_type_problem
from airsim_mapper.convert import catalog
from airsim_mapper.mapping import template
from airsim_mapper.mapping.errors import Problem
from airsim_mapper.mapping.match import match_problems
from airsim_mapper.mapping.model import DOMAIN_VARIABLES, ROS_TO_SIM, SIM_TO_ROS, Rule
from airsim_mapper.mapping.names import did_you_mean, ros_name_problem
from airsim_mapper.mapping.origins import located, place_text
from airsim_mapper.mapping.yamlmarks import Marks

SAMPLE_VALUE = "x1"  # stands for every template variable when checking generated names statically
IMAGE_BOUNDS = ("max_pixels", "max_bytes")  # what a converter marked max_pixels in the catalogue takes
# the image_transport converters' params (ranges in the schema), with the image kinds that take each
TRANSPORT_PARAMS = {
    "jpeg_quality": (catalog.COLOUR,),
    "png_level": (catalog.COLOUR, catalog.FLOAT),
    "depth_max": (catalog.FLOAT,),
    "depth_quantization": (catalog.FLOAT,),
}


class _Checker:
    def __init__(self, data: dict[str, Any], marks: Marks, file: str) -> None:
        self.data = data
        self.marks = marks
        self.file = file
        self.problems: list[Problem] = []

    def add(self, path: tuple[Any, ...], message: str, at_key: bool = False) -> None:
        self.problems.append(located(self.marks, path, self.file, message, at_key))

    def rule(self, rule: Rule, index: int) -> Rule:
        base = ("rules", index)
        info = catalog.find(rule.converter)
        if info is None:
            hint = did_you_mean(rule.converter, catalog.CONVERTERS)
            self.add((*base, "converter"), f"rule '{rule.name}': unknown converter '{rule.converter}'{hint}")
        else:
            self._converter_fit(rule, info, base)
            self._params(rule, info, base)
        self._sides(rule, info, base)
        self.templates(rule, base)
        self._options(rule, base)
        for path, at_key, message in match_problems(self.data["rules"][index].get("match"), rule.domain):
            self.add((*base, "match", *path), f"rule '{rule.name}': {message}", at_key)
        kind = "topic"
        if rule.ros_type is not None:
            found = ros_type_kind(rule.ros_type)
            if found is None:
                self.add(
                    (*base, "type"),
                    f"rule '{rule.name}': ROS type '{rule.ros_type}'{ros_type_problem(rule.ros_type)}",
                )
            else:
                kind = found
        return dataclasses.replace(rule, ros_kind=kind)

    def _params(self, rule: Rule, info: catalog.ConverterInfo, base: tuple[Any, ...]) -> None:
        """The params the converter cannot run without, and those with a fixed set of values."""
        for key, what in info.required_params.items():
            if key not in rule.params:
                where = (*base, "params") if "params" in self.data["rules"][base[1]] else base
                self.add(where, f"rule '{rule.name}': converter '{info.name}' needs params.{key}: {what}")
        for key, choices in info.param_choices.items():
            value = rule.params.get(key, next(iter(choices)))
            where = (*base, "params", key) if key in rule.params else base
            if not isinstance(value, str) or value not in choices:
                hint = did_you_mean(str(value), choices)
                self.add(
                    where,
                    f"rule '{rule.name}': params.{key} must be one of {', '.join(choices)}, got "
                    f"{value!r}{hint}",
                )
                continue
            method, called = choices[value], (rule.sim or "").rsplit("/", 1)[-1]
            if method and called in choices.values() and called != method:
                self.add(
                    where,
                    f"rule '{rule.name}': params.{key} {value} goes with the simulator method "
                    f"{method}, not {called}",
                )

    def _converter_fit(self, rule: Rule, info: catalog.ConverterInfo, base: tuple[Any, ...]) -> None:
        if info.direction != rule.direction:
            self.add(
                (*base, "direction"),
                f"rule '{rule.name}': converter '{info.name}' is {info.direction}, "
                f"but the rule's direction is {rule.direction}",
            )
        if rule.ros_type is not None and rule.ros_type not in info.ros_types:
            self.add(
                (*base, "type"),
                f"rule '{rule.name}': converter '{info.name}' handles {' or '.join(info.ros_types)}, "
                f"not {rule.ros_type}",
            )
        if rule.sim is None and info.sim_kind in ("topic", "service"):
            what = "a simulator topic" if info.sim_kind == "topic" else "a simulator service method"
            self.add(base, f"rule '{rule.name}': 'sim' is required: converter '{info.name}' needs {what}")

    def _sides(self, rule: Rule, info: catalog.ConverterInfo | None, base: tuple[Any, ...]) -> None:
        if rule.ros is None:
            if rule.tf is None or rule.direction != SIM_TO_ROS:
                self.add(
                    base,
                    f"rule '{rule.name}': 'ros' is required (only a sim_to_ros rule with 'tf' may omit it)",
                )
        elif rule.ros_type is None:
            self.add((*base, "ros"), f"rule '{rule.name}': 'type' is required when 'ros' is set")

    def templates(self, rule: Rule, base: tuple[Any, ...]) -> None:
        """The rule's template mistakes (malformed, unknown variables) and a `ros` that is no ROS name."""
        allowed = DOMAIN_VARIABLES[rule.domain]
        fields = {("sim",): rule.sim, ("ros",): rule.ros, ("frame_id",): rule.frame_id}
        if rule.tf is not None:
            fields |= {("tf", "parent"): rule.tf.parent, ("tf", "child"): rule.tf.child}
        fields |= dict(template.templates_in(rule.params, ("params",)))
        for keys, text in fields.items():
            if text is None:
                continue
            key = ".".join(map(str, keys))
            path = (*base, *keys)
            bad = template.malformed(text)
            if bad:
                self.add(path, f"rule '{rule.name}': {key} '{text}': {bad}")
                continue
            declared = self.data.get("variables") or {}
            for name in template.variables(text):
                if name not in allowed and name not in declared:  # a bad variable is reported itself
                    known = (*allowed, *declared)
                    hint = did_you_mean(name, known) or f" (for_each {rule.domain} has: {', '.join(allowed)})"
                    self.add(
                        path,
                        f"rule '{rule.name}': unknown template variable <{name}> in {key} "
                        f"for for_each {rule.domain}{hint}",
                    )
        if rule.ros is not None and not template.malformed(rule.ros):
            sample = template.PLACEHOLDER.sub(
                lambda m: "" if m.group(1) in ("namespace", "frame_prefix") else SAMPLE_VALUE, rule.ros
            )
            why = ros_name_problem(sample)
            if why:
                self.add(
                    (*base, "ros"), f"rule '{rule.name}': ros '{rule.ros}' is not a valid ROS name: {why}"
                )

    def position_box(self, path: tuple[Any, ...], limits: Any, owner: str) -> None:
        """A position box's min must not exceed its max on any axis."""
        box = limits.get("position_box") if isinstance(limits, dict) else None
        if not isinstance(box, dict):
            return
        inverted = [axis for axis, low, high in zip("xyz", box["min"], box["max"]) if low > high]
        if inverted:
            self.add(
                (*path, "limits", "position_box"),
                f"{owner}: limits.position_box has min above max on {', '.join(inverted)}",
            )

    def _options(self, rule: Rule, base: tuple[Any, ...]) -> None:
        raw = self.data["rules"][base[1]]
        self.position_box(base, raw.get("limits"), f"rule '{rule.name}'")
        for key in IMAGE_BOUNDS:
            if key not in rule.params:
                continue
            value = rule.params[key]
            info = catalog.find(rule.converter)
            if info is None or not info.max_pixels:
                self.add(
                    (*base, "params", key),
                    f"rule '{rule.name}': params.{key} applies only to the image converters",
                    True,
                )
            elif isinstance(value, bool) or not isinstance(value, int) or value <= 0:
                self.add(
                    (*base, "params", key),
                    f"rule '{rule.name}': params.{key} must be a positive integer, got {value!r}",
                )
        kind = getattr(catalog.find(rule.converter), "image_kind", None)
        for key, kinds in TRANSPORT_PARAMS.items():
            if key in rule.params and kind not in kinds:
                takers = [c.name for c in catalog.CONVERTERS.values() if c.image_kind in kinds]
                self.add(
                    (*base, "params", key),
                    f"rule '{rule.name}': params.{key} applies only to {' and '.join(takers)}",
                    True,
                )
        if rule.direction == SIM_TO_ROS:
            for key in ("watchdog_s", "limits"):
                if raw.get(key) is not None:
                    self.add(
                        (*base, key), f"rule '{rule.name}': {key} applies only to {ROS_TO_SIM} rules", True
                    )

    def across(self, rules: Sequence[Rule], indexes: Sequence[int]) -> None:
        names: dict[str, int] = {}
        outputs: dict[str, tuple[str, str, int]] = {}
        for rule, index in zip(rules, indexes):
            if rule.name in names:
                first = self.marks.value(("rules", names[rule.name]))[0]
                self.add(
                    ("rules", index, "name"),
                    f"duplicate rule name '{rule.name}' (first used at line {first})",
                )
            else:
                names[rule.name] = index
            if rule.ros is None or not rule.options.enabled or rule.match:
                continue  # rules with a match may share a template; expansion finds real collisions
            if rule.ros in outputs:
                other, file, line = outputs[rule.ros]
                where = place_text(file, line, self.file)
                self.add(
                    ("rules", index, "ros"),
                    f"rule '{rule.name}': ROS name '{rule.ros}' is also used by rule '{other}' ({where})",
                )
            else:
                outputs[rule.ros] = (rule.name, rule.file, rule.line)


def check_rules(
    rules: Sequence[Rule],
    indexes: Sequence[int],
    data: dict[str, Any],
    marks: Marks,
    file: str,
    refused: Sequence[tuple[Rule, int]] = (),
) -> tuple[list[Problem], list[Rule]]:
    """All semantic problems of `rules` (at `indexes` of data['rules']), and the rules with their ros_kind.

    `refused` are the rules the schema refused, each built from its other keys with its index: their
    templates are checked, and they take part in the checks across rules (a name used twice is found
    whichever of the two the schema refused)."""
    checker = _Checker(data, marks, file)
    checker.position_box(("defaults",), data.get("defaults", {}).get("limits"), "defaults")
    checked = [checker.rule(rule, index) for rule, index in zip(rules, indexes)]
    for rule, index in refused:
        checker.templates(rule, ("rules", index))
    every = sorted([*zip(checked, indexes), *refused], key=lambda pair: pair[1])
    checker.across([rule for rule, _ in every], [index for _, index in every])
    return checker.problems, checked
