"""Safe YAML loading that remembers where every value came from.

`load_marked(text, file)` returns plain Python data (dicts with str keys, lists, scalars) and a table from
each value's path (a tuple of keys and indexes) to its (line, column), 1-based. Only the safe YAML tags are
constructed; `!!python/...` tags and other unknown tags are errors. Duplicate keys and recursive aliases are
errors too, never silently accepted. Merge keys (`<<: *defaults`) are supported, and a mapping's own keys
win over merged ones.

Aliases are expanded into plain data, so a few hundred bytes of nested aliases ("billion laughs") could
expand to billions of values. `YamlLimits` bounds the expansion (values built, alias expansions) and the
file size; exceeding a bound is a located error, raised as soon as it happens.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import yaml

from airsim_mapper.mapping.errors import MappingError, Problem

Path = tuple[Any, ...]
MAX_DEPTH = 64
PLAIN_COLLECTION_TAGS = ("tag:yaml.org,2002:map", "tag:yaml.org,2002:seq")
MERGE_TAG = "tag:yaml.org,2002:merge"


@dataclass(frozen=True)
class YamlLimits:
    """Bounds on a mapping document (the shipped mappings use a few hundred values and no alias)."""

    max_bytes: int = 16 * 1024 * 1024  # size of the file
    max_values: int = 100_000  # values built, aliases expanded
    max_alias_expansions: int = 10_000  # times an alias (or a value inside one) is expanded


class _TooLarge(Exception):
    """The document exceeded a YamlLimits bound; the problem is already recorded."""


@dataclass(frozen=True)
class Marks:
    """Where each path's value (and, for mapping entries, its key) starts in the file."""

    values: dict[Path, tuple[int, int]]
    keys: dict[Path, tuple[int, int]]

    def value(self, path: Path) -> tuple[int, int]:
        """The nearest known mark for `path`, walking up to its parents."""
        for cut in range(len(path), -1, -1):
            if path[:cut] in self.values:
                return self.values[path[:cut]]
        return (1, 1)

    def key(self, path: Path) -> tuple[int, int]:
        """The mark of the key that names `path` (or of its value when it has no key)."""
        return self.keys.get(path) or self.value(path)


def _mark(node: yaml.Node) -> tuple[int, int]:
    return (node.start_mark.line + 1, node.start_mark.column + 1)


MISSING_COLON = "could not find expected ':'"
# PyYAML's words for the commonest indentation mistakes -> what they mean in a mapping file
PLAIN_PROBLEMS = (
    (
        "expected <block end>, but found '-'",
        "a list item ('- ') where the mapping above expects its next key (a rule's keys after its first "
        "take no '- ')",
    ),
    (
        "expected <block end>",
        "this line is indented differently from the lines above it (the keys of one mapping, and the "
        "items of one list, start in the same column)",
    ),
    (
        "mapping values are not allowed here",
        "a ':' where no key can start: is this line indented deeper than the key above it, or does a "
        "value hold ': ' and need quotes?",
    ),
    (
        MISSING_COLON,
        "a key without its ':', or a line indented under a value as if it continued it",
    ),
)


def _yaml_problem(file: str, err: yaml.YAMLError) -> Problem:
    mark = getattr(err, "problem_mark", None) or getattr(err, "context_mark", None)
    problem = getattr(err, "problem", None) or str(err)
    context = getattr(err, "context", None)
    if "'\\t'" in problem:
        problem, context = "a tab character; YAML allows only spaces for indentation", None
    known = next(((start, words) for start, words in PLAIN_PROBLEMS if problem.startswith(start)), None)
    if known is not None:
        start, words = known
        if start == MISSING_COLON and getattr(err, "context_mark", None) is not None:
            mark = err.context_mark  # the key that lacks its ':', not the line after it
        problem, context = words, f"YAML: {problem}"
    text = f"invalid YAML: {problem}" + (f" ({context})" if context else "")
    if mark is None:
        return Problem(file, 1, 1, text)
    return Problem(file, mark.line + 1, mark.column + 1, text)


