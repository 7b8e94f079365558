"""The converter catalogue: every converter a mapping may name, with what it fits.

Pure data, importable without ROS, so that mapping validation can check a rule's converter against its
ROS type and direction. The implementation of each converter lives in the module named here and is
looked up by `airsim_mapper.convert.registry` at run time.

Contract of an implementation (see registry.py):
- sim_to_ros: ``fn(msg: dict, ctx: ConvertContext) -> ROS message`` (or None to publish nothing)
- ros_to_sim: ``fn(ros_msg, ctx: ConvertContext) -> dict`` (sim topic message or service params)
Converters raise ``ConversionError`` (airsim_mapper.convert.errors) for malformed input, nothing else.

Each entry also says how the engine runs the converter (`runner`, engine/bridges.py) and what follows a
successful simulator call (`after`), so the engine never tests converter names.

`markdown_table` renders the catalogue for people: `airsim-mapper converters` prints it, and
`docs/converters.md` is that output (a test keeps the two equal).
"""

from __future__ import annotations

from collections.abc import Iterable
from dataclasses import dataclass

SIM_TO_ROS = "sim_to_ros"
ROS_TO_SIM = "ros_to_sim"

# How the engine runs a converter's bridges (engine/bridges.py has one runner for each).
PUBLISH = "publish"  # a simulator topic -> the converter -> a ROS topic and/or tf
STREAM = "stream"  # the active streaming camera's image -> a ROS topic (the camera follows switch_view)
SEND = "send"  # a ROS topic -> the converter -> a simulator topic
CALL = "call"  # a ROS topic -> the converter -> a simulator service call (with the command watchdog)
SERVE = "serve"  # a ROS service -> the converter -> a simulator service call; answered from its result
SERVE_ALL = "serve_all"  # a ROS service -> the rule's robot method on every robot of the scene
ACTION = "action"  # a ROS topic -> the converter -> an engine action (the entry's `action`)
RUNNERS = (PUBLISH, STREAM, SEND, CALL, SERVE, SERVE_ALL, ACTION)
SIM_KINDS = {PUBLISH: "topic", SEND: "topic", CALL: "service", SERVE: "service", SERVE_ALL: "service"}
# What runs after a successful simulator call (engine/bridges.py AFTER_HOOKS), and the engine's actions.
AFTER_HOOKS = ("remember_camera_pose", "next_streaming_camera")
ACTIONS = ("load_scene",)


@dataclass(frozen=True)
class ConverterInfo:
    name: str
    direction: str  # SIM_TO_ROS or ROS_TO_SIM
    ros_types: tuple[str, ...]  # ROS message (or service) types it produces / consumes
    runner: str  # one of RUNNERS
    module: str  # module in airsim_mapper.convert holding the function
    function: str
    summary: str
    after: str | None = None  # one of AFTER_HOOKS
    action: str | None = None  # one of ACTIONS (runner ACTION)

    @property
    def sim_kind(self) -> str:
        """What the rule's `sim` names: "topic", "service", or "node" (the engine supplies the source)."""
        return SIM_KINDS.get(self.runner, "node")


def _c(
    name, direction, ros_types, runner, module, function, summary, after=None, action=None
) -> ConverterInfo:
    return ConverterInfo(name, direction, tuple(ros_types), runner, module, function, summary, after, action)


