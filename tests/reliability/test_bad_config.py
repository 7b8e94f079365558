"""Hand-edited configs: a bad mapping or start scene stops the node cleanly; a bad load_scene is refused."""

from __future__ import annotations

import json
import os
import shutil
import subprocess
import sys
import time
from pathlib import Path

import pytest
from harness import ROOT, Rig, RosMaster, wait_until

from reliability.relkit import (
    PROJECT_SIM_CONFIG,
    ROBOT,
    SCENE,
    SimPorts,
    probe,
    stamps,
    start_node,
    start_server,
    statuses,
    wait_output,
)
from tools.rig import NODE_SCRIPT

pytestmark = pytest.mark.live  # every test starts the node

BROKEN = ROOT / "tests" / "mapping" / "broken"


def run_node(*args: str) -> subprocess.CompletedProcess:
    """The node up to its config checks (no master needed: they run before rospy.init_node)."""
    argv = [sys.executable, str(NODE_SCRIPT), "--simconfigpath", str(PROJECT_SIM_CONFIG), *args]
    return subprocess.run(argv, capture_output=True, text=True, timeout=60, cwd=ROOT)


def test_an_invalid_mapping_stops_the_node_with_exit_code_1_and_the_validation_errors():
    result = run_node("--mapping", str(BROKEN / "misspelt_converter.yaml"))
    assert result.returncode == 1
    assert "misspelt_converter.yaml" in result.stderr and "converter" in result.stderr
    assert "Traceback" not in result.stderr + result.stdout


def test_a_missing_mapping_file_stops_the_node_with_exit_code_1_and_no_traceback(tmp_path: Path):
    result = run_node("--mapping", str(tmp_path / "nope.yaml"))
    assert result.returncode == 1
    assert "nope.yaml" in result.stderr
    assert "Traceback" not in result.stderr + result.stdout


def test_a_non_utf8_mapping_or_a_directory_stops_the_node_with_exit_code_1_and_a_located_error(
    tmp_path: Path,
):
    result = run_node("--mapping", str(BROKEN / "non_utf8.yaml"))
    assert result.returncode == 1
    assert f"{BROKEN / 'non_utf8.yaml'}:4:6: the mapping file is not UTF-8 text (byte 0xe9)" in result.stderr
    result = run_node("--mapping", str(tmp_path))
    assert result.returncode == 1
    assert f"{tmp_path}: the mapping file is a directory, not a regular file" in result.stderr
    assert "Traceback" not in result.stderr + result.stdout


def test_a_missing_start_scene_stops_the_node_with_exit_code_1_and_no_traceback():
    result = run_node("--scene", "no_such_scene.jsonc")
    assert result.returncode == 1
    assert "no_such_scene.jsonc" in result.stderr
    assert "Traceback" not in result.stderr + result.stdout


@pytest.fixture
def config_dir(tmp_path: Path) -> Path:
    """The project's scenes plus broken ones, and a symlink leading out of the directory."""
    root = tmp_path / "configs"
    shutil.copytree(PROJECT_SIM_CONFIG, root)
    (root / "invalid_json.jsonc").write_text('{"id": "X", "actors": [')
    scene = json.loads(
        "\n".join(
            line for line in (root / SCENE).read_text().splitlines() if not line.lstrip().startswith("//")
        )
    )
    scene["actors"] = "not a list"
    (root / "schema_violation.jsonc").write_text(json.dumps(scene))
    os.mkfifo(root / "fifo.jsonc")  # a FIFO with no writer: opening it for reading would block for good
    os.mkfifo(root / "robot_fifo.jsonc")
    text = (root / SCENE).read_text()
    (root / "fifo_robot.jsonc").write_text(text.replace("robot_quadrotor_sensors.jsonc", "robot_fifo.jsonc"))
    with open(root / "big.jsonc", "wb") as big:  # sparse: 17 MiB of size, no disk
        big.truncate(17 * 1024 * 1024)
    outside = tmp_path / "outside.jsonc"
    shutil.copy(root / SCENE, outside)
    (root / "escape.jsonc").symlink_to(outside)
    return root


