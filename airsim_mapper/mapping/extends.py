"""`extends:` a mapping builds on a shipped mapping (`extends: default`) or a file (`extends: ./base.yaml`,
relative to the extending file), and the result is one merged document, as if written in one file.

Merging a child onto its (already resolved) base:
- `rules`: an entry whose `name` is a base rule's overrides it: a partial entry (without all of `for_each`,
  `direction`, `converter`) merges into the base rule key by key (maps such as `params`, `tf`, `limits` and
  `match` merge too; other values replace); a full entry replaces the base rule. `remove: [names]` drops
  base rules. Any other full entry is a new rule, appended in the child's order; a partial entry naming no
  base rule is an error with a did-you-mean.
- `defaults` merge key by key (and `limits` inside them), `image_types` and `variables` entry by entry.
- `version` is the child's; `extends` and `remove` do not appear in the result.

Every value of the merged document keeps where it was written (`Origins`: file, line and column), so later
checks report a problem in the file the user must edit. Cycles, missing or unreadable bases, overrides and
removals of rule names the base lacks are located errors.
"""

from __future__ import annotations

import copy
import functools
from pathlib import Path
from typing import Any

from airsim_mapper.common.files import MAX_CONFIG_BYTES, ConfigFileError, read_config_text
from airsim_mapper.common.image_types import DOCUMENTED_IMAGE_TYPES
from airsim_mapper.common.resources import MAPPING_SUFFIX, MAPPINGS_DIR, shipped_mappings
from airsim_mapper.mapping.errors import MappingError, Problem
from airsim_mapper.mapping.names import did_you_mean
from airsim_mapper.mapping.origins import KeyPath, Origins, Table, located
from airsim_mapper.mapping.yamlmarks import YamlLimits, load_marked

FULL_RULE_KEYS = ("for_each", "direction", "converter")  # an entry with all of them is a whole rule
MERGED_MAPS = ("image_types", "variables", "defaults")
MAX_CHAIN = 16  # bases deep


def _located(origins: Origins, path: KeyPath, message: str, at_key: bool = False) -> Problem:
    return located(origins, path, origins.file, message, at_key)


def _merge(base: Any, over: Any) -> Any:
    """`over` merged into `base`: maps key by key (recursively), anything else replaced."""
    if isinstance(base, dict) and isinstance(over, dict):
        merged = dict(base)
        for key, value in over.items():
            merged[key] = _merge(base.get(key), value)
        return merged
    return copy.deepcopy(over)


def is_bare_name(spec: str) -> bool:
    """Whether `spec` is written as a shipped mapping's name (`enu`), not as a file."""
    return "/" not in spec and "\\" not in spec and not spec.endswith((".yaml", ".yml"))


def base_path(spec: str, file: str) -> Path:
    """The file `extends: spec` in `file` names: a shipped mapping for a bare name, else a path relative to
    the extending file's folder (the working directory for a mapping given as text)."""
    if is_bare_name(spec):
        return MAPPINGS_DIR / f"{spec}{MAPPING_SUFFIX}"
    path = Path(spec).expanduser()
    if path.is_absolute() or file.startswith("<"):
        return path
    return Path(file).parent / path


def shipped_hint(spec: str) -> str:
    """What to say of a shipped mapping name that does not exist: the close one, or the list."""
    shipped = ", ".join(shipped_mappings())
    return did_you_mean(spec, shipped_mappings()) or f" (shipped: {shipped}; a file is written ./{spec}.yaml)"


def _read_base(spec: str, origins: Origins, chain: tuple[Path, ...], limits: YamlLimits | None):
    """Load the base `spec` named at ('extends',) of the top document of `chain`."""
    here = origins.file_of(("extends",))
    path = base_path(spec, here)
    if is_bare_name(spec) and spec not in shipped_mappings():
        hint = shipped_hint(spec)
        raise MappingError([_located(origins, ("extends",), f"extends: no shipped mapping '{spec}'{hint}")])
    resolved = path.resolve()
    if resolved in chain:
        loop = " -> ".join(str(p) for p in (*chain[chain.index(resolved) :], resolved))
        raise MappingError([_located(origins, ("extends",), f"extends: cycle: {loop}")])
    if len(chain) >= MAX_CHAIN:
        raise MappingError([_located(origins, ("extends",), f"extends: more than {MAX_CHAIN} bases deep")])
    try:
        text = read_config_text(path, limit=limits.max_bytes if limits else MAX_CONFIG_BYTES)
    except ConfigFileError as err:
        what = f"extends: cannot read the base mapping '{spec}' ({path}): {err.reason}"
        raise MappingError([_located(origins, ("extends",), what)]) from None
    data, origins = _parsed(text, str(path), limits)
    return resolve(data, origins, (*chain, resolved), limits)


