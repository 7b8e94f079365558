"""One receive path: a mission script's client runs the bridge's receive loop whatever the order in which
the script made `World` and the bridge, and a malformed frame stops neither the mission nor the bridge."""

from __future__ import annotations

import json
from pathlib import Path

import pytest
from harness import Rig, RosMaster

from reliability.fake_server import FakeSimServer
from reliability.relkit import PROJECT_SIM_CONFIG, ROBOT, SCENE, SimPorts
from reliability.test_bad_sim_data import POSE, good_pose, pose_frames

MISSION = Path(__file__).resolve().parent / "mission_receive.py"
RUN_S = 6.0


@pytest.mark.parametrize("order", ["world-first", "bridge-first"])
def test_the_bridge_receive_loop_runs_and_survives_a_malformed_frame(
    launcher: Rig, ros_master: RosMaster, order: str
):
    ports = SimPorts.free()
    sim = FakeSimServer("127.0.0.1", ports.topics, ports.services, "SceneDroneSensors", {POSE: pose_frames()})
    try:
        args = [order, str(ports.topics), str(ports.services), str(PROJECT_SIM_CONFIG), SCENE, POSE]
        mission = launcher.python(
            f"mission_{order}", [str(MISSION), *args, f"{ROBOT}/actual_pose", str(RUN_S)]
        )
        assert mission.wait(RUN_S + 60) == 0, mission.output()
    finally:
        sim.close()
    line = next(x for x in mission.output().splitlines() if x.startswith("RESULT "))
    result = json.loads(line.removeprefix("RESULT "))
    stack = result["receive_stack"]
    assert "airsim_mapper.engine.receive.receive" in stack, stack
    if order == "world-first":  # the client's own thread, now running the bridge's loop
        assert "projectairsim.client.__recv_topic" in stack and result["receive_thread"] != "sim-receive"
    else:
        assert result["receive_thread"] == "sim-receive"
    # The fake sends truncated and otherwise broken frames between good poses: the client's own loop
    # would have stopped at the first truncated one.
    assert result["bad_frames"] > 3, result
    assert result["mission_last_second"] > 10, result
    assert result["published_last_second"] > 10, result
    # The mission's callback gets what the bare client would give it: msgpack's own decoding.
    assert good_pose(1) in result["mission_messages_seen"], result["mission_messages_seen"][:3]
    assert "Traceback" not in mission.output()
