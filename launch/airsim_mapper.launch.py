"""The Project AirSim bridge node on ROS 2, for a ROS 2 install's `ros2 launch` (launch and launch_ros).

    ros2 launch launch/airsim_mapper.launch.py scene:=scene_drone_sensors.jsonc namespace:=sim1

The arguments are launch/projectairsim.launch's: mapping, scene, address, topicsport, servicesport,
simconfigpath, nodename, namespace; plus use_sim_time, and executable (the checkout's
.venv-ros2/bin/airsim-mapper-node, which `make setup` builds). Each setting goes to the node as its ROS 2
parameter. namespace is the node's ROS namespace (what `<group ns>` is on ROS1): the mapping's topics go
below it and its frames are prefixed with it. With the defaults the node runs load_scene and waits for a
scene file name on it; scene:=FILE loads one at start. The node runs with PYTHONPATH unset, so that a
sourced ROS 2 setup's packages stay out of the venv.
"""

from __future__ import annotations

from pathlib import Path

from launch.actions import DeclareLaunchArgument
from launch.launch_description import LaunchDescription
from launch.substitutions import LaunchConfiguration
from launch_ros.actions import Node
from launch_ros.parameter_descriptions import ParameterValue

ROOT = Path(__file__).resolve().parent.parent
# name: (default, type, description): the node's parameters, typed so that launch_ros does not read them
# as YAML (an empty scene would be null, a scene named 0123 a number)
PARAMETERS = {
    "mapping": ("default", str, "mapping YAML file, or a shipped mapping's name"),
    "scene": ("", str, "scene config file to load at start (empty: wait for one on load_scene)"),
    "address": ("127.0.0.1", str, "host running Project AirSim"),
    "topicsport": ("8989", int, "Project AirSim pub-sub port"),
    "servicesport": ("8990", int, "Project AirSim services port"),
    "simconfigpath": (str(ROOT / "sim_config"), str, "directory holding the scene configs"),
    "use_sim_time": ("false", bool, "the node's clock follows /clock (the node publishes it)"),
}
ARGUMENTS = {
    **{name: (default, description) for name, (default, _kind, description) in PARAMETERS.items()},
    "nodename": ("projectairsim", "the node's name"),
    "namespace": ("", "the node's ROS namespace: topics below it, frames prefixed with it"),
    "executable": (str(ROOT / ".venv-ros2" / "bin" / "airsim-mapper-node"), "the bridge node to run"),
}


def generate_launch_description() -> LaunchDescription:
    arguments = [
        DeclareLaunchArgument(name, default_value=default, description=description)
        for name, (default, description) in ARGUMENTS.items()
    ]
    parameters = {
        name: ParameterValue(LaunchConfiguration(name), value_type=kind)
        for name, (_default, kind, _description) in PARAMETERS.items()
    }
    node = Node(
        executable=LaunchConfiguration("executable"),
        name=LaunchConfiguration("nodename"),
        namespace=LaunchConfiguration("namespace"),
        parameters=[parameters],
        prefix="env -u PYTHONPATH",
        output="screen",
    )
    return LaunchDescription([*arguments, node])
