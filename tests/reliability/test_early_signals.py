"""A signal at any moment of the node's start-up, even during its imports, stops it cleanly: exit status 0,
no traceback. A signal in the interpreter's own start-up (`site`, before the script's first line) is out
of any script's reach; it takes 0.05 s on an idle machine and over 0.8 s on a loaded one, so each signal
comes that long, measured just before, plus a delay."""

from __future__ import annotations

import signal
import subprocess
import sys
import time

import pytest
from harness import Rig, RosMaster

from reliability.relkit import SCENE, SimPorts, start_node, wait_output


@pytest.mark.parametrize("sig", [signal.SIGINT, signal.SIGTERM])
def test_a_signal_in_the_first_second_of_start_up_stops_the_node_cleanly(
    launcher: Rig, ros_master: RosMaster, sig: int
):
    ports = SimPorts.free()  # nothing listens there: start-up goes on to wait for the simulator
    outcomes = []
    for delay in (0.05, 0.2, 0.4, 0.7, 1.2):
        started = time.monotonic()
        subprocess.run([sys.executable, "-c", "pass"], check=True)  # the interpreter's own start-up, now
        interpreter = time.monotonic() - started
        # a generous deadline: this is about a clean stop, and a loaded machine slows rospy's start
        node = start_node(
            launcher, ports, "--scene", SCENE, "--shutdown-timeout", "30", node_name="early_signal"
        )
        time.sleep(interpreter + delay)
        node.popen.send_signal(sig)
        try:
            code = node.popen.wait(timeout=40)
        except subprocess.TimeoutExpired:
            code = None
        outcomes.append((round(interpreter + delay, 2), code, "Traceback" in node.output()))
        if code != 0 or "Traceback" in node.output():
            print(f"----- {interpreter:.2f} + {delay} s:\n{node.output()[-1500:]}")
        launcher.stop(node)
    print(f"{signal.Signals(sig).name}: (delay s, exit status, traceback) {outcomes}")
    assert all(code == 0 and not traceback for _, code, traceback in outcomes), outcomes


def test_a_node_started_before_its_master_says_so_stops_at_once_on_a_signal_and_starts_with_the_master(
    launcher: Rig,
):
    """Before its master is up the node has registered nothing: it says what it waits for, one Ctrl-C ends
    it at once with status 0 (not after --shutdown-timeout with status 1), and a master that comes up is
    joined."""
    from tools.rig import free_port, ros_environment

    port = free_port()
    launcher.env = ros_environment(launcher.env, launcher.workdir, port)  # no master there yet
    ports = SimPorts.free()  # nor a simulator: once registered, the node waits for it
    node = start_node(launcher, ports, "--scene", SCENE, "--shutdown-timeout", "30", node_name="early_bird")
    wait_output(node, f"waiting for the ROS master at http://localhost:{port}", 30)
    node.popen.send_signal(signal.SIGINT)
    assert node.popen.wait(timeout=5) == 0, node.output()
    assert "SIGINT before the node registered: exiting" in node.output()
    node = start_node(launcher, ports, "--scene", SCENE, node_name="early_bird")
    wait_output(node, "waiting for the ROS master", 30)
    launcher.start("roscore", ["roscore", "-p", str(port)])
    wait_output(node, "setting scene = 'scene_drone_sensors.jsonc' (command line)", 60)
    wait_output(node, "waiting for it", 30)  # registered, now waiting for the simulator
    assert launcher.stop(node) == 0, node.output()
