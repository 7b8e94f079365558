"""The catalogue's pose entries: the robot's pose, its cameras' and sensors' poses, its odometry, and
the point where it collided (all light, converted on the receive thread)."""

from __future__ import annotations

from airsim_mapper.convert.entries.model import POSE, PUBLISH, SIM_TO_ROS, STAMP, Example, converter_info

POSES = (
    converter_info(
        "pose",
        SIM_TO_ROS,
        ["geometry_msgs/PoseStamped"],
        PUBLISH,
        "pose",
        "robot_pose",
        "sim PoseStamped (robot actual_pose) -> PoseStamped; with tf, also the robot's transform",
        inline=True,
        example=Example({**STAMP, **POSE}),
    ),
    converter_info(
        "camera_pose",
        SIM_TO_ROS,
        ["geometry_msgs/PoseStamped"],
        PUBLISH,
        "pose",
        "camera_pose",
        "robot actual_pose composed with the camera mount (and any camera pose command) -> camera pose",
        inline=True,
        example=Example({**STAMP, **POSE}),
    ),
    converter_info(
        "sensor_pose",
        SIM_TO_ROS,
        ["geometry_msgs/PoseStamped"],
        PUBLISH,
        "pose",
        "sensor_pose",
        "robot actual_pose composed with a sensor's config origin (lidar, radar, distance) -> its pose",
        inline=True,
        example=Example({**STAMP, **POSE}),
    ),
    converter_info(
        "camera_optical_pose",
        SIM_TO_ROS,
        ["geometry_msgs/PoseStamped"],
        PUBLISH,
        "pose",
        "camera_optical_pose",
        "as camera_pose, turned into the optical frame (z forward, x right, y down) for image frames",
        inline=True,
        example=Example({**STAMP, **POSE}),
    ),
    converter_info(
        "odometry",
        SIM_TO_ROS,
        ["nav_msgs/Odometry"],
        PUBLISH,
        "odometry",
        "odometry",
        "robot actual_pose -> Odometry; body-frame twist from successive poses (state in ctx.state)",
        inline=True,
        example=Example({**STAMP, **POSE}),
    ),
    converter_info(
        "collision",
        SIM_TO_ROS,
        ["geometry_msgs/PointStamped"],
        PUBLISH,
        "collision",
        "collision",
        "sim CollisionInfo -> PointStamped of the impact point (world frame)",
        inline=True,
        events=True,
        example=Example({**STAMP, "object_name": "x", "impact_point": {"x": 1.0, "y": 2.0, "z": 3.0}}),
    ),
)
