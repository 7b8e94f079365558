"""The runners against a fake simulator link: what each catalogue runner sends, and its after-hooks."""

from __future__ import annotations

import concurrent.futures
from dataclasses import dataclass, field
from typing import Any

import pytest
from geometry_msgs.msg import PoseStamped
from harness import SIM_CONFIG
from std_msgs.msg import String
from std_srvs.srv import TriggerRequest, TriggerResponse

from airsim_mapper.convert.pose import camera_pose_key
from airsim_mapper.engine.bridges import RosService, RosToSim, Services, SimToRos, StreamingImage, build
from airsim_mapper.mapping.expand import expand
from airsim_mapper.mapping.loader import load_mapping
from airsim_mapper.scene import read_scene


@dataclass
class FakeSim:
    """Records what the runners send; every call succeeds with `result`."""

    result: Any = True
    calls: list[tuple[str, dict]] = field(default_factory=list)
    published: list[tuple[str, dict]] = field(default_factory=list)

    def call(self, method: str, params: dict, timeout: float = 30.0) -> Any:
        self.calls.append((method, params))
        return self.result

    def call_async(self, method: str, params: dict) -> concurrent.futures.Future:
        self.calls.append((method, params))
        future: concurrent.futures.Future = concurrent.futures.Future()
        future.set_result(self.result)
        return future

    def publish(self, topic: str, message: dict) -> None:
        self.published.append((topic, message))


@dataclass
class FakeStreaming:
    switched: int = 0

    def next_camera(self) -> None:
        self.switched += 1


@pytest.fixture(scope="module")
def specs():
    scene = read_scene(str(SIM_CONFIG), "scene_drone_sensors.jsonc")
    return {spec.name: spec for spec in expand(load_mapping("default"), scene, "node", "")}


@pytest.fixture
def sim() -> FakeSim:
    return FakeSim()


@pytest.fixture
def services(sim: FakeSim) -> Services:
    actions: list[tuple[str, dict]] = []
    found = Services(sim, None, None, {}, lambda action, params: actions.append((action, params)))
    found.actions = actions  # type: ignore[attr-defined]
    return found


def test_the_catalogue_picks_each_runner(specs, services):
    kinds = {name.split("[")[0]: type(build(spec, services)) for name, spec in specs.items()}
    assert kinds["actual_pose"] is SimToRos
    assert kinds["streaming_image"] is StreamingImage
    assert kinds["cmd_vel"] is RosToSim and kinds["load_scene"] is RosToSim
    assert kinds["switch_view"] is RosService and kinds["takeoff_all"] is RosService


def test_switch_view_calls_the_simulator_then_every_streaming_image_follows(specs, services, sim):
    spec = next(s for n, s in specs.items() if n.startswith("switch_view["))
    streams = [FakeStreaming(), FakeStreaming()]
    services.streaming.extend(streams)
    service = build(spec, services)
    service._response = TriggerResponse  # what start() takes from the service class it registers
    answer = service.on_request(TriggerRequest())
    assert answer.success and sim.calls == [(spec.sim, {})]
    assert [s.switched for s in streams] == [1, 1]
    sim.result = False  # the simulator refused: the streaming images stay on their cameras
    assert not service.on_request(TriggerRequest()).success
    assert [s.switched for s in streams] == [1, 1]


def test_a_camera_pose_command_is_remembered_once_the_simulator_took_it(specs, services, sim):
    spec = next(s for n, s in specs.items() if n.startswith("camera_desired_pose[Drone1/DownCamera"))
    runner = build(spec, services)
    goal = PoseStamped()
    goal.pose.orientation.w = 1.0
    goal.pose.position.x = 2.0
    runner.on_message(goal)
    assert [method for method, _ in sim.calls] == [spec.sim]
    assert camera_pose_key("Drone1", "DownCamera") in services.shared


def test_load_scene_asks_the_engine_for_its_action(specs, services, sim):
    spec = next(s for n, s in specs.items() if n.startswith("load_scene["))
    build(spec, services).on_message(String(data=" scene_basic_drone.jsonc "))
    assert services.actions == [("load_scene", {"scene": "scene_basic_drone.jsonc"})]
    assert sim.calls == [] and sim.published == []
