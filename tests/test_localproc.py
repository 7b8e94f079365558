"""Local process helpers: ports outside the ephemeral range, and stopping a whole process group."""

from __future__ import annotations

import os
import socket
import subprocess
import sys
import time
from pathlib import Path

from airsim_mapper.localproc import (
    CpuMark,
    _ephemeral_start,
    command_name,
    cpu_mark,
    cpu_shares,
    free_port,
    stop_group,
)


def test_free_ports_are_bindable_and_below_the_ephemeral_range() -> None:
    ports = {free_port() for _ in range(20)}
    assert all(port < _ephemeral_start() for port in ports)
    for port in ports:
        with socket.socket() as sock:
            sock.bind(("127.0.0.1", port))


def stubborn_parent(child_kwargs: str) -> tuple[subprocess.Popen, int]:
    """A process group leader that ignores SIGINT and has one sleeping child (Popen `child_kwargs`)."""
    code = (
        "import signal, subprocess, sys, time;"
        "signal.signal(signal.SIGINT, signal.SIG_IGN);"
        f"g = subprocess.Popen([sys.executable, '-c', 'import time; time.sleep(60)']{child_kwargs});"
        "print(g.pid, flush=True); time.sleep(60)"
    )
    parent = subprocess.Popen([sys.executable, "-c", code], stdout=subprocess.PIPE, start_new_session=True)
    return parent, int(parent.stdout.readline())


def test_stop_group_ends_a_child_that_ignores_sigint_and_its_own_children() -> None:
    child, grandchild = stubborn_parent("")
    assert grandchild > 0
    stop_group(child, grace_s=0.5)
    assert child.poll() is not None
    deadline = time.monotonic() + 5  # SIGKILL is delivered at once, the exit and reaping follow
    while subprocess.run(["pgrep", "-g", str(child.pid)], capture_output=True).returncode == 0:
        assert time.monotonic() < deadline, "a process of the group outlived stop_group"
        time.sleep(0.05)


def test_wait_until_returns_when_true_and_raises_the_callers_error_otherwise() -> None:
    import pytest

    from airsim_mapper.localproc import wait_until

    calls = iter([False, False, True])
    wait_until(lambda: next(calls), 5, "the third call", interval=0.001)

    class RigError(RuntimeError):
        pass

    with pytest.raises(RigError, match="timed out after 0 s waiting for nothing"):
        wait_until(lambda: False, 0.05, "nothing", interval=0.01, error=RigError)


def test_stop_group_also_ends_a_descendant_in_a_session_of_its_own() -> None:
    """Like a roslaunch node whose roslaunch was killed before it could stop it."""
    child, grandchild = stubborn_parent(", start_new_session=True")
    assert os.getpgid(grandchild) != child.pid
    stop_group(child, grace_s=0.5)
    deadline = time.monotonic() + 5
    while Path(f"/proc/{grandchild}").exists() and "Z" not in _state(grandchild):
        assert time.monotonic() < deadline, "the grandchild outlived stop_group"
        time.sleep(0.05)


def _state(pid: int) -> str:
    try:
        return Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()[0]
    except OSError:
        return "Z"


def fake_proc(tmp_path, pid: int, comm: str, utime: int, stime: int, nice: int, argv: list[str]):
    """A /proc/<pid> with a stat line (fields 3-52 after a command name holding a space and a ')')."""
    entry = tmp_path / str(pid)
    entry.mkdir()
    fields = ["S", "1", *["0"] * 9, str(utime), str(stime), *["0"] * 3, str(nice), *["0"] * 33]
    (entry / "stat").write_text(f"{pid} ({comm}) {' '.join(fields)}\n")
    (entry / "cmdline").write_bytes(b"\0".join(arg.encode() for arg in argv) + b"\0")


def test_cpu_marks_read_user_plus_system_time_and_nice_and_shares_rank_the_busiest(tmp_path):
    ticks = os.sysconf("SC_CLK_TCK")
    fake_proc(tmp_path, 7, "py (x) y", 2 * ticks, ticks, 10, ["/v/bin/python", "-m", "pkg.worker", "3"])
    before = cpu_mark("worker", 7, tmp_path)
    assert before == CpuMark("worker", 3.0, 10)
    assert command_name(7, tmp_path) == "pkg.worker"
    fake_proc(tmp_path, 8, "python3", ticks, 0, 0, ["/usr/bin/python3", "/opt/scripts/hello_ros.py", "--x"])
    assert command_name(8, tmp_path) == "hello_ros.py"
    assert cpu_mark("gone", 99, tmp_path) is None and command_name(99, tmp_path) == "99"
    after = [CpuMark("worker", 4.0, 10), CpuMark("bridge", 3.0, 0), CpuMark("new", 1.0, 0)]
    shares = cpu_shares([before, CpuMark("bridge", 1.0, 0)], after, 4.0)
    assert shares == [("bridge", 50.0, 0), ("worker", 25.0, 10)]  # "new" was not there at the start
