"""Host tuning for a saturated machine: the kernel's softirq threads ahead of busy user threads.

On Linux every loopback TCP segment (TCPROS between ROS nodes, nng between the simulator and its client)
is delivered in softirq context. Under load the kernel hands pending softirq work to the per-CPU
`ksoftirqd/N` threads, which run at nice 0 and queue behind every busy thread on their CPU: messages that
every process sent on time then wait in the kernel, in bursts. Running those threads at nice -10 lets
that work through first. SCHED_FIFO does as well, but a real-time ksoftirqd also preempts every process
for the softirq work of the image streams; nice -10 is the milder of the two.

Kernel threads are outside every autogroup, so their nice value counts against every process. That is
why renicing them helped, while the larger cause of long gaps was autogroup scheduling itself (the
render worker's nice value counted only within the server's session; see `simserver/render/render_worker.py`).

This changes a machine setting, so only `make soak` applies it, by default and for the length of the run,
and only as root. docs/host-tuning.md gives the one-line equivalent (`renice`) for running a simulation
on a small machine, and docs/reliability.md the measurements.
"""

from __future__ import annotations

import os
from dataclasses import dataclass
from pathlib import Path

from tools.rig import stat_fields

SOFTIRQ_NICE = -10


class HostTuningError(RuntimeError):
    """The host's softirq threads could not be found or re-prioritised."""


@dataclass(frozen=True)
class KernelThread:
    pid: int
    name: str
    nice: int
    policy: int = os.SCHED_OTHER
    rt_priority: int = 0

    def describe(self) -> str:
        if self.policy == os.SCHED_FIFO:
            return f"{self.name} (SCHED_FIFO {self.rt_priority})"
        return f"{self.name} (nice {self.nice})"


def softirq_threads(proc: Path = Path("/proc")) -> list[KernelThread]:
    """The `ksoftirqd/N` threads with their current nice value and scheduling policy, by pid."""
    found = []
    for entry in proc.iterdir():
        if not entry.name.isdigit():
            continue
        try:
            name = (entry / "comm").read_text().strip()
            if not name.startswith("ksoftirqd/"):
                continue
            stat = (entry / "stat").read_text()
        except OSError:  # the process ended while we looked
            continue
        fields = stat_fields(stat)  # from field 3 on: nice is field 19, rt_priority 40, policy 41
        nice, rt_priority, policy = int(fields[16]), int(fields[37]), int(fields[38])
        found.append(KernelThread(int(entry.name), name, nice, policy, rt_priority))
    return sorted(found, key=lambda t: t.pid)


def set_nice(threads: list[KernelThread], nice: int) -> None:
    """Normal scheduling at `nice` for each thread."""
    for thread in threads:
        try:
            os.sched_setscheduler(thread.pid, os.SCHED_OTHER, os.sched_param(0))
            os.setpriority(os.PRIO_PROCESS, thread.pid, nice)
        except PermissionError as exc:
            raise HostTuningError(f"cannot renice {thread.name}: {exc.strerror} (needs root)") from exc
        except ProcessLookupError:
            continue


def raise_softirq_priority(nice: int = SOFTIRQ_NICE, proc: Path = Path("/proc")) -> list[KernelThread]:
    """Run every ksoftirqd thread at `nice`; returns their previous state for `restore`."""
    try:
        before = softirq_threads(proc)
    except OSError as exc:
        raise HostTuningError(f"cannot read {proc}: {exc}") from exc
    if not before:
        raise HostTuningError(f"no ksoftirqd threads in {proc}")
    try:
        set_nice(before, nice)
    except HostTuningError:
        restore(before)
        raise
    return before


def restore(previous: list[KernelThread]) -> None:
    """Put each thread back to the policy and priority it had; never raises."""
    for thread in previous:
        try:
            os.sched_setscheduler(thread.pid, thread.policy, os.sched_param(thread.rt_priority))
            if thread.policy not in (os.SCHED_FIFO, os.SCHED_RR):
                os.setpriority(os.PRIO_PROCESS, thread.pid, thread.nice)
        except OSError:
            continue