@functools.lru_cache(maxsize=16)
def _parsed(text: str, file: str, limits: YamlLimits | None) -> tuple[dict[str, Any], Origins]:
    """A base file's data and marks, parsed once per text: a live reload of a small mapping that extends
    `default` re-reads the base but does not parse it again. Nothing downstream mutates them."""
    data, marks = load_marked(text, file, limits)
    if not isinstance(data, dict):
        raise MappingError.single(file, "the top level must be a mapping of keys", 1, 1)
    return data, Origins.of(marks, file)


def _frame_problems(data: dict[str, Any], origins: Origins, extending: bool = True) -> list[Problem]:
    """Wrong types of the keys that steer the merge, in an extending file or (not `extending`) in a base
    (the schema checks everything else afterwards)."""
    problems = []
    if extending and (not isinstance(data.get("extends"), str) or not data["extends"].strip()):
        problems.append(_located(origins, ("extends",), "extends: expected a mapping name or a file path"))
    remove = data.get("remove", [])
    if not isinstance(remove, list) or not all(isinstance(name, str) for name in remove):
        problems.append(_located(origins, ("remove",), "remove: expected a list of rule names"))
    if not isinstance(data.get("rules", []), list):
        problems.append(_located(origins, ("rules",), "rules: expected array"))
    for key in MERGED_MAPS:
        if not isinstance(data.get(key, {}), dict):
            problems.append(_located(origins, (key,), f"{key}: expected object"))
    return problems


def resolve(
    data: dict[str, Any],
    origins: Origins,
    chain: tuple[Path, ...] = (),
    limits: YamlLimits | None = None,
    sink: list[Problem] | None = None,
) -> tuple[dict[str, Any], Origins]:
    """The document `data` with its `extends` chain merged in (unchanged without `extends`), and where each
    of its values was written; MappingError for cycles, missing bases and unknown rule names. Given a
    `sink` list, the mistakes of `data`'s own rules (a name twice, an unknown rule, a bad `after`) go
    there instead, their rules left out of the merge, so that the caller reports them with the rest."""
    if "extends" not in data:
        rules = data.get("rules") if isinstance(data.get("rules"), list) else []
        for index, rule in enumerate(rules):
            if isinstance(rule, dict) and "after" in rule:
                message = "after: only a rule of a mapping that extends another may say where it goes"
                raise MappingError([_located(origins, ("rules", index, "after"), message, at_key=True)])
        if "remove" in data:
            message = "remove: only a mapping that extends another may remove rules"
            raise MappingError([_located(origins, ("remove",), message, at_key=True)])
        return data, origins
    if not chain and not origins.file.startswith("<"):
        chain = (Path(origins.file).resolve(),)
    problems = _frame_problems(data, origins)
    if problems:
        raise MappingError(problems)
    base, base_origins = _read_base(data["extends"].strip(), origins, chain, limits)
    problems = _frame_problems(base, base_origins, extending=False)
    if problems:
        raise MappingError(problems)
    return _overlay(base, base_origins, data, origins, sink)


def _overlay(
    base: dict[str, Any],
    base_origins: Origins,
    child: dict[str, Any],
    origins: Origins,
    sink: list[Problem] | None = None,
) -> tuple[dict[str, Any], Origins]:
    """`child` merged onto its resolved `base` (see the module's docstring), with the merged marks."""
    table = Table(origins.file)
    table.copy(origins, (), ())  # the child's own marks (top level, version, ...)
    merged: dict[str, Any] = {}
    for key in ("version", *MERGED_MAPS, "rules"):
        if key in child or key in base:
            merged[key] = None  # keeps the usual key order
    for key, value in child.items():
        if key not in ("extends", "remove", "rules", *MERGED_MAPS):
            merged[key] = copy.deepcopy(value)  # version, and unknown keys for the schema to report
    for key in MERGED_MAPS:
        if key in base:
            table.copy(base_origins, (key,), (key,))
            table.copy(origins, (key,), (key,))
        if key in base or key in child:
            below = base.get(key, {})
            if key == "image_types" and key not in base:  # a partial table completes the documented one
                below = {str(number): name for number, name in DOCUMENTED_IMAGE_TYPES.items()}
            merged[key] = _merge(below, child.get(key, {}))
    merged["rules"], problems = _rules(base, base_origins, child, origins, table)
    if problems and sink is None:
        raise MappingError(sorted(problems))
    if sink is not None:
        sink.extend(problems)
    chain = (origins.file, *(base_origins.chain or (base_origins.file,)))
    return {key: value for key, value in merged.items() if value is not None}, table.origins(chain)


