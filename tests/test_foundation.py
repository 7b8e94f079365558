"""The foundation: one interpreter sees ROS and the client, radar messages match upstream, a private
master carries real messages, setup is idempotent, and the repo is a catkin package."""

from __future__ import annotations

import json
import re
import shutil
import subprocess
import sys

import pytest
from harness import ROOT, Rig, RosMaster


@pytest.mark.live
def test_one_interpreter_imports_rospy_tf2_client_and_radar_messages():
    code = (
        "import rospy, tf2_ros, projectairsim, radar_msgs.msg, uuid_msgs.msg; print(projectairsim.__file__)"
    )
    run = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120)
    assert run.returncode == 0, run.stderr
    assert ".venv" in run.stdout


def test_generated_radar_messages_carry_upstream_md5sums():
    from radar_msgs.msg import RadarReturn, RadarScan, RadarTrack, RadarTracks
    from uuid_msgs.msg import UniqueID

    assert RadarScan._md5sum == "6dfacef1e665538dbd8e159d5ce7a97a"
    assert RadarTrack._md5sum == "3344659e36aff40bd4f09e82be663ec5"
    assert RadarTracks._md5sum == "d068321616577632690aba69b8985e75"
    assert RadarReturn.__slots__ == ["range", "azimuth", "elevation", "doppler_velocity", "amplitude"]
    assert UniqueID._slot_types == ["uint8[16]"]
    assert RadarTrack.DYNAMIC == 2


def test_image_and_radar_scan_cross_a_private_master(launcher: Rig, ros_master: RosMaster):
    launcher.python("talker", [str(ROOT / "tests/nodes/talker.py")])
    listener = launcher.python("listener", [str(ROOT / "tests/nodes/listener.py")])
    assert listener.wait(timeout=60) == 0, listener.output()
    line = next(row for row in listener.output().splitlines() if row.startswith("RESULT "))
    got = json.loads(line[len("RESULT ") :])
    assert got["image"] == {"shape": [2, 3], "encoding": "bgr8", "data": list(range(18)), "frame": "cam"}
    assert got["radar"]["frame"] == "radar"
    assert got["radar"]["n"] == 1
    assert got["radar"]["range"] == pytest.approx(12.5)
    assert got["radar"]["azimuth"] == pytest.approx(0.25)
    assert got["radar"]["doppler"] == pytest.approx(-3.0)
    assert got["radar"]["amplitude"] == pytest.approx(7.0)


def test_private_master_uses_temporary_ros_home(ros_master: RosMaster, tmp_path):
    assert ros_master.env["ROS_MASTER_URI"].endswith(f":{ros_master.port}")
    assert ros_master.env["ROS_HOSTNAME"] == "localhost"
    assert ros_master.env["ROS_LOG_DIR"].startswith(str(tmp_path))
    assert ros_master.pid() is not None


@pytest.mark.live
def test_setup_second_run_installs_nothing():
    run = subprocess.run(["bash", str(ROOT / "tools/setup.sh")], capture_output=True, text=True, timeout=300)
    assert run.returncode == 0, run.stdout + run.stderr
    assert "installing" not in run.stdout
    assert "generated" not in run.stdout
    assert "all" in run.stdout and "up to date" in run.stdout


@pytest.mark.live
def test_repository_is_a_catkin_package_that_catkin_make_accepts(tmp_path):
    assert shutil.which("catkin_make"), "catkin is not installed: run `make setup`"
    src = tmp_path / "ws" / "src"
    src.mkdir(parents=True)
    (src / "projectairsim_ros").symlink_to(ROOT)
    run = subprocess.run(
        ["catkin_make", "-C", str(src.parent), "-DPYTHON_EXECUTABLE=/usr/bin/python3", "install"],
        cwd=src.parent,
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert run.returncode == 0, run.stdout[-3000:] + run.stderr[-3000:]
    assert "projectairsim_ros" in run.stdout
    installed = src.parent / "install"
    launch_text = "".join(path.read_text() for path in (ROOT / "launch").glob("*.launch"))
    scripts = set(re.findall(r'type="(\w+\.py)"', launch_text)) | set(
        re.findall(r"/scripts/(\w+\.py)", launch_text)
    )
    assert scripts >= {"projectairsim_node.py", "airsim_mapper_sim.py", "hello_ros.py", "wait_for_ports.py"}
    for script in scripts:
        assert (installed / "lib" / "projectairsim_ros" / script).is_file(), script
    share = installed / "share" / "projectairsim_ros"
    for data in (
        "mappings/default.yaml",
        "mappings/enu.yaml",
        "schemas/mapping.schema.json",
        "rviz/airsim_mapper.rviz",
    ):
        assert (share / data).is_file(), data
    assert sorted(p.name for p in (share / "sim_config").iterdir()) == sorted(
        p.name for p in (ROOT / "sim_config").iterdir()
    )
    assert sorted(p.name for p in (share / "launch").iterdir()) == sorted(
        p.name for p in (ROOT / "launch").iterdir()
    )


def test_rospack_finds_the_package_from_the_checkout_parent(launcher: Rig, tmp_path):
    parent = tmp_path / "src"  # a parent holding only this checkout (a real one may hold other clones)
    parent.mkdir()
    (parent / "projectairsim_ros").symlink_to(ROOT)
    run = subprocess.run(
        ["rospack", "find", "projectairsim_ros"],
        capture_output=True,
        text=True,
        env={**launcher.env, "ROS_PACKAGE_PATH": str(parent), "ROS_HOME": str(launcher.workdir)},
        timeout=60,
    )
    assert run.returncode == 0, run.stderr
    assert run.stdout.strip() == str(parent / "projectairsim_ros")
