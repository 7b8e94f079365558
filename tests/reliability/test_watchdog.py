"""The cmd_vel watchdog stops the robot on time, and the robot stops when the node goes away."""

from __future__ import annotations

import signal
import statistics
import time
from pathlib import Path

from harness import ROOT, Rig, RosMaster, wait_until

from reliability.relkit import (
    ROBOT,
    SCENE,
    SIM_ROBOT,
    SimPorts,
    SimView,
    probe,
    start_node,
    start_server,
    statuses,
)

SHORT_WATCHDOG_S = 0.3
SHORT_TRIALS = 18
DEFAULT_TRIALS = 2


def short_watchdog_mapping(tmp_path: Path) -> Path:
    """cmd_vel with a 0.3 s watchdog and a 30 s command duration: only the watchdog can stop the robot."""
    text = (ROOT / "mappings" / "default.yaml").read_text()
    replacements = {
        "    watchdog_s: 3.0\n": f"    watchdog_s: {SHORT_WATCHDOG_S}\n",
        "    params: {frame: body}": "    params: {frame: body, duration: 30.0}",
    }
    for old, new in replacements.items():
        assert text.count(old) == 1
        text = text.replace(old, new)
    path = tmp_path / "short_watchdog.yaml"
    path.write_text(text)
    return path


def run_trials(launcher: Rig, ports: SimPorts, node_name: str, count: int, *node_args: str) -> list[float]:
    node = start_node(launcher, ports, "--scene", SCENE, *node_args, node_name=node_name)
    status = probe(launcher, f"status_{node_name}", "status", node_name)
    wait_until(lambda: statuses(status) and statuses(status)[-1]["scene"] == SCENE, 30, what="the scene")
    view = SimView(ports)
    view.ready()
    view.close()
    args = (f"{ROBOT}/cmd_vel", str(count), "1.0", str(ports.services), SIM_ROBOT)
    trials = probe(launcher, f"trials_{node_name}", "trials", *args)
    return _collect(trials, node, count)


def _collect(trials, node, count: int) -> list[float]:
    def lines() -> list[float]:
        return [float(x.split()[1]) for x in trials.output().splitlines() if x.startswith("TRIAL ")]

    wait_until(lambda: len(lines()) >= count or not trials.alive(), 120, what=f"{count} watchdog trials")
    assert len(lines()) == count, trials.output()
    node.stop()
    return lines()


def test_the_watchdog_stops_the_robot_just_after_its_timeout_in_20_trials(
    launcher: Rig, ros_master: RosMaster, tmp_path: Path
):
    ports = SimPorts.free()
    start_server(launcher, ports)
    mapping = short_watchdog_mapping(tmp_path)
    short = run_trials(launcher, ports, "wd_short", SHORT_TRIALS, "--mapping", str(mapping))
    default = run_trials(launcher, ports, "wd_default", DEFAULT_TRIALS)
    errors = [t - SHORT_WATCHDOG_S for t in short] + [t - 3.0 for t in default]
    print(
        f"watchdog error over {len(errors)} trials: min {min(errors) * 1000:.0f} ms, "
        f"median {statistics.median(errors) * 1000:.0f} ms, max {max(errors) * 1000:.0f} ms; "
        f"all: {[round(e * 1000) for e in errors]}"
    )
    assert len(errors) == 20
    assert min(errors) > -0.05  # never before the timeout
    assert max(errors) < 0.25
    assert statistics.median(errors) < 0.12


def test_the_robot_stops_when_the_node_is_interrupted_while_driving_it(launcher: Rig, ros_master: RosMaster):
    ports = SimPorts.free()
    start_server(launcher, ports)
    node = start_node(launcher, ports, "--scene", SCENE, node_name="interrupted")
    status = probe(launcher, "status", "status", "interrupted")
    wait_until(lambda: statuses(status) and statuses(status)[-1]["scene"] == SCENE, 30, what="the scene")
    view = SimView(ports)
    view.ready()
    driver = probe(launcher, "drive", "twist", f"{ROBOT}/cmd_vel", "100", "2.0")
    wait_until(lambda: view.still(0.1) > 0.1, 20, what="the robot to move")
    node.popen.send_signal(signal.SIGINT)
    interrupted = time.monotonic()
    wait_until(lambda: view.still(0.05) < 1e-4, 5.0, interval=0.0, what="the robot to stop")
    # The command's own duration is the 3 s watchdog: stopping well before means the node stopped it.
    print(f"stopped {time.monotonic() - interrupted:.2f} s after SIGINT")
    assert time.monotonic() - interrupted < 2.0
    assert node.wait(15) == 0
    assert "bridge stopping: sending Hover" in node.output()
    driver.stop()
    view.close()
