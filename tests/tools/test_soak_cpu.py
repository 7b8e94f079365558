"""The soak's CPU accounting, read from a fake /proc."""

from __future__ import annotations

import os

from tools.soak.cpu import CpuMark, command_name, cpu_mark, cpu_shares


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
