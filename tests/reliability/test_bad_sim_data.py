"""Bad simulator data: each malformed message is dropped and counted, the streams go on."""

from __future__ import annotations

import time

import msgpack
import pytest
from harness import Rig, RosMaster, wait_until

from reliability.fake_server import FakeSimServer, message_frame
from reliability.relkit import ROBOT, SCENE, SimPorts, probe, stamps, start_node, statuses

SIM = "/Sim/SceneDroneSensors/robots/Drone1"
POSE = f"{SIM}/actual_pose"
RADAR = f"{SIM}/sensors/radar1/radar_detections"


def good_pose(t: int) -> dict:
    return {
        "time_stamp": t,
        "position": {"x": 1.0, "y": 2.0, "z": -3.0},
        "orientation": {"w": 1.0, "x": 0.0, "y": 0.0, "z": 0.0},
    }


def pose_frames() -> list[bytes]:
    """Good poses between every kind of broken frame (whole frame, body, and message content)."""
    good = message_frame(POSE, good_pose(1))
    broken_content = [
        {"time_stamp": 2},  # missing keys
        {**good_pose(3), "position": {"x": "north", "y": 0.0, "z": 0.0}},  # wrong type
        {**good_pose(4), "orientation": {"w": 0.0, "x": 0.0, "y": 0.0, "z": 0.0}},  # zero quaternion
        [1, 2, 3],  # not a map
        {**good_pose(5), "time_stamp": -7},  # impossible stamp
    ]
    broken_frames = [
        good[: len(good) // 2],  # truncated frame
        msgpack.packb([2, POSE, good[5:9]], use_bin_type=False),  # truncated body
        msgpack.packb(42),  # not a frame at all
        msgpack.packb([2, "/Sim/unknown/topic", b"\x80"], use_bin_type=False),  # a topic nobody asked for
    ]
    frames: list[bytes] = []
    for bad in [*(message_frame(POSE, m) for m in broken_content), *broken_frames]:
        frames += [good, bad]
    return frames


def radar_frames() -> list[bytes]:
    """Stamped after every pose above: the lazy radar bridge drops what was taken before it attached."""
    return [
        message_frame(RADAR, {"time_stamp": 1000, "radar_detections": "many"}),  # wrong type
        message_frame(RADAR, {"time_stamp": 1000, "radar_detections": [{"range": 1.0}]}),  # missing fields
        message_frame(RADAR, {"time_stamp": 1000, "radar_detections": []}),  # fine
    ]


@pytest.fixture
def fake(launcher: Rig) -> tuple[FakeSimServer, SimPorts]:
    ports = SimPorts.free()
    sim = FakeSimServer(
        "127.0.0.1",
        ports.topics,
        ports.services,
        "SceneDroneSensors",
        {POSE: pose_frames(), RADAR: radar_frames()},
    )
    yield sim, ports
    sim.close()


def test_malformed_simulator_frames_are_dropped_counted_and_reported_while_the_streams_go_on(
    launcher: Rig, ros_master: RosMaster, fake: tuple[FakeSimServer, SimPorts]
):
    _sim, ports = fake
    node = start_node(launcher, ports, "--scene", SCENE, node_name="sturdy")
    status = probe(launcher, "status", "status", "sturdy")
    watcher = probe(launcher, "pose", "watch", f"{ROBOT}/actual_pose")
    radar = probe(launcher, "radar", "watch", f"{ROBOT}/radar1/radar_detections")  # radar bridges are lazy
    wait_until(lambda: len(stamps(watcher)) > 20, 40, what="good actual_pose messages between the bad ones")
    start, count = time.time(), len(stamps(watcher))
    time.sleep(2.0)
    rate = (len(stamps(watcher)) - count) / (time.time() - start)

    def errors(bridge: str) -> int:
        reports = statuses(status)
        return reports[-1]["bridge_errors"].get(bridge, 0) if reports else 0

    # the radar bridge attaches once its watcher process has subscribed
    wait_until(lambda: errors("radar_detections[Drone1/radar1]") > 0, 20, what="a counted bad radar frame")
    wait_until(lambda: len(stamps(radar)) > 0, 20, what="the good radar message")
    last = statuses(status)[-1]
    assert last["state"] == "connected" and last["sim_losses"] == 0
    assert last["bad_frames"] > 0
    assert last["bridge_errors"]["actual_pose[Drone1]"] > 0
    # Half the pose frames are good, sent at 50 Hz: about 25 good poses a second keep arriving.
    assert rate > 10, rate
    assert len(stamps(radar)) > 0  # the good radar message still gets through
    log = node.output()
    assert "Traceback" not in log
    dropped = [line for line in log.splitlines() if "undecodable frame dropped" in line]
    assert 1 <= len(dropped) <= 3  # rate-limited: once per 5 s, with a count of the rest
    assert node.alive()
