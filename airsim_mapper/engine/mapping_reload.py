"""Live reload of the node's mapping: on a change of its file (or of a file it extends), or on request.

The edited mapping is loaded and expanded over the running scene before anything is touched. If it is
invalid, the located errors are logged and reported (status topic and /diagnostics) and every running
bridge stays as it was. If it is valid, the engine applies the difference only (Engine.apply_mapping).
"""

from __future__ import annotations

import os
import threading
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from typing import Any

from airsim_mapper.common.errors import ConfigError
from airsim_mapper.common.logs import ros_logger
from airsim_mapper.mapping.diff import BridgeDiff
from airsim_mapper.mapping.model import MappingDoc

log = ros_logger("airsim_mapper.mapping")
POLL_PERIOD_S = 0.25
SETTLE_S = 0.05  # a file must stay the same this long before it is read (editors write in steps)
Stamp = tuple[int, int, int] | None


def stamp(path: str) -> Stamp:
    """What identifies a version of `path` (inode, size, mtime), or None when it cannot be read."""
    try:
        info = os.stat(path)
    except OSError:
        return None
    return (info.st_ino, info.st_size, info.st_mtime_ns)


def stamps(files: Sequence[str]) -> dict[str, Stamp]:
    return {path: stamp(path) for path in files}


APPLIED, PARTIAL = "applied", "partial"


@dataclass
class Outcome:
    """One reload: applied (with the difference) or rejected (with the located errors)."""

    applied: bool
    message: str
    errors: tuple[str, ...] = ()  # rejected: the located errors; applied: the bridges that could not start
    diff: BridgeDiff | None = None

    @property
    def ok(self) -> bool:
        """Applied, with every bridge it added or changed running (the ~reload_mapping answer's success)."""
        return self.applied and not self.errors


@dataclass
class MappingReport:
    """What the status topic and /diagnostics say about the mapping."""

    file: str
    # "loaded"; after a reload "applied", "partial" (applied, but bridges it added or changed could not
    # start: `errors` names them) or "rejected" (nothing changed: `errors` are the located problems)
    state: str = "loaded"
    reloads: int = 0
    rejections: int = 0
    errors: list[str] = field(default_factory=list)
    last_change: str = ""

    def as_dict(self) -> dict[str, Any]:
        return {
            "file": self.file,
            "state": self.state,
            "reloads": self.reloads,
            "rejections": self.rejections,
            "errors": list(self.errors),
            "last_change": self.last_change,
        }


class MappingReloader:
    """Reloads `spec` (a mapping file or shipped name) into `engine`; watches its files when started."""

    def __init__(
        self,
        engine: Any,
        spec: str,
        mapping: MappingDoc,
        load: Callable[[str], MappingDoc] | None = None,
        period_s: float = POLL_PERIOD_S,
    ) -> None:
        from airsim_mapper.mapping.loader import load_mapping

        self.engine = engine
        self.spec = spec
        self.load = load or load_mapping
        self.period_s = period_s
        self.files = tuple(mapping.files or (mapping.source,))
        self.seen = stamps(self.files)
        self.report = MappingReport(mapping.source)
        self._lock = threading.Lock()
        self._stop = threading.Event()
        self._thread: threading.Thread | None = None
        engine.report_mapping(self.report.as_dict())

    def reload(self, why: str = "requested") -> Outcome:
        """Load the mapping again and apply it, or reject it; never raises for a bad mapping."""
        with self._lock:
            self.seen = stamps(self.files)
            try:
                mapping = self.load(self.spec)
                diff = self.engine.apply_mapping(mapping)
            except ConfigError as exc:
                return self._rejected(str(exc).splitlines(), why)
            except OSError as exc:
                return self._rejected([f"{self.spec}: {exc.strerror or exc}"], why)
            self.files = tuple(mapping.files or (mapping.source,))
            self.seen = stamps(self.files)
            touched = {*diff.added, *diff.changed}
            refused = getattr(self.engine, "refused_bridges", dict)()
            errors = [
                f"bridge {name} could not start: {why}" for name, why in refused.items() if name in touched
            ]
            report = self.report
            report.state = PARTIAL if errors else APPLIED
            report.errors, report.last_change = errors, diff.summary()
            report.reloads += 1
            self._publish()
        log.info("mapping %s reloaded (%s): %s", mapping.source, why, diff.summary())
        message = f"applied: {diff.summary()}" + "".join(f"\n{line}" for line in errors)
        return Outcome(True, message, tuple(errors), diff=diff)

    def _rejected(self, errors: list[str], why: str) -> Outcome:
        report = self.report
        report.state, report.errors = "rejected", errors
        report.rejections += 1
        self._publish()
        log.error(
            "mapping %s rejected (%s); every bridge keeps running:\n%s", self.spec, why, "\n".join(errors)
        )
        return Outcome(False, "rejected; every bridge keeps running:\n" + "\n".join(errors), tuple(errors))

    def _publish(self) -> None:
        self.engine.report_mapping(self.report.as_dict())
        publish = getattr(self.engine, "publish_status", None)
        if publish is not None:
            publish()

    def changed(self) -> bool:
        """Whether a watched file differs from the version last read (once it has settled)."""
        now = stamps(self.files)
        if now == self.seen:
            return False
        time.sleep(SETTLE_S)
        return stamps(self.files) == now

    def start(self) -> None:
        """Watch the mapping's files (polling) and reload on every change."""
        self._thread = threading.Thread(target=self._watch, name="mapping-watch", daemon=True)
        self._thread.start()

    def _watch(self) -> None:
        while not self._stop.wait(self.period_s):
            try:
                if self.changed():
                    self.reload("file changed")
            except Exception:  # the watcher must outlive anything a reload throws
                log.exception("mapping reload failed")

    def stop(self) -> None:
        self._stop.set()
        if self._thread is not None:
            self._thread.join(timeout=2)