class _Builder:
    """Turns a composed YAML node tree into plain data, recording marks and collecting problems."""

    def __init__(self, loader: yaml.SafeLoader, file: str, limits: YamlLimits) -> None:
        self.loader = loader
        self.file = file
        self.limits = limits
        self.values: dict[Path, tuple[int, int]] = {}
        self.keys: dict[Path, tuple[int, int]] = {}
        self.problems: list[Problem] = []
        self.built = 0
        self.expansions = 0
        self._seen: set[int] = set()
        self._alias: yaml.Node | None = None  # the outermost alias being expanded

    def problem(self, node: yaml.Node, message: str) -> None:
        line, col = _mark(node)
        self.problems.append(Problem(self.file, line, col, message))

    def _count(self, node: yaml.Node) -> bool:
        """Count one value built; True if `node` was built before (an alias expansion). Abort beyond the
        limits, at the outermost alias being expanded."""
        self.built += 1
        again = id(node) in self._seen
        if again:
            self.expansions += 1
        else:
            self._seen.add(id(node))
        limits = self.limits
        if self.built > limits.max_values:
            what = f"more than {limits.max_values} values"
        elif self.expansions > limits.max_alias_expansions:
            what = f"more than {limits.max_alias_expansions} alias expansions"
        else:
            return again
        if self._alias is None:
            self.problem(node, f"the YAML holds {what}; nothing was loaded")
        else:
            self.problem(
                self._alias,
                f"the aliases of this anchor expand the YAML to {what} (an alias bomb?); nothing was loaded",
            )
        raise _TooLarge

    def build(self, node: yaml.Node, path: Path, stack: tuple[int, ...]) -> Any:
        if self._count(node) and self._alias is None:
            self._alias = node
            try:
                return self._build(node, path, stack)
            finally:
                self._alias = None
        return self._build(node, path, stack)

    def _build(self, node: yaml.Node, path: Path, stack: tuple[int, ...]) -> Any:
        self.values.setdefault(path, _mark(node))
        if id(node) in stack or len(stack) > MAX_DEPTH:
            self.problem(node, "recursive or too deeply nested YAML (aliases that contain themselves?)")
            return None
        stack = (*stack, id(node))
        if node.tag not in PLAIN_COLLECTION_TAGS and not isinstance(node, yaml.ScalarNode):
            self.problem(node, f"invalid YAML value: the tag '{node.tag}' is not allowed (only plain data)")
            return None
        if isinstance(node, yaml.MappingNode):
            return self._mapping(node, path, stack)
        if isinstance(node, yaml.SequenceNode):
            return [self.build(item, (*path, i), stack) for i, item in enumerate(node.value)]
        return self._scalar(node)

    def _scalar(self, node: yaml.Node) -> Any:
        try:
            return self.loader.construct_object(node, deep=True)
        except yaml.YAMLError as err:
            problem = getattr(err, "problem", None) or str(err)
            self.problem(node, f"invalid YAML value: {problem}")
            return None

    def _mapping(self, node: yaml.MappingNode, path: Path, stack: tuple[int, ...]) -> dict[str, Any]:
        """A mapping's entries. Merge keys (`<<: *anchor`, or a list of anchors) bring in the merged
        mappings' entries (an earlier mapping of a list wins over a later one, as in PyYAML), and the
        mapping's own keys win over every merged one; only the own keys must be unique."""
        own_count = sum(key.tag != MERGE_TAG for key, _value in node.value)
        if own_count < len(node.value):
            entries = _flat_size(node, {})
            if entries > self.limits.max_values:
                self.problem(
                    node,
                    f"merge keys expand this mapping to more than {self.limits.max_values} entries "
                    "(a merge bomb?); nothing was loaded",
                )
                raise _TooLarge
        try:
            self.loader.flatten_mapping(node)  # merged pairs first, then the own ones (PyYAML's order)
        except (yaml.YAMLError, RecursionError) as err:
            self.problem(node, f"invalid YAML merge: {getattr(err, 'problem', None) or type(err).__name__}")
            return {}
        split = len(node.value) - own_count
        entries: dict[str, tuple[yaml.Node, yaml.Node]] = {}
        own: set[str] = set()
        for index, (key_node, value_node) in enumerate(node.value):
            if not isinstance(key_node, yaml.ScalarNode):
                self.problem(key_node, "mapping keys must be plain scalars")
                continue
            raw_key = self._scalar(key_node)
            key = "null" if raw_key is None else str(raw_key)
            if index >= split:
                if key in own:
                    self.problem(key_node, f"duplicate key '{key}'")
                    continue
                own.add(key)
            entries[key] = (key_node, value_node)
        result: dict[str, Any] = {}
        for key, (key_node, value_node) in entries.items():
            self.keys[(*path, key)] = _mark(key_node)
            result[key] = self.build(value_node, (*path, key), stack)
        return result


def _flat_size(node: yaml.MappingNode, sizes: dict[int, int]) -> int:
    """How many entries `node` has once its merge keys are flattened (duplicates included, as PyYAML's
    flatten_mapping makes them), counted without flattening: each node once, so nested merges cost no more
    than their text. A mapping that merges itself counts as empty here (flattening it fails later)."""
    if id(node) in sizes:
        return sizes[id(node)]
    sizes[id(node)] = 0
    total = 0
    for key, value in node.value:
        if key.tag != MERGE_TAG:
            total += 1
            continue
        sources = value.value if isinstance(value, yaml.SequenceNode) else [value]
        total += sum(_flat_size(src, sizes) for src in sources if isinstance(src, yaml.MappingNode))
    sizes[id(node)] = total
    return total


def _reader_problem(file: str, text: str, err: yaml.reader.ReaderError) -> Problem:
    position = max(0, min(err.position, len(text)))
    line = text.count("\n", 0, position) + 1
    column = position - (text.rfind("\n", 0, position) + 1) + 1
    return Problem(file, line, column, f"invalid YAML: character #x{err.character:04x} is not allowed")


def load_marked(text: str, file: str, limits: YamlLimits | None = None) -> tuple[Any, Marks]:
    """Parse one YAML document safely; raise MappingError listing every problem found."""
    limits = limits or YamlLimits()
    if len(text) > limits.max_bytes:
        raise MappingError.single(file, f"the file is larger than {limits.max_bytes} bytes", 1, 1)
    try:
        loader = yaml.SafeLoader(text)
    except yaml.reader.ReaderError as err:
        raise MappingError([_reader_problem(file, text, err)]) from None
    try:
        try:
            node = loader.get_single_node()
        except yaml.reader.ReaderError as err:
            raise MappingError([_reader_problem(file, text, err)]) from None
        except yaml.YAMLError as err:
            raise MappingError([_yaml_problem(file, err)]) from None
        except (ValueError, RecursionError) as err:  # e.g. too deep nesting for the composer
            raise MappingError.single(file, f"invalid YAML: {type(err).__name__}", 1, 1) from None
        if node is None:
            raise MappingError.single(file, "the file is empty (expected a mapping document)", 1, 1)
        builder = _Builder(loader, file, limits)
        try:
            data = builder.build(node, (), ())
        except _TooLarge:
            raise MappingError(builder.problems[-1:]) from None
        if builder.problems:
            raise MappingError(sorted(builder.problems))
        return data, Marks(builder.values, builder.keys)
    finally:
        loader.dispose()
