"""/diagnostics' simulator entry: state, scene and the counts of refused simulator frames."""

from __future__ import annotations

from types import SimpleNamespace

from airsim_mapper.engine.diagnostics import ERROR, OK, Diagnostics
from airsim_mapper.engine.sim_link import FrameCounts


def diagnostics(**engine: object) -> Diagnostics:
    made = Diagnostics.__new__(Diagnostics)  # no ROS: only the pure report is used
    connected = {"state": "connected", "reason": "", "scene": None, "bridges": {}}
    made.engine = SimpleNamespace(**{**connected, **engine})
    made.prefix = "node: "
    return made


def test_the_simulator_entry_counts_bad_and_oversized_frames():
    status = diagnostics(frame_counts=FrameCounts(bad=3, oversized=2)).connection_status()
    assert status["level"] == OK
    assert (status["values"]["bad_frames"], status["values"]["oversized_frames"]) == ("3", "2")


def test_a_recent_jump_back_in_sim_time_is_a_warning_on_the_simulator_entry():
    from airsim_mapper.engine.diagnostics import WARN
    from airsim_mapper.engine.simtime import SimTimeWatch

    watch = SimTimeWatch()
    watch.observe(5_000_000_000, 10.0)
    watch.observe(0, 11.0)
    status = diagnostics(sim_time=watch).connection_status(now=12.0)
    assert status["level"] == WARN
    assert status["message"] == "connected; simulation time went back 5.000 s 1 s ago (1 jumps back in all)"
    assert status["values"]["sim_time_jumps_back"] == "1"
    assert diagnostics(sim_time=watch).connection_status(now=100.0)["level"] == OK


def test_requests_unanswered_while_topic_frames_arrive_are_a_warning_on_the_simulator_entry():
    from airsim_mapper.engine.diagnostics import WARN

    reason = "no answer to 4 probes of 1 s, but topic frames arrive"
    status = diagnostics(reason=reason).connection_status()
    assert status["level"] == WARN and status["message"] == f"connected: {reason}"
    assert diagnostics(state="stale", reason="unresponsive").connection_status()["level"] == ERROR


class Publisher:
    def __init__(self, connections: int) -> None:
        self.connections, self.sent = connections, []

    def get_num_connections(self) -> int:
        return self.connections

    def publish(self, message) -> None:
        self.sent.append(message)


def test_nothing_is_built_while_nobody_subscribes_and_the_next_rate_starts_from_the_skipped_report(
    monkeypatch,
):
    import rospy

    from airsim_mapper.engine import diagnostics as module

    clock = iter([10.0, 12.0])
    monkeypatch.setattr(module.time, "monotonic", lambda: next(clock))
    bridge = SimpleNamespace(
        stats=SimpleNamespace(messages=0, errors=0, last_time=0.0, last_error="", stale_dropped=0, clamped=0),
        spec=SimpleNamespace(direction="sim_to_ros", sim="/s", ros="/r", name="imu", converter="imu"),
        _attached=False,
    )
    made = diagnostics(hub=SimpleNamespace(streams=dict))
    made.engine.bridges = {"imu": bridge}
    made.engine.ros = SimpleNamespace(now=lambda: rospy.Time(1))  # the engine's ROS link's clock
    made._seen = {}
    made.publisher = Publisher(connections=0)
    bridge.stats.messages = 500  # before the skipped report (t = 10 s): not in the next rate
    made.publish()
    assert made.publisher.sent == [] and made._seen["imu"].messages == 500
    made.publisher.connections = 1
    bridge.stats.messages = 700
    made.publish()  # t = 12 s
    [array] = made.publisher.sent
    [status] = [s for s in array.status if s.name == "node: imu"]
    values = {kv.key: kv.value for kv in status.values}
    assert (values["messages"], values["rate_hz"]) == ("700", "100.00")


def test_a_silent_event_stream_is_ok_and_a_silent_sensor_stream_a_warning():
    """Collisions come only when something collides: a subscribed collision topic with nothing on it is
    normal, where a subscribed IMU with nothing on it is a fault."""
    from airsim_mapper.engine.bridges import BridgeStats
    from airsim_mapper.engine.diagnostics import WARN, _Seen, bridge_status

    def status(converter: str, last_time: float = 0.0) -> dict:
        spec = SimpleNamespace(
            name=f"{converter}[Drone1]",
            converter=converter,
            direction="sim_to_ros",
            sim="/Sim/s/robots/Drone1/x",
            ros="/airsim_node/Drone1/x",
        )
        bridge = SimpleNamespace(stats=BridgeStats(last_time=last_time), spec=spec, _attached=True)
        return bridge_status(bridge, _Seen(), 100.0, 0, "node: ")

    assert (status("collision")["level"], status("collision")["message"]) == (OK, "no event yet")
    assert status("collision", last_time=40.0)["message"] == "last event 60.0 s ago"
    assert (status("imu")["level"], status("imu")["message"]) == (WARN, "no data from the simulator")
    assert status("imu", last_time=40.0)["message"] == "stale for 60.0 s"
