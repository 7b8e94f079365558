"""Where each value of a mapping document was written, when the document was merged from several files
(`extends`): the marks of `yamlmarks.Marks` plus the file of each value and key."""

from __future__ import annotations

import functools
from dataclasses import dataclass, field
from typing import Any

from airsim_mapper.mapping.errors import Problem
from airsim_mapper.mapping.yamlmarks import Marks

KeyPath = tuple[Any, ...]


@dataclass(frozen=True)
class Origins(Marks):
    """Marks of a document merged from several files: each value and key also knows its file."""

    value_files: dict[KeyPath, str] = field(default_factory=dict)
    key_files: dict[KeyPath, str] = field(default_factory=dict)
    file: str = "<string>"  # the file the user named (for paths nobody wrote, e.g. the top level)
    chain: tuple[str, ...] = ()  # with extends: this file and each of its bases, in order
    # (merged rule index, file) -> the rule's index in that file, where the two differ
    rule_indices: dict[tuple[int, str], int] = field(default_factory=dict)

    @classmethod
    def of(cls, marks: Marks, file: str) -> Origins:
        """The marks of one file."""
        if isinstance(marks, Origins):
            return marks
        return cls(
            dict(marks.values),
            dict(marks.keys),
            dict.fromkeys(marks.values, file),
            dict.fromkeys(marks.keys, file),
            file,
        )

    @functools.cached_property
    def heads(self) -> dict[KeyPath, tuple[list[KeyPath], list[KeyPath]]]:
        """Value and key paths grouped by their first two parts (a rule's subtree), for Table.copy."""
        groups: dict[KeyPath, tuple[list[KeyPath], list[KeyPath]]] = {}
        for which, table in enumerate((self.values, self.keys)):
            for path in table:
                if len(path) >= 2:
                    groups.setdefault(path[:2], ([], []))[which].append(path)
        return groups

    def file_of(self, path: KeyPath, at_key: bool = False) -> str:
        """The file `path`'s value (or key) was written in: the same walk up as `value` and `key`."""
        if at_key and path in self.keys:
            return self.key_files.get(path, self.file)
        for cut in range(len(path), -1, -1):
            if path[:cut] in self.values:
                return self.value_files.get(path[:cut], self.file)
        return self.file

    def local_index(self, index: int, file: str) -> int:
        """The index in `file` of the merged rule `index`."""
        return self.rule_indices.get((index, file), index)

    def local(self, path: KeyPath, at_key: bool = False) -> KeyPath:
        """`path` as the file it was written in numbers it: a merged rule's index becomes its index there."""
        if len(path) >= 2 and path[0] == "rules" and isinstance(path[1], int):
            return ("rules", self.local_index(path[1], self.file_of(path, at_key)), *path[2:])
        return path


def file_of(marks: Marks, path: KeyPath, file: str, at_key: bool = False) -> str:
    """The file a problem at `path` belongs to: from Origins when the document was merged, else `file`."""
    return marks.file_of(path, at_key) if isinstance(marks, Origins) else file


def local_path(marks: Marks, path: KeyPath, at_key: bool = False) -> KeyPath:
    """`path` as numbered in the file it was written in (see Origins.local)."""
    return marks.local(path, at_key) if isinstance(marks, Origins) else path


def key_text(path: KeyPath) -> str:
    """A key path as text: `rules[3].params.args`."""
    text = ""
    for part in path:
        text += f"[{part}]" if isinstance(part, int) else (f".{part}" if text else str(part))
    return text


def place_text(file: str, line: int, here: str) -> str:
    """Where another rule was written, as seen from a problem in `here`: `line 12` in the same file,
    `base.yaml:12` in another."""
    return f"{file}:{line}" if file and file != here else f"line {line}"


def located(marks: Marks, path: KeyPath, file: str, message: str, at_key: bool = False) -> Problem:
    """A problem at `path`: its file, line and column (of the key with `at_key`, else of the value), and
    its key path as the file numbers it."""
    line, column = marks.key(path) if at_key else marks.value(path)
    where = file_of(marks, path, file, at_key)
    return Problem(where, line, column, message, key_text(local_path(marks, path, at_key)))


class Table:
    """Origins under construction: copies of subtrees of other Origins, re-rooted."""

    def __init__(self, file: str) -> None:
        self.file = file
        self.values: dict[KeyPath, tuple[int, int]] = {}
        self.keys: dict[KeyPath, tuple[int, int]] = {}
        self.value_files: dict[KeyPath, str] = {}
        self.key_files: dict[KeyPath, str] = {}
        self.rule_indices: dict[tuple[int, str], int] = {}

    def copy(self, source: Origins, old: KeyPath, new: KeyPath) -> None:
        """Copy every mark at or below `old` in `source` to the same place below `new`."""
        size = len(old)
        group = source.heads.get(old, ([], [])) if size == 2 else None
        for which, (table, files, target, target_files) in enumerate(
            (
                (source.values, source.value_files, self.values, self.value_files),
                (source.keys, source.key_files, self.keys, self.key_files),
            )
        ):
            for path in table if group is None else group[which]:
                if path[:size] == old:
                    moved = (*new, *path[size:])
                    target[moved] = table[path]
                    target_files[moved] = files.get(path, source.file)
                    if size == 2 and old[0] == new[0] == "rules":
                        written = target_files[moved]
                        self.rule_indices[(new[1], written)] = source.local_index(old[1], written)

    def copy_one(self, source: Origins, path: KeyPath) -> None:
        """Copy the marks of `path` itself (not those below it)."""
        if path in source.values:
            self.values[path] = source.values[path]
            self.value_files[path] = source.value_files.get(path, source.file)
        if path in source.keys:
            self.keys[path] = source.keys[path]
            self.key_files[path] = source.key_files.get(path, source.file)

    def origins(self, chain: tuple[str, ...] = ()) -> Origins:
        return Origins(
            self.values, self.keys, self.value_files, self.key_files, self.file, chain, self.rule_indices
        )
