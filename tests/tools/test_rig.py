"""The process rig: ports outside the ephemeral range, stopping whole process trees, children that exit."""

from __future__ import annotations

import os
import socket
import subprocess
import sys
import time
from pathlib import Path

import pytest

from tools.rig import Rig, RigError, _ephemeral_start, free_port, port_open, stop_group, wait_until

pytestmark = pytest.mark.live  # starts and stops processes


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
    calls = iter([False, False, True])
    wait_until(lambda: next(calls), 5, "the third call", interval=0.001)

    class CallersError(RuntimeError):
        pass

    with pytest.raises(CallersError, match="timed out after 0 s waiting for nothing"):
        wait_until(lambda: False, 0.05, "nothing", interval=0.01, error=CallersError)


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


def test_a_child_that_exits_is_reported_with_its_log_and_a_waited_port_fails_at_once(tmp_path) -> None:
    with Rig(tmp_path) as rig:
        child = rig.python("quitter", ["-c", "print('no luck here'); raise SystemExit(3)"])
        child.wait(10)
        with pytest.raises(RigError, match=r"quitter exited with 3; .*quitter\.0\.log:\nno luck here"):
            rig.wait_ports(child, [free_port()], timeout=30)


def test_a_rig_stops_every_child_and_keeps_their_logs(tmp_path) -> None:
    port = free_port()
    serve = (
        f"import socket, time; s = socket.socket(); s.bind(('127.0.0.1', {port})); s.listen(); print('up')"
    )
    with Rig(tmp_path) as rig:
        server = rig.python("server", ["-c", serve + "; time.sleep(60)"])
        rig.wait_ports(server, [port], timeout=30)
        sleeper = rig.python("sleeper", ["-c", "import time; time.sleep(60)"])
    assert not server.alive() and not sleeper.alive() and not port_open(port)
    assert "----- server (exit" in rig.dump_logs() and "up" in server.output()
