"""The catalogue's command entries (ROS -> simulator topics): velocity, robot and camera pose commands,
and scene loading."""

from __future__ import annotations

from airsim_mapper.convert.entries.model import (
    ACTION,
    CALL,
    DEFAULT_QOS,
    POSE,
    ROS_TO_SIM,
    SEND,
    Example,
    converter_info,
)

# cmd_vel's params.frame, what the Twist's linear velocity is in (body, the default, first), with the
# simulator method that takes a velocity in that frame
VELOCITY_FRAMES = {"body": "MoveByVelocityBodyFrame", "world": "MoveByVelocity"}

COMMANDS = (
    converter_info(
        "cmd_vel",
        ROS_TO_SIM,
        ["geometry_msgs/Twist"],
        CALL,
        "command",
        "cmd_vel",
        "Twist -> MoveByVelocityBodyFrame params (or MoveByVelocity with params.frame world), with "
        "limits and a watchdog",
        qos=DEFAULT_QOS,
        param_choices={"frame": VELOCITY_FRAMES},  # the default first
        example=Example(
            {"linear": {"x": 1.0, "y": 0.0, "z": -0.5}, "angular": {"x": 0.0, "y": 0.0, "z": 0.2}}
        ),
    ),
    converter_info(
        "desired_pose",
        ROS_TO_SIM,
        ["geometry_msgs/PoseStamped"],
        SEND,
        "command",
        "desired_pose",
        "PoseStamped -> sim desired_pose message (robot teleport)",
        qos=DEFAULT_QOS,
        example=Example({"pose": POSE}),
    ),
    converter_info(
        "camera_desired_pose",
        ROS_TO_SIM,
        ["geometry_msgs/PoseStamped"],
        CALL,
        "command",
        "camera_desired_pose",
        "PoseStamped -> camera SetPose params with wait_for_pose_update",
        qos=DEFAULT_QOS,
        after="remember_camera_pose",
        example=Example({"pose": POSE}),
    ),
    converter_info(
        "load_scene",
        ROS_TO_SIM,
        ["std_msgs/String"],
        ACTION,
        "command",
        "load_scene",
        "String scene file name -> the engine loads it from --simconfigpath",
        qos=DEFAULT_QOS,
        action="load_scene",
        example=Example({"data": "scene_basic_drone.jsonc"}),
    ),
)
