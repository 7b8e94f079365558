"""The converter catalogue: every converter a mapping may name, with what it fits.

Pure data, importable without ROS, so that mapping validation can check a rule's converter against its
ROS type and direction. The implementation of each converter lives in the module named here and is
looked up by `airsim_mapper.convert.registry` at run time.

Contract of an implementation (see registry.py):
- sim_to_ros: ``fn(msg: dict, ctx: ConvertContext) -> ROS message`` (or None to publish nothing)
- ros_to_sim: ``fn(ros_msg, ctx: ConvertContext) -> dict`` (sim topic message or service params)
Converters raise ``ConversionError`` (airsim_mapper.convert.errors) for malformed input, nothing else.

Each entry also says how the engine runs the converter (`runner`, engine/bridges.py) and what follows a
successful simulator call (`after`), so the engine never tests converter names, and carries an example
message (`example`) that the property tests convert and then damage in every way they can.

The catalogue is the one source of the converters' names: the mapping schema's `converter` enum and the
table in `docs/converters.md` are generated from it (`python -m tools.catalogue`), and tests name any entry
either lacks. `markdown_table` renders the catalogue for people (`airsim-mapper converters` prints it).

Over 400 lines on purpose: it is one table, an entry of about a dozen lines per converter, and reads
better whole than split.
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping
from dataclasses import dataclass, field
from typing import Any

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
# What an image-encoding converter takes (`image_kind`): 8-bit colour/mono images, or float depth images
# (image_types.FLOAT_IMAGE_TYPES); the expansion refuses a bridge of it on the other kind.
COLOUR, FLOAT = "colour", "float"


@dataclass(frozen=True)
class Example:
    """A message the converter turns into a result, and the rule parameters and scene element it needs."""

    message: Mapping[str, Any]  # sim -> ROS: the simulator message; ROS -> sim: the ROS message's fields
    params: Mapping[str, Any] = field(default_factory=dict)  # the rule's params
    source: Mapping[str, Any] = field(default_factory=dict)  # the scene element (robot actor, sensor, ...)


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
    example: Example | None = None  # what the property tests start from (every entry has one)
    max_pixels: bool = False  # takes the rule's params.max_pixels and params.max_bytes (images)
    inline: bool = False  # light: a few fields in, one small message out; run on the receive thread
    events: bool = False  # the simulator sends one only when something happens: silence is no fault
    # params it cannot run without, with what each is
    required_params: Mapping[str, str] = field(default_factory=dict)
    # params with a fixed set of values: each value with the simulator method it goes with ("" for any)
    param_choices: Mapping[str, Mapping[str, str]] = field(default_factory=dict)
    # the only images it can encode: COLOUR (8-bit) or FLOAT (depth) image types; None: any
    image_kind: str | None = None

    @property
    def sim_kind(self) -> str:
        """What the rule's `sim` names: "topic", "service", or "node" (the engine supplies the source)."""
        return SIM_KINDS.get(self.runner, "node")


def _c(name, direction, ros_types, runner, module, function, summary, **more: Any) -> ConverterInfo:
    return ConverterInfo(name, direction, tuple(ros_types), runner, module, function, summary, **more)


def _e(message: Mapping[str, Any], **context: Any) -> Example:
    return Example(message, **context)


