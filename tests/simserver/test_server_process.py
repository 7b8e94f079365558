"""The server as a process: signals, options, a hello-drone mission, and bad requests that it survives."""

from __future__ import annotations

import json
import signal
import socket
from pathlib import Path

import msgpack
import pynng
import pytest
from harness import EXAMPLE_CONFIG, SIM_CONFIG, wait_until
from projectairsim import Drone
from simconfigs import both_configs

from simserver.clientkit import load_world, scene_config

HELLO = Path(__file__).parent / "scripts" / "hello_drone.py"


@pytest.mark.parametrize("sig", [signal.SIGINT, signal.SIGTERM])
def test_the_server_exits_0_with_its_threads_stopped_on_sigint_and_sigterm(launcher, sig):
    server = launcher.simserver()
    client = server.client()
    load_world(client, "scene_basic_drone.jsonc")
    client.disconnect()
    assert server.process.stop(sig, timeout=10.0) == 0
    assert "stopped" in server.process.output()


# scene_drone_sensors.jsonc's DownCamera: 320x240 in the project's robot config, 400x225 in the example's
DOWN_CAMERA_SHAPE = {SIM_CONFIG: (240, 320), EXAMPLE_CONFIG: (225, 400)}


@pytest.mark.parametrize("sim_config", both_configs(), indirect=True)
def test_a_hello_drone_script_using_only_the_client_api_flies_and_reads_sensors(launcher, sim_config):
    server = launcher.simserver()
    args = [str(HELLO), server.address, str(server.topics_port), str(server.services_port), str(sim_config)]
    script = launcher.python("hello_drone", args)
    assert script.wait(timeout=90) == 0, script.output()
    out = script.output()
    height, width = DOWN_CAMERA_SHAPE[sim_config]
    for line in (
        "takeoff True",
        "move True",
        f"image ({height}, {width}, 3) depth ({height}, {width})",
        "subscribed image True",
        "land True",
        "landed state 0",
    ):
        assert line in out


def test_a_world_file_option_replaces_the_built_in_world(launcher, tmp_path):
    world_file = tmp_path / "world.json"
    world_file.write_text(
        json.dumps(
            {
                "objects": [
                    {
                        "name": "Wall",
                        "shape": "box",
                        "center": [5.0, 0.0, -4.0],
                        "size": [1.0, 10.0, 10.0],
                        "segmentation-id": 42,
                        "color-bgr": [1, 2, 3],
                    }
                ]
            }
        )
    )
    server = launcher.simserver("--world", str(world_file), "--pose-rate", "50")
    client = server.client()
    try:
        world = load_world(client, "scene_basic_drone.jsonc")
        drone = Drone(client, world, "Drone1")
        scene = drone.get_images("DownCamera", [0])
        assert 0 in scene
        assert (
            client.request(
                {
                    "method": f"{drone.sensors_topic}/DownCamera/LookAtObject",
                    "params": {"object_name": "Wall", "wait_for_pose_update": True},
                }
            )
            is True
        )
    finally:
        client.disconnect()


def test_a_bad_world_file_stops_the_server_at_start_with_a_message(launcher, tmp_path):
    world_file = tmp_path / "bad.json"
    world_file.write_text("{not json")
    proc = launcher.python("simserver", ["-m", "airsim_mapper.simserver", "--world", str(world_file)])
    assert proc.wait(timeout=30) == 1
    assert f"cannot start: world file {world_file}" in proc.output()


def test_bad_requests_get_error_replies_and_the_server_keeps_serving(launcher):
    server = launcher.simserver()
    client = server.client()
    try:
        world = load_world(client, "scene_basic_drone.jsonc")
        unknown = r"ERROR code: 1\.0, message: Requested ServiceMethod /Sim/Nope is not supported by Request"
        with pytest.raises(RuntimeError, match=unknown):
            client.request({"method": "/Sim/Nope", "params": {}, "version": 1.0})
        missing = r"ERROR code: 3\.0, message: Required parameter 'do_pause' not provided when calling:/Sim/"
        with pytest.raises(RuntimeError, match=missing):
            client.request({"method": f"{world.parent_topic}/Pause", "params": {}, "version": 1.0})
        with pytest.raises(RuntimeError, match=r"ERROR code: 2\.0, message: pose has no 'frame_id'"):
            client.request(
                {
                    "method": f"{world.parent_topic}/robots/Drone1/SetPose",
                    "params": {"pose": {"translation": {}}, "reset_kinematics": True},
                    "version": 1.0,
                }
            )
        with pynng.Req0(dial=f"tcp://{server.address}:{server.services_port}", recv_timeout=5000) as raw:
            raw.send(b"\x00\xffgarbage")
            outer = msgpack.unpackb(raw.recv(), raw=False)
        error = msgpack.unpackb(outer["error"]["data"], raw=False)
        assert error["code"] == 2.0 and error["message"].startswith("Got bad request message:")
        with socket.create_connection((server.address, server.services_port), timeout=2) as sock:
            sock.sendall(b"not an nng handshake at all")
        assert world.list_actors() == ["Drone1"]
    finally:
        client.disconnect()


