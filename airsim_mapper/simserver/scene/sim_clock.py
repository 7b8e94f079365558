"""Simulation clocks: steppable (starts at 0, follows wall time unless paused) and real-time (Unix ns).

The steppable clock is computed lazily from the monotonic wall clock, so `now_ns` is exact at any moment;
`continue_for`/`continue_until` set a target at which the clock pauses itself.

Lock-step (`lock_step=True`, as the server runs it): a continue call made while the clock is paused does
not let wall time run. The server's simulation loop advances the clock one `step_ns` at a time
(`begin_step`), does that step's work (motion, instruments, every sensor sample due at that time, images
included) and only then calls `finish_step`; a waiting continue call returns after the last step's work.
So no sample whose time falls inside the continued span is skipped, however long its rendering takes.
"""

from __future__ import annotations

import threading
import time

from airsim_mapper.simserver.wire.services import ServiceError


class SimClock:
    """Thread-safe sim clock of one scene."""

    def __init__(
        self, kind: str = "steppable", step_ns: int = 3_000_000, paused: bool = False, lock_step: bool = False
    ) -> None:
        self.kind = kind
        self.step_ns = step_ns
        self.lock_step = lock_step
        self._lock = threading.Lock()
        self._stepped = threading.Condition(self._lock)
        self._stepping = False  # a lock-step continue is in progress (the clock stays paused between steps)
        self._completed_ns = 0  # sim time whose step work is done
        self._base_sim = 0
        self._base_wall = time.monotonic_ns()
        self._paused = paused and kind == "steppable"
        self._target: int | None = None

    # -- reading

    def _settle(self) -> int:
        """Current sim time; applies a pending pause target (call with the lock held)."""
        if self.kind != "steppable":
            return time.time_ns()
        if self._paused:
            return self._base_sim
        now = self._base_sim + (time.monotonic_ns() - self._base_wall)
        if self._target is not None and now >= self._target:
            self._base_sim = self._target
            self._target = None
            self._paused = True
            return self._base_sim
        return now

    def now_ns(self) -> int:
        with self._lock:
            return self._settle()

    def is_paused(self) -> bool:
        with self._lock:
            self._settle()
            return self._paused and not self._stepping

    # -- lock-step driving (the server's simulation loop)

    def stepping(self) -> bool:
        with self._lock:
            return self._stepping

    def begin_step(self) -> int:
        """Advance a lock-step continue by one step (not past its target); the new sim time."""
        with self._lock:
            if self._stepping and self._target is not None:
                self._base_sim = min(self._base_sim + self.step_ns, self._target)
            return self._base_sim

    def finish_step(self) -> None:
        """The work of the current step is done; at the target the continue ends and its waiters wake."""
        with self._lock:
            self._completed_ns = self._base_sim
            if self._stepping and (self._target is None or self._base_sim >= self._target):
                self._end_stepping()

    def cancel_stepping(self) -> None:
        """End a lock-step continue where it is (its scene is going away): waiters return at once."""
        with self._lock:
            if self._stepping:
                self._end_stepping()

    def _end_stepping(self) -> None:
        self._stepping = False
        self._target = None
        self._stepped.notify_all()

    # -- control

    def _require_steppable(self, what: str) -> None:
        if self.kind != "steppable":
            raise ServiceError(f"This clock type doesn't support {what}.")

    def _run_from(self, sim_ns: int) -> None:
        self._base_sim = sim_ns
        self._base_wall = time.monotonic_ns()
        self._paused = False

    def pause(self, do_pause: bool) -> str:
        self._require_steppable("SimPause")
        with self._lock:
            now = self._settle()
            if do_pause:
                self._base_sim = now
                self._paused = True
                self._target = None
                if self._stepping:
                    self._end_stepping()
                return f"Sim time paused at t = {now}"
            self._target = None
            if self._stepping:
                self._end_stepping()
            if self._paused:
                self._run_from(now)
            return f"Sim time resumed from t = {now}"

    def continue_until(self, target_ns: int, wait: bool, what: str = "ContinueUntilSimTime") -> int:
        self._require_steppable(what)
        with self._lock:
            now = self._settle()
            if target_ns > now:
                self._target = int(target_ns)
                if self._paused and self.lock_step:
                    self._stepping = True
                elif self._paused:
                    self._run_from(now)
            stepping = self._stepping
        if wait and stepping:
            self._wait_stepped(int(target_ns))
        elif wait:
            self.wait_until(target_ns)
        return self.now_ns()

    def _wait_stepped(self, target_ns: int, timeout_s: float = 300.0) -> None:
        deadline = time.monotonic() + timeout_s
        with self._lock:
            while self._stepping and self._completed_ns < target_ns:
                remaining = deadline - time.monotonic()
                if remaining <= 0:
                    return
                self._stepped.wait(remaining)

    def continue_for(self, delta_ns: int, wait: bool, what: str = "ContinueForSimTime") -> int:
        self._require_steppable(what)
        return self.continue_until(self.now_ns() + int(delta_ns), wait, what)

    def wait_until(self, target_ns: int, timeout_s: float = 300.0) -> bool:
        deadline = time.monotonic() + timeout_s
        while self.now_ns() < target_ns:
            if time.monotonic() > deadline:
                return False
            time.sleep(0.0005)
        return True