STAMP = {"time_stamp": 1}
# cmd_vel's params.frame, what the Twist's linear velocity is in (body, the default, first), with the
# simulator method that takes a velocity in that frame
VELOCITY_FRAMES = {"body": "MoveByVelocityBodyFrame", "world": "MoveByVelocity"}
POSE = {"position": {"x": 1.0, "y": 2.0, "z": 3.0}, "orientation": {"w": 1.0, "x": 0.0, "y": 0.0, "z": 0.0}}
ORIGIN = {"xyz": "1 2 -3", "rpy-deg": "0 0 90"}  # a robot actor's origin in a scene
# a 1x1 PNG of one black pixel, as the simulator sends a compressed colour image
PNG_1X1 = bytes.fromhex(
    "89504e470d0a1a0a0000000d4948445200000001000000010802000000907753de"
    "0000000a49444154081d63000200000400010d3ba4b90000000049454e44ae426082"
)


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
            inline=True,
            example=_e({**STAMP, **POSE}),
        ),
        _c(
            "camera_pose",
            SIM_TO_ROS,
            ["geometry_msgs/PoseStamped"],
            PUBLISH,
            "pose",
            "camera_pose",
            "robot actual_pose composed with the camera mount (and any camera pose command) -> camera pose",
            inline=True,
            example=_e({**STAMP, **POSE}),
        ),
        _c(
            "sensor_pose",
            SIM_TO_ROS,
            ["geometry_msgs/PoseStamped"],
            PUBLISH,
            "pose",
            "sensor_pose",
            "robot actual_pose composed with a sensor's config origin (lidar, radar, distance) -> its pose",
            inline=True,
            example=_e({**STAMP, **POSE}),
        ),
        _c(
            "camera_optical_pose",
            SIM_TO_ROS,
            ["geometry_msgs/PoseStamped"],
            PUBLISH,
            "pose",
            "camera_optical_pose",
            "as camera_pose, turned into the optical frame (z forward, x right, y down) for image frames",
            inline=True,
            example=_e({**STAMP, **POSE}),
        ),
        _c(
            "odometry",
            SIM_TO_ROS,
            ["nav_msgs/Odometry"],
            PUBLISH,
            "odometry",
            "odometry",
            "robot actual_pose -> Odometry; body-frame twist from successive poses (state in ctx.state)",
            inline=True,
            example=_e({**STAMP, **POSE}),
        ),
        _c(
            "collision",
            SIM_TO_ROS,
            ["geometry_msgs/PointStamped"],
            PUBLISH,
            "collision",
            "collision",
            "sim CollisionInfo -> PointStamped of the impact point (world frame)",
            inline=True,
            events=True,
            example=_e({**STAMP, "object_name": "x", "impact_point": {"x": 1.0, "y": 2.0, "z": 3.0}}),
        ),
        _c(
            "image",
            SIM_TO_ROS,
            ["sensor_msgs/Image"],
            PUBLISH,
            "image",
            "image",
            "sim Image (BGR, PNG, 16FC1, 16UC1, GRAY8) -> Image (bgr8, 32FC1 metres, mono8)",
            example=_e({**STAMP, "width": 2, "height": 1, "encoding": "BGR", "data": bytes(6)}),
            max_pixels=True,
        ),
        _c(
            "compressed_image",
            SIM_TO_ROS,
            ["sensor_msgs/CompressedImage"],
            PUBLISH,
            "compressed_image",
            "compressed_image",
            "sim Image sent as PNG (capture setting compress: true) -> CompressedImage of those bytes, "
            "format 'bgr8; png compressed bgr8' (image_transport's compressed transport)",
            example=_e({**STAMP, "width": 1, "height": 1, "encoding": "PNG", "data": PNG_1X1}),
            max_pixels=True,
        ),
        # image_transport's sibling topics, encoded here (convert/encoded_image.py)
        _c(
            "image_compressed",
            SIM_TO_ROS,
            ["sensor_msgs/CompressedImage"],
            PUBLISH,
            "encoded_image",
            "image_compressed",
            "sim colour Image -> CompressedImage as image_transport's compressed transport writes it: "
            "params.format jpeg (jpeg_quality, default 80) or png (png_level, default 9)",
            example=_e({**STAMP, "width": 2, "height": 1, "encoding": "BGR", "data": bytes(6)}),
            max_pixels=True,
            param_choices={"format": {"jpeg": "", "png": ""}},  # the default first
            image_kind=COLOUR,
        ),
        _c(
            "image_compressed_depth",
            SIM_TO_ROS,
            ["sensor_msgs/CompressedImage"],
            PUBLISH,
            "encoded_image",
            "image_compressed_depth",
            "sim depth Image -> CompressedImage as image_transport's compressedDepth transport writes it "
            "(quantised inverse depth in a 16-bit PNG: depth_max, depth_quantization, png_level)",
            example=_e({**STAMP, "width": 1, "height": 1, "encoding": "16FC1", "data": bytes(2)}),
            max_pixels=True,
            image_kind=FLOAT,
        ),
        _c(
            "camera_info",
            SIM_TO_ROS,
            ["sensor_msgs/CameraInfo"],
            PUBLISH,
            "camera_info",
            "camera_info",
            "sim Image (for its size and stamp) + capture settings -> CameraInfo (plumb_bob, K, P from fov)",
            example=_e({**STAMP, "width": 2, "height": 1}),
        ),
        _c(
            "pointcloud",
            SIM_TO_ROS,
            ["sensor_msgs/PointCloud2"],
            PUBLISH,
            "pointcloud",
            "pointcloud",
            "sim Lidar -> PointCloud2 with x, y, z, intensity, segmentation",
            example=_e(
                {
                    **STAMP,
                    "point_cloud": [1.0, 2.0, 3.0, 4.0, 5.0, 6.0],
                    "intensity_cloud": [0.5, 0.25],
                    "segmentation_cloud": [1, 2],
                }
            ),
        ),
        _c(
            "radar_scan",
            SIM_TO_ROS,
            ["radar_msgs/RadarScan"],
            PUBLISH,
            "radar",
            "radar_scan",
            "sim RadarDetection -> RadarScan (range, azimuth, elevation, doppler, amplitude dB from rcs)",
            example=_e(
                {
                    **STAMP,
                    "radar_detections": [
                        {"range": 1.0, "azimuth": 0.1, "elevation": 0.0, "velocity": 0.0, "rcs_sqm": 1.0}
                    ],
                }
            ),
        ),
        _c(
            "radar_tracks",
            SIM_TO_ROS,
            ["radar_msgs/RadarTracks"],
            PUBLISH,
            "radar",
            "radar_tracks",
            "sim RadarTrack -> RadarTracks (uuid from id, position, velocity, acceleration)",
            example=_e(
                {
                    **STAMP,
                    "radar_tracks": [
                        {
                            "id": 3,
                            "position_est": {"x": 1.0, "y": 0.0, "z": 0.0},
                            "velocity_est": {"x": 0.0, "y": 0.0, "z": 0.0},
                            "accel_est": {"x": 0.0, "y": 0.0, "z": 0.0},
                        }
                    ],
                }
            ),
        ),
        _c(
            "clock",
            SIM_TO_ROS,
            ["rosgraph_msgs/Clock"],
            PUBLISH,
            "clock",
            "clock",
            "any stamped sim message -> Clock at its sim time",
            inline=True,
            example=_e(STAMP),
        ),
        _c(
            "imu",
            SIM_TO_ROS,
            ["sensor_msgs/Imu"],
            PUBLISH,
            "instruments",
            "imu",
            "sim IMU -> Imu",
            inline=True,
            example=_e(
                {
                    **STAMP,
                    "orientation": {"w": 1.0, "x": 0.0, "y": 0.0, "z": 0.0},
                    "angular_velocity": {"x": 0.0, "y": 0.0, "z": 0.0},
                    "linear_acceleration": {"x": 0.0, "y": 0.0, "z": -9.8},
                }
            ),
        ),
        _c(
            "gps",
            SIM_TO_ROS,
            ["sensor_msgs/NavSatFix"],
            PUBLISH,
            "instruments",
            "gps",
            "sim GPS -> NavSatFix",
            inline=True,
            example=_e(
                {
                    **STAMP,
                    "latitude": 47.6,
                    "longitude": -122.1,
                    "altitude": 100.0,
                    "fix_type": 3,
                    "eph": 1.0,
                    "epv": 2.0,
                }
            ),
        ),
        _c(
            "barometer",
            SIM_TO_ROS,
            ["sensor_msgs/FluidPressure"],
            PUBLISH,
            "instruments",
            "barometer",
            "sim Barometer -> FluidPressure (Pa)",
            inline=True,
            example=_e({**STAMP, "pressure": 101325.0}),
        ),
        _c(
            "magnetometer",
            SIM_TO_ROS,
            ["sensor_msgs/MagneticField"],
            PUBLISH,
            "instruments",
            "magnetometer",
            "sim Magnetometer (gauss) -> MagneticField (tesla)",
            inline=True,
            example=_e(
                {
                    **STAMP,
                    "magnetic_field_body": {"x": 0.2, "y": 0.0, "z": 0.4},
                    "magnetic_field_covariance": [0.0] * 9,
                }
            ),
        ),
        _c(
            "distance",
            SIM_TO_ROS,
            ["sensor_msgs/Range"],
            PUBLISH,
            "instruments",
            "distance",
            "sim DistanceSensor -> Range",
            inline=True,
            example=_e({**STAMP, "current_distance": 3.0}),
        ),
        _c(
            "battery",
            SIM_TO_ROS,
            ["sensor_msgs/BatteryState"],
            PUBLISH,
            "instruments",
            "battery",
            "sim Battery -> BatteryState",
            inline=True,
            example=_e(
                {**STAMP, "battery_pct_remaining": 50.0, "battery_charge_state": "BATTERY_CHARGE_STATE_OK"}
            ),
        ),
        _c(
            "airspeed",
            SIM_TO_ROS,
            ["sensor_msgs/FluidPressure"],
            PUBLISH,
            "instruments",
            "airspeed",
            "sim Airspeed (differential pressure) -> FluidPressure (Pa)",
            inline=True,
            example=_e({**STAMP, "diff_pressure": 3.0}),
        ),
        _c(
            "streaming_image",
            SIM_TO_ROS,
            ["sensor_msgs/Image"],
            STREAM,
            "image",
            "image",
            "the active streaming camera's scene image (the engine follows switch_view)",
            example=_e({**STAMP, "width": 1, "height": 1, "encoding": "16FC1", "data": bytes(2)}),
            max_pixels=True,
        ),
        # --- ROS -> simulator ----------------------------------------------------------------
        _c(
            "cmd_vel",
            ROS_TO_SIM,
            ["geometry_msgs/Twist"],
            CALL,
            "command",
            "cmd_vel",
            "Twist -> MoveByVelocityBodyFrame params (or MoveByVelocity with params.frame world), with "
            "limits and a watchdog",
            param_choices={"frame": VELOCITY_FRAMES},  # the default first
            example=_e(
                {"linear": {"x": 1.0, "y": 0.0, "z": -0.5}, "angular": {"x": 0.0, "y": 0.0, "z": 0.2}}
            ),
        ),
        _c(
            "desired_pose",
            ROS_TO_SIM,
            ["geometry_msgs/PoseStamped"],
            SEND,
            "command",
            "desired_pose",
            "PoseStamped -> sim desired_pose message (robot teleport)",
            example=_e({"pose": POSE}),
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
            example=_e({"pose": POSE}),
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
            example=_e({"data": "scene_basic_drone.jsonc"}),
        ),
        _c(
            "trigger",
            ROS_TO_SIM,
            ["std_srvs/Trigger", "std_srvs/Empty"],
            SERVE,
            "command",
            "trigger",
            "service request -> sim service call with the rule's fixed params; reply from its result",
            example=_e({}),
        ),
        _c(
            "reset_pose",
            ROS_TO_SIM,
            ["std_srvs/Trigger", "std_srvs/Empty"],
            SERVE,
            "reset",
            "reset_pose",
            "service request -> robot SetPose params that return it to its scene origin, at rest",
            example=_e({}, source={"origin": ORIGIN}),
        ),
        _c(
            "trigger_all",
            ROS_TO_SIM,
            ["std_srvs/Trigger"],
            SERVE_ALL,
            "command",
            "trigger",
            "Trigger -> the robot method params.method on every robot of the scene (sim: the robots prefix)",
            example=_e({}, params={"method": "Hover"}),
            required_params={"method": "the robot method to call on every robot (e.g. Hover)"},
        ),
        _c(
            "set_bool",
            ROS_TO_SIM,
            ["std_srvs/SetBool"],
            SERVE,
            "command",
            "set_bool",
            "SetBool request -> sim service call with the bool as the rule's param",
            example=_e({"data": True}, params={"arg": "do_pause"}),
            required_params={"arg": "the simulator parameter that receives the bool (e.g. do_pause)"},
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
            example=_e({}),
        ),
    )
}