def test_an_invalid_scene_gets_an_error_and_the_previous_scene_keeps_running(launcher):
    server = launcher.simserver()
    client = server.client()
    try:
        world = load_world(client, "scene_basic_drone.jsonc")
        broken = scene_config("scene_basic_drone.jsonc")
        broken["id"] = "Broken"
        broken["actors"][0]["origin"] = {"xyz": "1 2"}
        with pytest.raises(
            RuntimeError, match=r"ERROR code: 1\.0, message: Invalid scene config: robot 'Drone1'"
        ):
            client.request({"method": "/Sim/LoadScene", "params": {"scene_config": json.dumps(broken)}})
        with pytest.raises(RuntimeError, match="Invalid scene config: scene_config is not valid JSON"):
            client.request({"method": "/Sim/LoadScene", "params": {"scene_config": "{"}})
        with pytest.raises(RuntimeError, match="scene_config must be a JSON string, got int"):
            client.request({"method": "/Sim/LoadScene", "params": {"scene_config": 5}})
        assert world.list_actors() == ["Drone1"]
        assert Drone(client, world, "Drone1").get_ground_truth_pose()["translation"]["z"] == -4.0
        with pytest.raises(
            RuntimeError, match="Requested ServiceMethod /Sim/Broken/ListActors is not supported"
        ):
            client.request({"method": "/Sim/Broken/ListActors", "params": {}})
    finally:
        client.disconnect()


def test_a_client_that_goes_away_loses_its_subscriptions(launcher):
    server = launcher.simserver()
    first = server.client()
    world = load_world(first, "scene_basic_drone.jsonc")
    first.subscribe(Drone(first, world, "Drone1").robot_info["actual_pose"], lambda *_: None)
    first.state = False  # stop the receive thread, then drop the sockets without unsubscribing
    first.recv_topic_thread.join()
    first.socket_topics.close()
    first.socket_services.close()
    second = server.client()
    try:
        assert second.request({"method": "/Sim/SceneBasicDrone/ListActors", "params": {}}) == ["Drone1"]
    finally:
        second.disconnect()
    # the pose topic and /$topics were subscribed when the first client vanished
    wait_until(
        lambda: "topics client disconnected; cleared 2 subscriptions" in server.process.output(),
        5.0,
        what="the server to clear the vanished client's subscriptions",
    )


def listening_addresses(port: int) -> set[str]:
    """The local IPv4 addresses with a socket listening on `port` (from /proc/net/tcp)."""
    found = set()
    for line in Path("/proc/net/tcp").read_text().splitlines()[1:]:
        local, state = line.split()[1], line.split()[3]
        address, hex_port = local.split(":")
        if state == "0A" and int(hex_port, 16) == port:
            found.add(socket.inet_ntoa(bytes.fromhex(address)[::-1]))
    return found


def test_the_server_listens_on_loopback_unless_told_otherwise_and_then_warns(launcher):
    from harness import free_port

    ports = [free_port(), free_port()]
    argv = ["-m", "airsim_mapper.simserver", "--topicsport", str(ports[0]), "--servicesport", str(ports[1])]
    local = launcher.python("simserver_default", argv)
    wait_until(lambda: "ready" in local.output(), 30, what="the server with the default address")
    assert listening_addresses(ports[0]) == {"127.0.0.1"} == listening_addresses(ports[1])
    assert "WARNING" not in local.output()
    local.stop()
    ports = [free_port(), free_port()]
    argv = ["-m", "airsim_mapper.simserver", "--address", "0.0.0.0"]
    argv += ["--topicsport", str(ports[0]), "--servicesport", str(ports[1])]
    exposed = launcher.python("simserver_exposed", argv)
    wait_until(lambda: "ready" in exposed.output(), 30, what="the server on 0.0.0.0")
    assert listening_addresses(ports[0]) == {"0.0.0.0"}
    assert "listening on 0.0.0.0" in exposed.output() and "no authentication" in exposed.output()


def test_the_launch_files_start_the_server_on_the_bridge_address_loopback_by_default():
    from xml.etree import ElementTree

    root = Path(__file__).resolve().parents[2] / "launch"
    for name in ("demo.launch", "rviz.launch"):
        launch = ElementTree.parse(root / name).getroot()
        args = {arg.get("name"): arg.get("default") for arg in launch.findall("arg")}
        sims = [node for node in launch.iter("node") if node.get("type") == "airsim_mapper_sim.py"]
        assert args["address"] == "127.0.0.1", name
        assert sims and all("--address $(arg address)" in node.get("args") for node in sims), name


@pytest.mark.parametrize("switch", ["--topicsport", "--servicesport"])
def test_a_port_out_of_range_is_a_usage_error(switch, capsys):
    from airsim_mapper.simserver.cli import parse_args

    with pytest.raises(SystemExit) as exited:
        parse_args([switch, "65536"])
    assert exited.value.code == 2
    assert f"argument {switch}: invalid port value: '65536'" in capsys.readouterr().err
