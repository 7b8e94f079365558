"""A scene file edited or swapped for a symlink out of the config directory after the node loaded it:
a reconnect reloads the scene as it was validated, and never reads the file again."""

from __future__ import annotations

import shutil
import signal
import time

import pytest
from harness import Rig, RosMaster, wait_until

from reliability.relkit import (
    PROJECT_SIM_CONFIG,
    ROBOT,
    SCENE,
    SIM_ROBOT,
    SimPorts,
    SimView,
    probe,
    stamps,
    start_node,
    start_server,
    statuses,
)


@pytest.mark.parametrize("swap", ["symlink_out", "edited"])
def test_a_reconnect_reloads_the_validated_scene_whatever_became_of_its_file(
    launcher: Rig, ros_master: RosMaster, tmp_path, swap: str
):
    config = tmp_path / "config"
    shutil.copytree(PROJECT_SIM_CONFIG, config)
    ports = SimPorts.free()
    server = start_server(launcher, ports)
    node = start_node(launcher, ports, "--scene", SCENE, node_name="steadfast", sim_config=config)
    status = probe(launcher, "status", "status", "steadfast")
    pose = probe(launcher, "pose", "watch", f"{ROBOT}/actual_pose")
    wait_until(lambda: len(stamps(pose)) > 5, 40, what="actual_pose")
    scene = config / SCENE
    text = scene.read_text()
    if swap == "symlink_out":
        outside = tmp_path / "outside.jsonc"
        outside.write_text(text.replace("SceneDroneSensors", "SceneElsewhere").replace("Drone1", "Intruder"))
        scene.unlink()
        scene.symlink_to(outside)
    else:
        scene.write_text(text.replace('"Drone1"', '"Intruder"').replace("{", "{ broken", 1))
    server.stop(signal.SIGKILL)
    killed = time.time()
    start_server(launcher, ports)
    wait_until(lambda: any(t > killed + 0.3 for t in stamps(pose)), 20, what="actual_pose after the restart")
    wait_until(lambda: statuses(status)[-1]["reconnects"] == 1, 10, what="the reconnect in the status")
    assert statuses(status)[-1]["state"] == "connected"
    view = SimView(ports)
    assert len(view.position(SIM_ROBOT)) == 3  # the validated scene, with its robot, is what runs
    view.close()
    assert "Intruder" not in node.output() and "Elsewhere" not in node.output()
