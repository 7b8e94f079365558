"""The engine on fake links: scene loads, a simulator reconnect and a stalled simulator, in-process in
seconds (no simulator, no ROS master)."""

from __future__ import annotations

import logging
import threading

import pytest
from fakes import IMU_MESSAGE, EngineRig
from harness import SIM_CONFIG, wait_until

from airsim_mapper.engine.status import CONNECTED, STALE, STOPPED
from airsim_mapper.mapping.loader import load_mapping

SCENE = "scene_drone_sensors.jsonc"
IMU_ROS = "/airsim_node/Drone1/IMU1/imu"
IMU_SIM = "/Sim/SceneDroneSensors/robots/Drone1/sensors/IMU1/imu_kinematics"


@pytest.fixture
def rig():
    made = EngineRig()
    yield made
    made.engine.shutdown(timeout=2.0)


def test_a_scene_load_builds_its_bridges_and_a_second_replaces_them(rig: EngineRig):
    scene = rig.engine.load_scene(SCENE)
    assert scene.name == "SceneDroneSensors" and rig.worlds == [SCENE]
    names = set(rig.engine.bridges)
    assert "imu[Drone1/IMU1]" in names and IMU_ROS in rig.ros.publishers
    imu_publisher = rig.ros.publishers[IMU_ROS]
    basic = rig.engine.load_scene("scene_basic_drone.jsonc")
    assert rig.worlds == [SCENE, "scene_basic_drone.jsonc"] and rig.engine.scene is basic
    assert set(rig.engine.bridges) == {spec.name for spec in rig.engine.specs_for(basic)}
    assert imu_publisher.unregistered  # the old scene's bridges are gone, whatever the new one has


def test_a_refused_scene_keeps_the_current_one(rig: EngineRig):
    rig.engine.load_scene(SCENE)
    before = dict(rig.engine.bridges)
    with pytest.raises(Exception, match="no_such_scene"):
        rig.engine.load_scene("no_such_scene.jsonc")
    assert rig.engine.bridges == before and rig.worlds == [SCENE]


def test_a_dropped_connection_reconnects_reloads_and_moves_the_streams_over(rig: EngineRig):
    rig.engine.load_scene(SCENE)
    rig.ros.publishers[IMU_ROS].subscribers(1)
    first = rig.links[0]
    assert IMU_SIM in first.subscriptions
    first.dropped = True
    wait_until(lambda: rig.engine.counters["reconnects"] == 1, 10, what="the reconnect")
    assert first.closed and len(rig.links) == 2 and rig.worlds == [SCENE, SCENE]
    second = rig.links[1]
    assert IMU_SIM in second.subscriptions  # the lazy stream, moved to the new link
    assert second.deliver(IMU_SIM, IMU_MESSAGE) == 1
    wait_until(lambda: rig.ros.publishers[IMU_ROS].messages, 5, what="an IMU message after the reconnect")
    wait_until(lambda: rig.statuses()[-1]["state"] == CONNECTED, 5, what="the connected status")
    assert rig.engine.counters["sim_losses"] == 1


def test_a_silent_simulator_is_stale_then_answers_again_without_a_reload(rig: EngineRig):
    rig.engine.load_scene(SCENE)
    rig.links[0].answering = False
    wait_until(lambda: rig.engine.state == STALE, 10, what="the stall")
    assert rig.engine.reason.startswith("unresponsive")
    rig.links[0].answering = True
    wait_until(lambda: rig.engine.state == CONNECTED, 10, what="the simulator answering again")
    assert len(rig.links) == 1 and rig.worlds == [SCENE] and rig.engine.counters["reconnects"] == 0


def test_topic_frames_end_a_stall_as_an_answer_does_and_the_reason_names_the_probes_still_unanswered(
    rig: EngineRig,
):
    rig.engine.load_scene(SCENE)
    rig.ros.publishers[IMU_ROS].subscribers(1)
    link = rig.links[0]
    link.answering = False
    # the stall's status, not only its state: the status goes out just after the state changes, and the
    # connected status before the stall would otherwise pass the wait for the connected one below
    wait_until(lambda: [s["state"] for s in rig.statuses()][-1:] == [STALE], 10, what="the stall's status")
    flowing = threading.Event()

    def simulator_sending() -> None:  # the topics connection is back, the probes' one not yet
        while not flowing.wait(0.05):
            link.deliver(IMU_SIM, IMU_MESSAGE)

    sender = threading.Thread(target=simulator_sending)
    sender.start()
    try:
        wait_until(lambda: rig.statuses()[-1]["state"] == CONNECTED, 10, what="connected at the frames")
        assert "but topic frames arrive" in rig.statuses()[-1]["reason"]
        link.answering = True
        wait_until(lambda: rig.engine.reason == "", 10, what="the reason cleared by an answer")
    finally:
        flowing.set()
        sender.join()
    assert rig.engine.state == CONNECTED and rig.engine.counters["stalls"] == 1
    assert len(rig.links) == 1 and rig.engine.counters["reconnects"] == 0
    link.answering = False  # and with the frames stopped too, it is a stall again
    wait_until(lambda: rig.engine.state == STALE, 10, what="the second stall")
    assert rig.engine.counters["stalls"] == 2


