"""The engine with everything happening at once, on the fake links: mapping reloads, scene loads, simulator
reconnects, ROS subscribers coming and going and simulator messages arriving, for some seconds. Then the
engine's invariants hold: no bridge twice, no bridge of an old mapping or scene left, every stream where
its bridges are, the counters consistent. In-process (no simulator, no ROS master)."""

from __future__ import annotations

import random
import threading
import time
from collections import Counter
from collections.abc import Callable

import pytest
from fakes import IMU_MESSAGE, EngineRig
from harness import SIM_CONFIG, wait_until

from airsim_mapper.engine.bridges import SimToRos
from airsim_mapper.engine.errors import EngineError
from airsim_mapper.engine.status import CONNECTED, status_topic
from airsim_mapper.mapping.expand import expand
from airsim_mapper.mapping.loader import load_mapping, load_mapping_text

SECONDS = 4.0
SCENES = ("scene_drone_sensors.jsonc", "scene_basic_drone.jsonc")
POSE_MESSAGE = {
    "time_stamp": 5_000_000_000,
    "position": {"x": 1.0, "y": 2.0, "z": -3.0},
    "orientation": {"w": 1.0, "x": 0.0, "y": 0.0, "z": 0.0},
}
EDITED = """version: 1
extends: default
rules:
  - {name: actual_pose, ros: /drones/<robot_name>/pose}
  - {name: camera_image, rate_limit_hz: 5}
"""


def mappings():
    return (load_mapping("default"), load_mapping_text(EDITED, str(SIM_CONFIG / "edited.yaml")))


class Storm:
    """Threads that each repeat one kind of change until `stop` is set; what each managed is counted."""

    def __init__(self, rig: EngineRig) -> None:
        self.rig = rig
        self.stop = threading.Event()
        self.done: Counter[str] = Counter()
        self.failures: list[str] = []
        self._threads: list[threading.Thread] = []

    def run(self, name: str, step: Callable[[random.Random], None], pause: float) -> None:
        def loop() -> None:
            rng = random.Random(name)
            while not self.stop.is_set():
                try:
                    step(rng)
                except EngineError:  # a scene change while the simulator is lost: refused, by design
                    self.done[f"{name} refused"] += 1
                except Exception as exc:  # anything else is a finding
                    self.failures.append(f"{name}: {type(exc).__name__}: {exc}")
                else:
                    self.done[name] += 1
                self.stop.wait(pause)

        thread = threading.Thread(target=loop, name=f"storm-{name}", daemon=True)
        self._threads.append(thread)
        thread.start()

    def join(self) -> None:
        self.stop.set()
        for thread in self._threads:
            thread.join(timeout=30)
        assert not any(thread.is_alive() for thread in self._threads), "a storm thread hangs"


def test_reloads_scene_loads_reconnects_and_subscriber_churn_at_once_keep_the_engines_invariants():
    rig = EngineRig()
    engine, ros = rig.engine, rig.ros
    engine.load_scene(SCENES[0])
    storm = Storm(rig)
    reload_mappings = mappings()

    def reload(rng: random.Random) -> None:
        engine.apply_mapping(rng.choice(reload_mappings))

    def load(rng: random.Random) -> None:
        engine.load_scene(rng.choice(SCENES))

    def drop(_rng: random.Random) -> None:
        rig.links[-1].dropped = True  # the connection closes: lost, then reconnected by the supervisor

    def churn(rng: random.Random) -> None:
        live = [p for p in list(ros.publishers.values()) if p.on_peers is not None and not p.unregistered]
        if live:
            rng.choice(live).subscribers(rng.choice((0, 1, 2)))

    def deliver(_rng: random.Random) -> None:
        link = rig.links[-1]
        for topic in list(link.subscriptions):
            if topic.endswith("/imu_kinematics"):
                link.deliver(topic, IMU_MESSAGE)
            elif topic.endswith("/actual_pose"):
                link.deliver(topic, POSE_MESSAGE)

    storm.run("reload", reload, 0.05)
    storm.run("load", load, 0.1)
    storm.run("drop", drop, 1.2)
    storm.run("churn", churn, 0.002)
    storm.run("deliver", deliver, 0.005)
    time.sleep(SECONDS)
    storm.join()
    print(f"done: {dict(storm.done)}; counters {engine.counters}; links {len(rig.links)}")
    try:
        wait_until(lambda: engine.state == CONNECTED, 15, what="the last reconnect")
        assert storm.failures == []
        assert storm.done["reload"] > 5 and storm.done["load"] > 3 and storm.done["churn"] > 100
        assert engine.counters["reconnects"] >= 1 and engine.counters["sim_losses"] >= 1
        check_invariants(rig)
    finally:
        engine.shutdown(timeout=2.0)


def check_invariants(rig: EngineRig) -> None:
    engine, ros, link = rig.engine, rig.ros, rig.links[-1]
    with engine.lock:
        bridges = dict(engine.bridges)
        expected = {spec.name: spec for spec in expand(engine.mapping, engine.scene, "node", "")}
        # no bridge of an old mapping or scene left, none missing: exactly the current expansion
        assert {name: bridge.spec for name, bridge in bridges.items()} == expected
        # no bridge twice: one live publisher per ROS name, and exactly the current bridges' (and status)
        live = Counter(p.name for p in ros.made if not p.unregistered)
        assert [name for name, count in live.items() if count > 1] == []
        publishing = {b.spec.ros for b in bridges.values() if isinstance(b, SimToRos) and b.spec.ros}
        assert set(live) == publishing | {status_topic("node")}
        # every stream where its bridges are: attached iff it should be, each handler once
        streams = engine.hub.streams()
        attached: Counter[str] = Counter()
        for bridge in bridges.values():
            if not isinstance(bridge, SimToRos) or bridge.topic is None:
                continue
            wanted = not bridge.lazy or bridge.publisher.get_num_connections() > 0
            assert bridge._attached == wanted, bridge.spec.name
            if wanted:
                attached[bridge.topic] += 1
                assert bridge.topic in streams, bridge.spec.name
        assert {topic: len(stream.handlers) for topic, stream in streams.items()} == dict(attached)
        # the current link carries exactly the streams, once each; every older link is closed
        assert {topic: len(callbacks) for topic, callbacks in link.subscriptions.items()} == dict.fromkeys(
            streams, 1
        )
        assert all(old.closed for old in rig.links[:-1])
    # the counters agree with one another
    counters = engine.counters
    assert counters["reconnects"] <= counters["sim_losses"]
    status = engine.status()
    assert (status["state"], status["reconnects"], status["sim_losses"]) == (
        CONNECTED,
        counters["reconnects"],
        counters["sim_losses"],
    )
    assert status["bad_frames"] == 0 and status["bridge_errors"] == {}
    for topic, stream in status["streams"].items():
        assert stream["handled"] + stream["dropped"] <= stream["received"], topic
        assert stream["errors"] == 0, topic


def test_the_invariants_hold_on_a_quiet_engine_too_and_see_a_bridge_left_over():
    rig = EngineRig()
    try:
        rig.engine.load_scene(SCENES[0])
        check_invariants(rig)
        stale = next(b for b in rig.engine.bridges.values() if isinstance(b, SimToRos) and b.spec.ros)
        rig.engine.mapping = mappings()[1]  # as if a reload had swapped the mapping but left the bridges
        with pytest.raises(AssertionError):
            check_invariants(rig)
        assert stale.spec.name in rig.engine.bridges
    finally:
        rig.engine.shutdown(timeout=2.0)