def test_bad_scenes_on_load_scene_are_refused_and_the_current_scene_keeps_running(
    launcher: Rig, ros_master: RosMaster, config_dir: Path
):
    ports = SimPorts.free()
    start_server(launcher, ports)
    node = start_node(launcher, ports, "--scene", SCENE, node_name="picky", sim_config=config_dir)
    watcher = probe(launcher, "pose", "watch", f"{ROBOT}/actual_pose")
    status = probe(launcher, "status", "status", "picky")
    wait_until(lambda: len(stamps(watcher)) > 5, 30, what="actual_pose")
    bad = {
        "missing.jsonc": "No such file",
        "invalid_json.jsonc": "invalid JSON",
        "schema_violation.jsonc": "schema",
        str(config_dir / SCENE): "must be relative",
        "escape.jsonc": "symlink",
        "../configs/" + SCENE: "'..'",
        "fifo.jsonc": "the scene file is a FIFO (named pipe), not a regular file",
        "fifo_robot.jsonc": "robot config of actor 'Drone1' is a FIFO (named pipe), not a regular file",
        "big.jsonc": "is 17825792 bytes or more, over the limit of 16777216 bytes",
    }
    sender = probe(launcher, "load", "strings", "/ProjectAirSim/node/picky/load_scene", *bad)
    wait_output(sender, "SENT", 30)
    for name, why in bad.items():
        wait_output(node, f"load_scene {name!r} refused", 10)
        refusal = node.output().split(f"load_scene {name!r} refused", 1)[1].split("[ERROR]")[0]
        assert why in refusal, refusal
    count = len(stamps(watcher))
    wait_until(lambda: len(stamps(watcher)) > count + 20, 10, what="actual_pose after the refusals")
    assert statuses(status)[-1]["scene"] == SCENE and statuses(status)[-1]["state"] == "connected"
    assert node.alive() and "Traceback" not in node.output()


def settled_output_length(node, quiet_s: float = 1.0, timeout_s: float = 15.0) -> int:
    """The length of a process's output once nothing was added to it for `quiet_s`."""
    length, since, deadline = len(node.output()), time.monotonic(), time.monotonic() + timeout_s
    while time.monotonic() < deadline:
        time.sleep(0.1)
        now = len(node.output())
        if now != length:
            length, since = now, time.monotonic()
        elif time.monotonic() - since >= quiet_s:
            break
    return length


def test_a_flood_of_huge_load_scene_names_is_refused_in_a_few_short_log_lines(
    launcher: Rig, ros_master: RosMaster
):
    ports = SimPorts.free()
    start_server(launcher, ports)
    node = start_node(launcher, ports, "--scene", SCENE, node_name="terse")
    watcher = probe(launcher, "pose", "watch", f"{ROBOT}/actual_pose")
    status = probe(launcher, "status", "status", "terse")
    wait_until(lambda: len(stamps(watcher)) > 5, 30, what="actual_pose")
    before = settled_output_length(node)  # the start-up's bridges table is not part of the flood's lines
    rss_before = _rss_mb(node.popen.pid)
    count, size = 40, 1_000_000
    sender = probe(launcher, "huge", "huge", "/ProjectAirSim/node/terse/load_scene", str(count), str(size))
    wait_output(sender, "SENT", 60)
    wait_until(
        lambda: statuses(status)[-1]["bridge_errors"].get("load_scene[terse]", 0) == count,
        20,
        what="every huge name counted as refused",
    )
    logged = node.output()[before:]
    assert len(logged) < 20_000, len(logged)  # was two copies of every name: 80 MB
    assert "characters long; at most 4096" in logged
    assert _rss_mb(node.popen.pid) - rss_before < 100
    assert statuses(status)[-1]["scene"] == SCENE and node.alive()


def _rss_mb(pid: int) -> float:
    for line in Path(f"/proc/{pid}/status").read_text().splitlines():
        if line.startswith("VmRSS:"):
            return int(line.split()[1]) / 1024
    return 0.0