def find(name: str) -> ConverterInfo | None:
    return CONVERTERS.get(name)


DIRECTION_LABELS = {SIM_TO_ROS: "sim → ROS", ROS_TO_SIM: "ROS → sim"}
TABLE_HEADERS = ("converter", "direction", "ROS types", "runs on", "what it does")


def runs_on(info: ConverterInfo) -> str:
    """The thread a converter runs on (engine/streams.py): light ones on the receive thread."""
    if info.direction == ROS_TO_SIM:
        return "rospy's callback"
    return "receive thread" if info.inline else "its topic's worker"


def markdown_table(converters: Iterable[ConverterInfo] | None = None) -> str:
    """The converters (default: the whole catalogue, in its order) as a Markdown table, one row each."""
    rows = [
        (
            f"`{info.name}`",
            DIRECTION_LABELS[info.direction],
            ", ".join(f"`{t}`" for t in info.ros_types),
            runs_on(info),
            info.summary.replace("|", "\\|"),
        )
        for info in (CONVERTERS.values() if converters is None else converters)
    ]
    lines = ["| " + " | ".join(TABLE_HEADERS) + " |", "|" + "---|" * len(TABLE_HEADERS)]
    return "\n".join(lines + ["| " + " | ".join(row) + " |" for row in rows]) + "\n"