CONVERTERS: dict[str, ConverterInfo] = {
    info.name: info
    for info in (
        # --- simulator -> ROS ----------------------------------------------------------------
        _c(
            "pose",
            SIM_TO_ROS,
            ["geometry_msgs/PoseStamped"],
            PUBLISH,
            "pose",
            "pose_stamped",
            "sim PoseStamped (robot actual_pose) -> PoseStamped; with tf, also the robot's transform",
        ),
        _c(
            "camera_pose",
            SIM_TO_ROS,
            ["geometry_msgs/PoseStamped"],
            PUBLISH,
            "pose",
            "camera_pose",
            "robot actual_pose composed with the camera mount (and any camera pose command) -> camera pose",
        ),
        _c(
            "sensor_pose",
            SIM_TO_ROS,
            ["geometry_msgs/PoseStamped"],
            PUBLISH,
            "pose",
            "sensor_pose",
            "robot actual_pose composed with a sensor's config origin (lidar, radar, distance) -> its pose",
        ),
        _c(
            "camera_optical_pose",
            SIM_TO_ROS,
            ["geometry_msgs/PoseStamped"],
            PUBLISH,
            "pose",
            "camera_optical_pose",
            "as camera_pose, turned into the optical frame (z forward, x right, y down) for image frames",
        ),
        _c(
            "odometry",
            SIM_TO_ROS,
            ["nav_msgs/Odometry"],
            PUBLISH,
            "odometry",
            "odometry",
            "robot actual_pose -> Odometry; body-frame twist from successive poses (state in ctx.state)",
        ),
        _c(
            "collision",
            SIM_TO_ROS,
            ["geometry_msgs/PointStamped"],
            PUBLISH,
            "collision",
            "collision",
            "sim CollisionInfo -> PointStamped of the impact point (world frame)",
        ),
        _c(
            "image",
            SIM_TO_ROS,
            ["sensor_msgs/Image"],
            PUBLISH,
            "image",
            "image",
            "sim Image (BGR, PNG, 16FC1, 16UC1, GRAY8) -> Image (bgr8, 32FC1 metres, mono8)",
        ),
        _c(
            "camera_info",
            SIM_TO_ROS,
            ["sensor_msgs/CameraInfo"],
            PUBLISH,
            "camera_info",
            "camera_info",
            "sim Image (for its size and stamp) + capture settings -> CameraInfo (plumb_bob, K, P from fov)",
        ),
        _c(
            "pointcloud",
            SIM_TO_ROS,
            ["sensor_msgs/PointCloud2"],
            PUBLISH,
            "pointcloud",
            "pointcloud",
            "sim Lidar -> PointCloud2 with x, y, z, intensity, segmentation",
        ),
        _c(
            "radar_scan",
            SIM_TO_ROS,
            ["radar_msgs/RadarScan"],
            PUBLISH,
            "radar",
            "radar_scan",
            "sim RadarDetection -> RadarScan (range, azimuth, elevation, doppler, amplitude dB from rcs)",
        ),
        _c(
            "radar_tracks",
            SIM_TO_ROS,
            ["radar_msgs/RadarTracks"],
            PUBLISH,
            "radar",
            "radar_tracks",
            "sim RadarTrack -> RadarTracks (uuid from id, position, velocity, acceleration)",
        ),
        _c(
            "clock",
            SIM_TO_ROS,
            ["rosgraph_msgs/Clock"],
            PUBLISH,
            "clock",
            "clock",
            "any stamped sim message -> Clock at its sim time",
        ),
        _c("imu", SIM_TO_ROS, ["sensor_msgs/Imu"], PUBLISH, "instruments", "imu", "sim IMU -> Imu"),
        _c(
            "gps",
            SIM_TO_ROS,
            ["sensor_msgs/NavSatFix"],
            PUBLISH,
            "instruments",
            "gps",
            "sim GPS -> NavSatFix",
        ),
        _c(
            "barometer",
            SIM_TO_ROS,
            ["sensor_msgs/FluidPressure"],
            PUBLISH,
            "instruments",
            "barometer",
            "sim Barometer -> FluidPressure (Pa)",
        ),
        _c(
            "magnetometer",
            SIM_TO_ROS,
            ["sensor_msgs/MagneticField"],
            PUBLISH,
            "instruments",
            "magnetometer",
            "sim Magnetometer (gauss) -> MagneticField (tesla)",
        ),
        _c(
            "distance",
            SIM_TO_ROS,
            ["sensor_msgs/Range"],
            PUBLISH,
            "instruments",
            "distance",
            "sim DistanceSensor -> Range",
        ),
        _c(
            "battery",
            SIM_TO_ROS,
            ["sensor_msgs/BatteryState"],
            PUBLISH,
            "instruments",
            "battery",
            "sim Battery -> BatteryState",
        ),
        _c(
            "airspeed",
            SIM_TO_ROS,
            ["sensor_msgs/FluidPressure"],
            PUBLISH,
            "instruments",
            "airspeed",
            "sim Airspeed (differential pressure) -> FluidPressure (Pa)",
        ),
        _c(
            "streaming_image",
            SIM_TO_ROS,
            ["sensor_msgs/Image"],
            STREAM,
            "image",
            "image",
            "the active streaming camera's scene image (the engine follows switch_view)",
        ),
        # --- ROS -> simulator ----------------------------------------------------------------
        _c(
            "cmd_vel",
            ROS_TO_SIM,
            ["geometry_msgs/Twist"],
            CALL,
            "command",
            "cmd_vel",
            "Twist -> MoveByVelocityBodyFrame (or MoveByVelocity) params, with limits and a watchdog",
        ),
        _c(
            "desired_pose",
            ROS_TO_SIM,
            ["geometry_msgs/PoseStamped"],
            SEND,
            "command",
            "desired_pose",
            "PoseStamped -> sim desired_pose message (robot teleport)",
        ),
        _c(
            "camera_desired_pose",
            ROS_TO_SIM,
            ["geometry_msgs/PoseStamped"],
            CALL,
            "command",
            "camera_desired_pose",
            "PoseStamped -> camera SetPose params with wait_for_pose_update",
            after="remember_camera_pose",
        ),
        _c(
            "load_scene",
            ROS_TO_SIM,
            ["std_msgs/String"],
            ACTION,
            "command",
            "load_scene",
            "String scene file name -> the engine loads it from --simconfigpath",
            action="load_scene",
        ),
        _c(
            "trigger",
            ROS_TO_SIM,
            ["std_srvs/Trigger", "std_srvs/Empty"],
            SERVE,
            "command",
            "trigger",
            "service request -> sim service call with the rule's fixed params; reply from its result",
        ),
        _c(
            "reset_pose",
            ROS_TO_SIM,
            ["std_srvs/Trigger", "std_srvs/Empty"],
            SERVE,
            "reset",
            "reset_pose",
            "service request -> robot SetPose params that return it to its scene origin, at rest",
        ),
        _c(
            "trigger_all",
            ROS_TO_SIM,
            ["std_srvs/Trigger"],
            SERVE_ALL,
            "command",
            "trigger",
            "Trigger -> the robot method params.method on every robot of the scene (sim: the robots prefix)",
        ),
        _c(
            "set_bool",
            ROS_TO_SIM,
            ["std_srvs/SetBool"],
            SERVE,
            "command",
            "set_bool",
            "SetBool request -> sim service call with the bool as the rule's param",
        ),
        _c(
            "switch_view",
            ROS_TO_SIM,
            ["std_srvs/Trigger"],
            SERVE,
            "command",
            "trigger",
            "Trigger -> SwitchStreamingView, and the streaming image follows the next camera",
            after="next_streaming_camera",
        ),
    )
}


def find(name: str) -> ConverterInfo | None:
    return CONVERTERS.get(name)


DIRECTION_LABELS = {SIM_TO_ROS: "sim → ROS", ROS_TO_SIM: "ROS → sim"}
TABLE_HEADERS = ("converter", "direction", "ROS types", "what it does")


def markdown_table(converters: Iterable[ConverterInfo] | None = None) -> str:
    """The converters (default: the whole catalogue, in its order) as a Markdown table, one row each."""
    rows = [
        (
            f"`{info.name}`",
            DIRECTION_LABELS[info.direction],
            ", ".join(f"`{t}`" for t in info.ros_types),
            info.summary.replace("|", "\\|"),
        )
        for info in (CONVERTERS.values() if converters is None else converters)
    ]
    lines = ["| " + " | ".join(TABLE_HEADERS) + " |", "|" + "---|" * len(TABLE_HEADERS)]
    return "\n".join(lines + ["| " + " | ".join(row) + " |" for row in rows]) + "\n"
