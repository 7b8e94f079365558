"""The catalogue's service entries (ROS services -> simulator calls): triggers, the reset to the scene
origin, a method on every robot, a bool parameter, and the streaming view switch."""

from __future__ import annotations

from airsim_mapper.convert.entries.model import (
    ROS_TO_SIM,
    SERVE,
    SERVE_ALL,
    SERVICES,
    Example,
    converter_info,
)

ORIGIN = {"xyz": "1 2 -3", "rpy-deg": "0 0 90"}  # a robot actor's origin in a scene

SERVICES = (
    converter_info(
        "trigger",
        ROS_TO_SIM,
        ["std_srvs/Trigger", "std_srvs/Empty"],
        SERVE,
        "command",
        "trigger",
        "service request -> sim service call with the rule's fixed params; reply from its result",
        qos=SERVICES,
        example=Example({}),
    ),
    converter_info(
        "reset_pose",
        ROS_TO_SIM,
        ["std_srvs/Trigger", "std_srvs/Empty"],
        SERVE,
        "reset",
        "reset_pose",
        "service request -> robot SetPose params that return it to its scene origin, at rest",
        qos=SERVICES,
        example=Example({}, source={"origin": ORIGIN}),
    ),
    converter_info(
        "trigger_all",
        ROS_TO_SIM,
        ["std_srvs/Trigger"],
        SERVE_ALL,
        "command",
        "trigger",
        "Trigger -> the robot method params.method on every robot of the scene (sim: the robots prefix)",
        qos=SERVICES,
        example=Example({}, params={"method": "Hover"}),
        required_params={"method": "the robot method to call on every robot (e.g. Hover)"},
    ),
    converter_info(
        "set_bool",
        ROS_TO_SIM,
        ["std_srvs/SetBool"],
        SERVE,
        "command",
        "set_bool",
        "SetBool request -> sim service call with the bool as the rule's param",
        qos=SERVICES,
        example=Example({"data": True}, params={"arg": "do_pause"}),
        required_params={"arg": "the simulator parameter that receives the bool (e.g. do_pause)"},
    ),
    converter_info(
        "switch_view",
        ROS_TO_SIM,
        ["std_srvs/Trigger"],
        SERVE,
        "command",
        "trigger",
        "Trigger -> SwitchStreamingView, and the streaming image follows the next camera",
        qos=SERVICES,
        after="next_streaming_camera",
        example=Example({}),
    ),
)