def test_shutdown_stops_every_bridge_and_says_so():
    rig = EngineRig(reconnect=False)
    rig.engine.load_scene(SCENE)
    publishers = list(rig.ros.publishers.values())
    assert rig.engine.shutdown(timeout=2.0)
    assert rig.engine.bridges == {} and rig.links[0].closed
    assert all(p.unregistered for p in publishers)
    assert rig.statuses()[-1]["state"] == STOPPED


def test_a_scene_read_and_expanded_at_start_up_is_loaded_without_reading_or_expanding_again(rig, monkeypatch):
    from airsim_mapper.engine import core as engine_module
    from airsim_mapper.mapping.expand import expand
    from airsim_mapper.mapping.scene import read_scene

    scene = read_scene(SIM_CONFIG, SCENE)
    specs = expand(rig.engine.mapping, scene, "node", "")

    def again(*_args, **_kwargs):
        raise AssertionError("read or expanded again")

    monkeypatch.setattr(engine_module, "read_scene", again)
    monkeypatch.setattr(engine_module, "expand", again)
    assert rig.engine.load_scene(scene, specs) is scene
    assert set(rig.engine.bridges) == {spec.name for spec in specs}


def test_an_edited_mapping_restarts_only_the_bridges_whose_expansion_changed(rig: EngineRig):
    from airsim_mapper.mapping.loader import load_mapping_text

    rig.engine.load_scene(SCENE)
    before = dict(rig.engine.bridges)
    edited = load_mapping_text(
        "version: 1\nextends: default\nrules:\n  - {name: actual_pose, ros: /drones/<robot_name>/pose}\n",
        str(SIM_CONFIG / "edited.yaml"),
    )
    diff = rig.engine.apply_mapping(edited)
    assert diff.changed == ("actual_pose[Drone1]",) and not diff.added and not diff.removed
    assert rig.engine.bridges["actual_pose[Drone1]"] is not before["actual_pose[Drone1]"]
    assert all(
        rig.engine.bridges[name] is bridge for name, bridge in before.items() if name != "actual_pose[Drone1]"
    )
    assert "/drones/Drone1/pose" in rig.ros.publishers
    assert rig.ros.publishers["/airsim_node/Drone1/actual_pose"].unregistered


def test_a_bridge_that_cannot_start_stays_off_and_every_other_one_runs(rig: EngineRig, caplog):
    from airsim_mapper.mapping.loader import load_mapping_text

    rig.engine.load_scene(SCENE)
    rig.ros.refused = {"/drones/Drone1/pose"}
    edited = load_mapping_text(
        "version: 1\nextends: default\nrules:\n"
        "  - {name: actual_pose, ros: /drones/<robot_name>/pose}\n"
        "  - {name: imu, ros: /drones/<robot_name>/imu}\n",
        str(SIM_CONFIG / "edited.yaml"),
    )
    diff = rig.engine.apply_mapping(edited)
    assert set(diff.changed) == {"actual_pose[Drone1]", "imu[Drone1/IMU1]"}
    assert "actual_pose[Drone1]" not in rig.engine.bridges  # refused by ROS: off, and said so
    assert "bridge actual_pose[Drone1] could not start" in caplog.text
    assert "/drones/Drone1/imu" in rig.ros.publishers  # the other changed bridge started
    assert list(rig.engine.bridges) == [
        s.name for s in rig.engine.specs_for(rig.engine.scene) if s.name in rig.engine.bridges
    ]
    rig.ros.refused = set()
    rig.engine.apply_mapping(edited)  # applying again starts what is missing
    assert "actual_pose[Drone1]" in rig.engine.bridges


EXTRA = """\
version: 1
extends: default
rules:
  - name: extra_pose
    for_each: robot
    direction: sim_to_ros
    converter: pose
    sim: /Sim/<scene_name>/robots/<robot_name>/actual_pose
    ros: {ros}
    type: geometry_msgs/PoseStamped
"""