def _index(entries: list[tuple[Any, Any]], name: Any) -> int | None:
    """Where the rule named `name` is in `entries`, or None."""
    for at, (rule, _) in enumerate(entries):
        if isinstance(rule, dict) and rule.get("name") == name:
            return at
    return None


def _rules(
    base: dict[str, Any], base_origins: Origins, child: dict[str, Any], origins: Origins, table: Table
) -> tuple[list[Any], list[Problem]]:
    """The merged rule list (see the module's docstring), with its marks written into `table`."""
    problems: list[Problem] = []
    names = [rule["name"] for rule in base.get("rules") or [] if isinstance(rule, dict) and "name" in rule]
    label = child["extends"].strip()
    removed = set()
    for index, name in enumerate(child.get("remove", [])):
        if name not in names:
            message = f"remove: the base '{label}' has no rule '{name}'{did_you_mean(name, names)}"
            problems.append(_located(origins, ("remove", index), message))
        removed.add(name)
    entries: list[tuple[Any, list[tuple[Origins, KeyPath]]]] = [
        (rule, [(base_origins, ("rules", index))])
        for index, rule in enumerate(base.get("rules") or [])
        if not (isinstance(rule, dict) and rule.get("name") in removed)
    ]
    seen: dict[str, int] = {}
    tails: dict[str, str] = {}  # anchor -> the last new rule placed after it
    for index, rule in enumerate(child.get("rules") or []):
        here = ("rules", index)
        name = rule.get("name") if isinstance(rule, dict) else None
        full = isinstance(rule, dict) and all(key in rule for key in FULL_RULE_KEYS)
        if not isinstance(name, str):
            entries.append((rule, [(origins, here)]))  # the schema reports what is wrong with it
            continue
        if name in seen:
            first = origins.value(("rules", seen[name]))[0]
            message = f"rule '{name}' appears twice in this mapping (first at line {first})"
            problems.append(_located(origins, (*here, "name"), message))
            continue
        seen[name] = index
        at = _index(entries, name)
        after = rule.get("after")
        if after is not None and (at is not None or not full):
            message = f"rule '{name}': after places a new rule; an override keeps the base rule's place"
            problems.append(_located(origins, (*here, "after"), message, at_key=True))
            continue
        rule = {key: value for key, value in rule.items() if key != "after"}
        if at is not None:
            old, sources = entries[at]
            entries[at] = (
                (rule, [(origins, here)]) if full else (_merge(old, rule), [*sources, (origins, here)])
            )
        elif full and after is None:
            entries.append((rule, [(origins, here)]))
        elif full:
            anchor = _index(entries, tails.get(after, after))
            if anchor is None:
                hint = did_you_mean(
                    after, [entry[0].get("name") for entry in entries if isinstance(entry[0], dict)]
                )
                message = f"rule '{name}': after: no rule '{after}' to place it after{hint}"
                problems.append(_located(origins, (*here, "after"), message))
                continue
            entries.insert(anchor + 1, (rule, [(origins, here)]))
            tails[after] = name
        else:
            why = "is dropped by remove" if name in removed else f"is not in the base '{label}'"
            hint = "" if name in removed else did_you_mean(name, names)
            missing = [key for key in FULL_RULE_KEYS if key not in rule]
            partial = f" (it has no {', '.join(missing)})" if len(missing) < len(FULL_RULE_KEYS) else ""
            message = (
                f"rule '{name}' overrides a rule that {why}{hint}; a new rule needs "
                f"{', '.join(FULL_RULE_KEYS)}{partial}"
            )
            problems.append(_located(origins, (*here, "name"), message))
    for path in [p for p in (*table.values, *table.keys) if p[:1] == ("rules",) and len(p) > 1]:
        table.values.pop(path, None)
        table.keys.pop(path, None)
    if "rules" not in child and "rules" in base:
        table.copy_one(base_origins, ("rules",))
    for at, (_, sources) in enumerate(entries):
        for source, old in sources:
            table.copy(source, old, ("rules", at))
    return [copy.deepcopy(rule) for rule, _ in entries], problems


def resolved_document(text: str, file: str, limits: YamlLimits | None = None) -> dict[str, Any]:
    """The mapping in `text` with its `extends` chain merged in: what `validate-mapping --resolved` prints."""
    data, marks = load_marked(text, file, limits)
    if not isinstance(data, dict):
        raise MappingError.single(file, "the top level must be a mapping of keys", 1, 1)
    return resolve(data, Origins.of(marks, file), limits=limits)[0]
