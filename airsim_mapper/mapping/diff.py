"""The difference between two sets of bridges: what applying an edited mapping adds, removes and changes.

A bridge is identified by its name (`rule[element]`); it is unchanged when its whole expanded spec is equal,
and only then may a running node keep it (its publishers, subscribers and simulator subscriptions).
"""

from __future__ import annotations

from collections.abc import Iterable
from dataclasses import dataclass

from airsim_mapper.mapping.model import BridgeSpec


@dataclass(frozen=True)
class BridgeDiff:
    """Bridge names, each in the order of the bridges they come from."""

    added: tuple[str, ...]
    removed: tuple[str, ...]
    changed: tuple[str, ...]
    kept: tuple[str, ...]

    @property
    def empty(self) -> bool:
        return not (self.added or self.removed or self.changed)

    def summary(self) -> str:
        return (
            f"{len(self.added)} added, {len(self.removed)} removed, {len(self.changed)} changed, "
            f"{len(self.kept)} unchanged"
        )


def bridge_diff(old: Iterable[BridgeSpec], new: Iterable[BridgeSpec]) -> BridgeDiff:
    """What turns the bridges `old` into `new`."""
    before = {spec.name: spec for spec in old}
    after = {spec.name: spec for spec in new}
    return BridgeDiff(
        added=tuple(name for name in after if name not in before),
        removed=tuple(name for name in before if name not in after),
        changed=tuple(name for name in after if name in before and after[name] != before[name]),
        kept=tuple(name for name in after if name in before and after[name] == before[name]),
    )


def format_diff(diff: BridgeDiff, old: Iterable[BridgeSpec], new: Iterable[BridgeSpec]) -> str:
    """One line a difference (`+ name  ros`, `- name  ros`, `~ name  what changed`), then the summary."""
    before = {spec.name: spec for spec in old}
    after = {spec.name: spec for spec in new}
    lines = [f"+ {name}  {after[name].ros or '(tf)'}" for name in diff.added]
    lines += [f"- {name}  {before[name].ros or '(tf)'}" for name in diff.removed]
    lines += [f"~ {name}  {', '.join(changes(before[name], after[name]))}" for name in diff.changed]
    return "\n".join([*lines, diff.summary()])


def changes(old: BridgeSpec, new: BridgeSpec) -> list[str]:
    """`field: old -> new` for each field that differs (options by option)."""
    out = []
    for field in ("ros", "sim", "ros_type", "converter", "frame_id", "tf", "convention", "direction", "qos"):
        if getattr(old, field) != getattr(new, field):
            out.append(f"{field}: {getattr(old, field)} -> {getattr(new, field)}")
    if old.options != new.options:
        for field in [name for name in old.options.__dataclass_fields__ if name != "qos"]:  # bridge's own
            a, b = getattr(old.options, field), getattr(new.options, field)
            if a != b:
                out.append(f"{field}: {a} -> {b}")
    if dict(old.params) != dict(new.params):
        out.append(f"params: {dict(old.params)} -> {dict(new.params)}")
    return out or ["source"]
