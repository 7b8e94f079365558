"""launch/airsim_mapper.launch.py, the ROS 2 launch file: its arguments mirror launch/projectairsim.launch's,
and it starts .venv-ros2's node with each setting as a typed ROS 2 parameter, the node's name and its
namespace. Read with recording stand-ins for `launch` and `launch_ros` (no wheel exists for them), and run
for real where they are importable."""

from __future__ import annotations

import importlib.util
import json
import signal
import subprocess
import sys
import types
import xml.etree.ElementTree as ET
from pathlib import Path
from typing import Any

import pytest
from harness import Rig
from ros2kit import ROOT, ros2_env

from airsim_mapper.cli.settings import SETTINGS

LAUNCH_FILE = ROOT / "launch" / "airsim_mapper.launch.py"
ROS1_LAUNCH = ROOT / "launch" / "projectairsim.launch"
NODE = ROOT / ".venv-ros2" / "bin" / "airsim-mapper-node"
LISTENER = Path(__file__).resolve().parent / "listen_ros2.py"


class Recorded:
    """A stand-in class of `launch` or `launch_ros`: keeps what it was made with."""

    def __init__(self, *args: Any, **kwargs: Any) -> None:
        self.args, self.kwargs = args, kwargs

    def __eq__(self, other: object) -> bool:
        return type(self) is type(other) and (self.args, self.kwargs) == (other.args, other.kwargs)

    def __repr__(self) -> str:
        return f"{type(self).__name__}{self.args}{self.kwargs}"


STAND_INS = {
    "launch.actions": ("DeclareLaunchArgument",),
    "launch.launch_description": ("LaunchDescription",),
    "launch.substitutions": ("LaunchConfiguration",),
    "launch_ros.actions": ("Node",),
    "launch_ros.parameter_descriptions": ("ParameterValue",),
}


@pytest.fixture
def description(monkeypatch) -> dict[str, Any]:
    """generate_launch_description() of the launch file, made of stand-ins: the declared arguments
    (name: default) and the node's keywords."""
    made: dict[str, type] = {}
    for package in ("launch", "launch_ros"):
        monkeypatch.setitem(sys.modules, package, types.ModuleType(package))
    for module_name, names in STAND_INS.items():
        module = types.ModuleType(module_name)
        for name in names:
            made[name] = type(name, (Recorded,), {})
            setattr(module, name, made[name])
        monkeypatch.setitem(sys.modules, module_name, module)
    spec = importlib.util.spec_from_file_location("airsim_mapper_launch", LAUNCH_FILE)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    result = module.generate_launch_description()
    assert isinstance(result, made["LaunchDescription"])
    (entities,) = result.args
    declared = [e for e in entities if isinstance(e, made["DeclareLaunchArgument"])]
    (node,) = [e for e in entities if isinstance(e, made["Node"])]
    return {
        "arguments": {a.args[0]: a.kwargs["default_value"] for a in declared},
        "descriptions": [a.kwargs["description"] for a in declared],
        "node": node.kwargs,
        "config": made["LaunchConfiguration"],
        "value": made["ParameterValue"],
    }


def ros1_arguments() -> dict[str, str]:
    return {arg.get("name"): arg.get("default") for arg in ET.parse(ROS1_LAUNCH).getroot().iter("arg")}


def test_the_launch_file_declares_the_ros1_launch_files_arguments_with_their_defaults(description) -> None:
    declared = description["arguments"]
    for name, default in ros1_arguments().items():
        assert name in declared, name
        if "$(find" in default:  # the package's folder on ROS1, the checkout's here
            assert declared[name] == str(ROOT / default.split(")/", 1)[1]), name
        else:
            assert declared[name] == default, name
    assert declared["use_sim_time"] == "false"
    assert all(description["descriptions"])


def test_the_node_runs_the_venvs_entry_point_named_and_namespaced_by_the_arguments(description) -> None:
    node, config = description["node"], description["config"]
    assert node["executable"] == config("executable")
    assert description["arguments"]["executable"] == str(NODE)
    assert node["name"] == config("nodename") and node["namespace"] == config("namespace")
    assert node["prefix"] == "env -u PYTHONPATH"  # a sourced ROS 2 setup's packages stay out of the venv
    assert node.get("package") is None  # not an ament package: the executable is a path


def test_each_setting_is_a_ros2_parameter_typed_as_the_node_reads_it(description) -> None:
    node, config, value = description["node"], description["config"], description["value"]
    (parameters,) = node["parameters"]
    settings = {s.name: s for s in SETTINGS if s.name != "namespace"}  # namespace: the node's own, above
    assert parameters.keys() == settings.keys() | {"use_sim_time"}
    for name, parameter in parameters.items():
        kind = bool if name == "use_sim_time" else (str if settings[name].kind is str else int)
        assert parameter == value(config(name), value_type=kind), name
        default = description["arguments"][name]
        if name in settings:
            settings[name].kind(default)  # the node takes the default as it stands
    assert description["arguments"]["scene"] == ""  # without a scene the node waits on load_scene


def launch_is_importable(python: Path) -> bool:
    check = [str(python), "-c", "import launch, launch_ros"]
    return subprocess.run(check, env=ros2_env(0), capture_output=True).returncode == 0


RUN_LAUNCH = """
import sys
from launch import LaunchDescription, LaunchService
from launch.actions import IncludeLaunchDescription
from launch.launch_description_sources import PythonLaunchDescriptionSource

path, *pairs = sys.argv[1:]
arguments = [tuple(pair.split(":=", 1)) for pair in pairs]
source = PythonLaunchDescriptionSource(path)
service = LaunchService()
service.include_launch_description(
    LaunchDescription([IncludeLaunchDescription(source, launch_arguments=arguments)])
)
sys.exit(service.run())
"""


@pytest.mark.live
def test_the_launch_file_starts_a_node_that_bridges_under_its_namespace(
    launcher: Rig, ros2_python: Path, ros_domain: int, tmp_path: Path
) -> None:
    if not launch_is_importable(ros2_python):
        pytest.skip(
            "launch and launch_ros are not importable in .venv-ros2: PyPI has no wheel for them "
            "(ros-launch, ros-launch-ros); a ROS 2 install's `ros2 launch` runs the launch file"
        )
    server = launcher.simserver()
    launcher.env = {**ros2_env(ros_domain), "PYTHONUNBUFFERED": "1"}
    script = tmp_path / "run_launch.py"
    script.write_text(RUN_LAUNCH)
    pairs = [f"topicsport:={server.ports.topics}", f"servicesport:={server.ports.services}"]
    pairs += ["scene:=scene_basic_drone.jsonc", "namespace:=sim1"]
    launched = launcher.start("launch", [str(ros2_python), str(script), str(LAUNCH_FILE), *pairs])
    topic = "/sim1/airsim_node/Drone1/actual_pose"
    out = subprocess.run(
        [str(ros2_python), str(LISTENER), "60", f"geometry_msgs/PoseStamped={topic}"],
        env=ros2_env(ros_domain),
        capture_output=True,
        text=True,
        timeout=120,
    )
    heard = json.loads(out.stdout.strip().splitlines()[-1])["topics"]
    assert heard.get(topic, {}).get("frame_id") == "sim1/map", launched.output()[-3000:]
    launched.popen.send_signal(signal.SIGINT)
    assert launched.popen.wait(timeout=30) == 0, launched.output()[-3000:]