def test_a_bridge_ros_refuses_at_run_time_is_an_error_in_the_reload_answer_and_on_diagnostics(rig, tmp_path):
    from airsim_mapper.engine.diagnostics import ERROR, mapping_status, refused_status
    from airsim_mapper.engine.mapping_reload import MappingReloader

    rig.engine.load_scene(SCENE)
    mine = tmp_path / "mine.yaml"
    mine.write_text(EXTRA.format(ros="/elsewhere/pose"))
    reloader = MappingReloader(rig.engine, str(mine), load_mapping("default"))
    rig.ros.refused.add("/elsewhere/pose")  # rospy refuses it, as it does a name taken with another type
    outcome = reloader.reload()
    why = "ValueError: /elsewhere/pose is already advertised with another type"
    assert outcome.applied and not outcome.ok
    assert outcome.errors == (f"bridge extra_pose[Drone1] could not start: {why}",)
    assert outcome.message == f"applied: 1 added, 0 removed, 0 changed, 81 unchanged\n{outcome.errors[0]}"
    assert rig.engine.refused_bridges() == {"extra_pose[Drone1]": why}
    assert rig.engine.mapping_report["state"] == "partial"  # applied, with a bridge that did not start
    status = mapping_status(rig.engine.mapping_report, "node: ")
    assert (status["level"], status["message"]) == (ERROR, f"applied; {outcome.errors[0]}")
    assert refused_status("extra_pose[Drone1]", why, "node: ")["level"] == ERROR
    rig.ros.refused.clear()  # the next reload tries it again, and it starts
    mine.write_text(EXTRA.format(ros="/elsewhere/pose") + "# touched\n")
    again = reloader.reload()
    assert again.ok and rig.engine.refused_bridges() == {} and "extra_pose[Drone1]" in rig.engine.bridges
    assert rig.engine.mapping_report["state"] == "applied"


def test_a_reload_taking_a_name_the_node_owns_is_refused_whole(rig, tmp_path):
    from airsim_mapper.engine.mapping_reload import MappingReloader

    rig.engine.load_scene(SCENE)
    before = dict(rig.engine.bridges)
    mine = tmp_path / "mine.yaml"
    mine.write_text(EXTRA.format(ros="<namespace>/<node_name>/reload_mapping"))
    outcome = MappingReloader(rig.engine, str(mine), load_mapping("default")).reload()
    assert not outcome.applied and rig.engine.bridges == before
    assert outcome.errors == (
        f"{mine}:9:10: bridge extra_pose[Drone1]: ROS name '/node/reload_mapping' belongs to the node's "
        "private service ~reload_mapping; a rule cannot take it",
    )


def test_time_going_back_in_the_pose_stream_starts_tf_and_the_stale_filters_over(rig: EngineRig, caplog):
    rig.engine.load_scene(SCENE)
    assert rig.ros.tf_cleared == 1  # a loaded scene's clock starts from zero
    pose = "/Sim/SceneDroneSensors/robots/Drone1/actual_pose"
    sim = rig.links[-1]
    message = {
        "time_stamp": 0,
        "pose": {
            "position": {"x": 0.0, "y": 0.0, "z": 0.0},
            "orientation": {"w": 1.0, "x": 0.0, "y": 0.0, "z": 0.0},
        },
    }
    for seconds in (60, 61, 62):  # the old session; nobody subscribes to /clock
        assert sim.deliver(pose, {**message, "time_stamp": seconds * 1_000_000_000}) == 1
    imu = rig.engine.bridges["imu[Drone1/IMU1]"]
    rig.ros.publishers[IMU_ROS].subscribers(1)  # a lazy bridge attaching waits for time after 62 s
    assert imu._fresh_after >= 62_000_000_000
    with caplog.at_level("INFO"):
        sim.deliver(pose, {**message, "time_stamp": 1_000_000_000})  # the simulator restarted its clock
    assert rig.engine.sim_time.jumps_back == 1 and rig.ros.tf_cleared == 2
    assert imu._fresh_after == 0 and rig.engine.hub.sim_now() <= 1_000_000_000
    assert "tf buffer cleared" in caplog.text


def test_a_requested_scene_load_logs_the_table_of_its_bridges(rig: EngineRig, caplog):
    caplog.set_level(logging.INFO, logger="rosout")
    rig.engine.request_scene(SCENE)
    wait_until(lambda: "bridges:\n" in caplog.text, 20, "the bridge table")
    table = caplog.text.split("bridges:\n", 1)[1]
    assert "/airsim_node/Drone1/actual_pose" in table and "geometry_msgs/PoseStamped" in table
