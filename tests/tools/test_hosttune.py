"""Host tuning for the soak: finding the ksoftirqd threads, renicing them, and always putting them back."""

from __future__ import annotations

import os

import pytest

from tools.soak import hosttune
from tools.soak.hosttune import HostTuningError, KernelThread


def fake_proc(tmp_path, processes: dict[int, tuple]):
    """A /proc with `pid: (comm, nice[, policy, rt_priority])` entries, stat laid out as the kernel's."""
    proc = tmp_path / "proc"
    proc.mkdir()
    (proc / "self").mkdir()  # not a pid: ignored
    (proc / "meminfo").write_text("MemTotal: 1 kB\n")
    for pid, (comm, nice, *sched) in processes.items():
        policy, rt_priority = sched or (0, 0)
        entry = proc / str(pid)
        entry.mkdir()
        (entry / "comm").write_text(comm + "\n")
        fields = ["S", "2"] + ["0"] * 13 + ["20", str(nice), "1"] + ["0"] * 21  # fields 3-41
        fields[37], fields[38] = str(rt_priority), str(policy)
        (entry / "stat").write_text(f"{pid} ({comm}) {' '.join(fields)}\n")
    return proc


def test_softirq_threads_are_found_with_their_nice_values(tmp_path):
    proc = fake_proc(
        tmp_path,
        {22: ("ksoftirqd/1", 0, 1, 5), 14: ("ksoftirqd/0", -5), 7: ("rcu_preempt", 0), 300: ("odd) (", 3)},
    )
    threads = hosttune.softirq_threads(proc)
    assert threads == [
        KernelThread(14, "ksoftirqd/0", -5, os.SCHED_OTHER, 0),
        KernelThread(22, "ksoftirqd/1", 0, os.SCHED_FIFO, 5),
    ]
    assert [t.describe() for t in threads] == ["ksoftirqd/0 (nice -5)", "ksoftirqd/1 (SCHED_FIFO 5)"]


def test_a_host_without_ksoftirqd_is_a_clear_error(tmp_path):
    proc = fake_proc(tmp_path, {1: ("init", 0)})
    with pytest.raises(HostTuningError, match="no ksoftirqd threads in"):
        hosttune.raise_softirq_priority(proc=proc)


def test_a_refused_renice_restores_what_was_changed_and_says_why(tmp_path, monkeypatch):
    proc = fake_proc(tmp_path, {14: ("ksoftirqd/0", 0), 22: ("ksoftirqd/1", 0, os.SCHED_FIFO, 4)})
    calls: list[tuple] = []

    def setpriority(_which, pid, nice):
        calls.append((pid, "nice", nice))
        if pid == 22 and nice == -10:
            raise PermissionError(1, "Operation not permitted")

    def sched_setscheduler(pid, policy, param):
        calls.append((pid, policy, param.sched_priority))

    monkeypatch.setattr(os, "setpriority", setpriority)
    monkeypatch.setattr(os, "sched_setscheduler", sched_setscheduler)
    with pytest.raises(
        HostTuningError, match=r"cannot renice ksoftirqd/1: Operation not permitted \(needs root\)"
    ):
        hosttune.raise_softirq_priority(-10, proc=proc)
    other, fifo = os.SCHED_OTHER, os.SCHED_FIFO
    assert calls == [
        (14, other, 0), (14, "nice", -10), (22, other, 0), (22, "nice", -10),  # the change, refused at 22
        (14, other, 0), (14, "nice", 0), (22, fifo, 4),  # everything back as it was
    ]  # fmt: skip


def test_the_real_threads_are_reniced_and_restored():
    before = hosttune.softirq_threads()
    assert before and all(t.name.startswith("ksoftirqd/") for t in before)
    if os.geteuid() != 0:
        with pytest.raises(HostTuningError, match="needs root"):
            hosttune.raise_softirq_priority()
        assert hosttune.softirq_threads() == before
        return
    previous = hosttune.raise_softirq_priority(-7)
    try:
        assert previous == before
        assert {(t.policy, t.nice) for t in hosttune.softirq_threads()} == {(os.SCHED_OTHER, -7)}
    finally:
        hosttune.restore(previous)
    assert hosttune.softirq_threads() == before


def test_the_soak_leaves_the_host_alone_when_asked(monkeypatch, capsys):
    from tools.soak.soak import tune_host

    monkeypatch.setenv("SOAK_HOST_TUNING", "0")
    assert tune_host() == []
    assert "host: left as is (SOAK_HOST_TUNING=0)" in capsys.readouterr().out
