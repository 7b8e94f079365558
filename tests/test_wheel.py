"""The wheel is the product: built as a user builds it, installed into a fresh venv on Debian's ROS, it
validates the shipped mappings on its sample scenes and runs the node from a temporary directory, radar
included, and its message space lets Debian's own rostopic read the radar."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest
from harness import ROOT, Rig, SimPorts, stock_tool

pytestmark = pytest.mark.live  # builds a wheel, makes a venv, installs into it, runs the stack

RADAR = "/airsim_node/RadarTower1/radar1"


def run(argv: list, cwd: Path, timeout: float = 300) -> subprocess.CompletedProcess:
    env = {k: v for k, v in os.environ.items() if k not in ("PYTHONPATH", "VIRTUAL_ENV")}
    done = subprocess.run(
        [str(a) for a in argv], cwd=cwd, env=env, capture_output=True, text=True, timeout=timeout
    )
    assert done.returncode == 0, f"{argv}: {done.stdout[-3000:]}{done.stderr[-3000:]}"
    return done


@pytest.fixture(scope="module")
def venv(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """A fresh venv on Debian's ROS holding the wheel built from this checkout and its dependencies."""
    work = tmp_path_factory.mktemp("wheel")
    run([sys.executable, "-m", "pip", "wheel", "--no-deps", "-q", "-w", work / "dist", ROOT], cwd=work)
    (wheel,) = (work / "dist").glob("airsim_mapper-*.whl")
    run(["/usr/bin/python3", "-m", "venv", "--system-site-packages", work / "venv"], cwd=work)
    run([work / "venv" / "bin" / "python", "-m", "pip", "install", "-q", wheel], cwd=work, timeout=900)
    return work / "venv"


def test_the_wheel_validates_a_shipped_mapping_on_a_sample_scene_with_radar_from_anywhere(venv, tmp_path):
    checked = run(
        [venv / "bin" / "validate-mapping", "default", "--scene", "scene_drone_sensors.jsonc"], tmp_path
    )
    assert "radar_msgs/RadarScan" in checked.stdout and "radar_msgs/RadarTracks" in checked.stdout
    shipped = run([venv / "bin" / "validate-mapping", "default"], tmp_path).stdout
    assert f"({venv}/lib/" in shipped  # the installed mapping, not the checkout's
    setup = run([venv / "bin" / "airsim-mapper", "ros-setup"], tmp_path).stdout.strip()
    assert Path(setup).is_file() and setup.startswith(str(venv))


def test_the_wheel_runs_the_node_from_a_temporary_directory_with_radar_flowing(venv, tmp_path):
    bin_dir = venv / "bin"
    with Rig(tmp_path / "logs", cwd=tmp_path) as rig:
        try:
            rig.roscore()
            ports = SimPorts.free()
            sim = rig.start("sim", [bin_dir / "airsim-mapper-sim", *ports.args()])
            rig.wait_ports(sim, (ports.topics, ports.services))
            node = rig.start(
                "node", [bin_dir / "airsim-mapper-node", *ports.args(), "--scene", "scene_radar_tower.jsonc"]
            )
            rig.wait_topics([f"{RADAR}/radar_detections", f"{RADAR}/radar_tracks"], node)
            setup = Path(run([bin_dir / "airsim-mapper", "ros-setup"], tmp_path).stdout.strip())
            for topic in ("radar_detections", "radar_tracks"):
                echo = stock_tool(rig, f"/usr/bin/rostopic echo -n 3 {RADAR}/{topic}", setup=setup)
                assert echo.returncode == 0, echo.stdout + echo.stderr
                assert echo.stdout.count('frame_id: "airsim_node/RadarTower1/radar1"') == 3, echo.stdout
            assert rig.stop(node) == 0, node.output()
        except BaseException:
            print(rig.dump_logs())
            raise
