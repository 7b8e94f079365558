"""Anyone may publish on a ROS graph: malformed commands never reach the simulator, limits hold."""

from __future__ import annotations

import math
import time
from dataclasses import dataclass
from pathlib import Path

import pytest
from harness import ROOT, Child, Rig, RosMaster, wait_until

from reliability.relkit import (
    ROBOT,
    SCENE,
    SimPorts,
    SimView,
    probe,
    start_node,
    start_server,
    statuses,
    wait_output,
)

MAX_SPEED = 1.0


def limited_mapping(tmp_path: Path, on_violation: str = "clamp") -> Path:
    """The default mapping with a speed limit on cmd_vel."""
    text = (ROOT / "mappings" / "default.yaml").read_text()
    shipped = next(line for line in text.splitlines(keepends=True) if "limits: {max_linear_speed" in line)
    assert text.count(shipped) == 1
    limits = f"    limits: {{max_linear_speed: {MAX_SPEED}, on_violation: {on_violation}}}\n"
    path = tmp_path / "limited.yaml"
    path.write_text(text.replace(shipped, limits))
    return path


@dataclass
class Guarded:
    launcher: Rig
    ports: SimPorts
    node: Child
    status: Child


@pytest.fixture(scope="module")
def rig(module_launcher: Rig, module_master: RosMaster, tmp_path_factory) -> Guarded:
    """One server and one node (cmd_vel limited to 1 m/s, clamped) for the module; the robot is armed."""
    ports = SimPorts.free()
    start_server(module_launcher, ports)
    mapping = limited_mapping(tmp_path_factory.mktemp("mapping"))
    node = start_node(module_launcher, ports, "--scene", SCENE, "--mapping", str(mapping), node_name="guard")
    status = probe(module_launcher, "status", "status", "guard")
    wait_until(lambda: statuses(status) and statuses(status)[-1]["scene"] == SCENE, 30, what="the scene")
    assert statuses(status)[-1]["gc_frozen"] > 10_000  # the running scene's heap is out of full collections
    view = SimView(ports)
    view.ready()
    view.close()
    return Guarded(module_launcher, ports, node, status)


def test_malformed_commands_are_rejected_with_one_warning_per_bridge_and_the_robot_stays_put(rig: Guarded):
    launcher, ports, node, status = rig.launcher, rig.ports, rig.node, rig.status
    view = SimView(ports)
    start = view.position()
    sender = probe(launcher, "bad", "bad", ROBOT, "DownCamera")
    wait_output(sender, "SENT", 30)
    wait_until(
        lambda: sum(statuses(status)[-1]["bridge_errors"].values()) == 3 + 6 + 5,
        5,
        what="every malformed message counted",
    )
    errors = statuses(status)[-1]["bridge_errors"]
    assert errors == {
        "cmd_vel[Drone1]": 3,
        "desired_pose[Drone1]": 6,
        "camera_desired_pose[Drone1/DownCamera]": 5,
    }
    assert math.dist(start, view.position()) < 1e-3
    log = node.output()
    for topic, first_reason in (
        ("cmd_vel", "must be finite"),
        ("desired_pose", "must be finite"),
        ("DownCamera/desired_pose", "must be finite"),
    ):
        lines = [line for line in log.splitlines() if f"rejected a message on {ROBOT}/{topic}:" in line]
        assert len(lines) == 1, lines  # rate-limited: the rest are counted, not logged
        assert first_reason in lines[0]
    view.close()


def test_a_velocity_beyond_the_mapping_limit_is_clamped_to_it(rig: Guarded):
    launcher, ports = rig.launcher, rig.ports
    view = SimView(ports)
    driver = probe(launcher, "drive", "twist", f"{ROBOT}/cmd_vel", "25", "5.0")
    wait_until(lambda: view.still(0.1) > 0.02, 20, what="the robot to move")
    t0, p0 = time.monotonic(), view.position()
    time.sleep(1.0)
    t1, p1 = time.monotonic(), view.position()
    speed = math.dist(p0, p1) / (t1 - t0)
    assert 0.7 * MAX_SPEED < speed < 1.1 * MAX_SPEED, speed
    driver.stop()
    view.close()
