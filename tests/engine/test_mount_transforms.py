"""Camera and sensor frames as static mounts: sent once on /tf_static from the robot's frame, again after a
camera pose command, gone when the bridge stops; and map -> robot -> mount is exactly the frame the
per-pose converters give, in both conventions, for any robot pose."""

from __future__ import annotations

import numpy as np
import pytest
from fakes import FakeRos, FakeSimLink
from geometry_msgs.msg import PoseStamped
from harness import SIM_CONFIG

from airsim_mapper.common.geometry import q_mul, q_rotate
from airsim_mapper.convert import registry
from airsim_mapper.convert.pose import camera_pose_key
from airsim_mapper.engine.bridges import BridgeParts, MountTransform, SimToRos
from airsim_mapper.engine.hub import StreamHub
from airsim_mapper.engine.mounts import CameraMounts
from airsim_mapper.engine.runners import build
from airsim_mapper.mapping.expand import expand
from airsim_mapper.mapping.loader import load_mapping
from airsim_mapper.mapping.scene import read_scene

MOUNT_RULES = ("camera_tf", "camera_optical_tf", "lidar_tf", "radar_tf", "distance_tf")


def specs_of(mapping: str) -> dict:
    scene = read_scene(str(SIM_CONFIG), "scene_drone_sensors.jsonc")
    return {spec.name: spec for spec in expand(load_mapping(mapping), scene, "node", "")}


@pytest.fixture
def ros() -> FakeRos:
    return FakeRos()


@pytest.fixture
def services(ros: FakeRos) -> BridgeParts:
    sim = FakeSimLink()
    return BridgeParts(sim, StreamHub(sim, ros.send_tf), ros, CameraMounts(), lambda *_: None)


def robot_pose(seed: int) -> dict:
    rng = np.random.default_rng(seed)
    q = rng.normal(size=4)
    q /= np.linalg.norm(q)
    x, y, z = rng.uniform(-50, 50, 3)
    return {
        "time_stamp": 5_000_000_000,
        "position": {"x": float(x), "y": float(y), "z": float(z)},
        "orientation": dict(zip("wxyz", map(float, q))),
    }


def chained(robot: PoseStamped, mount) -> tuple[list[float], list[float]]:
    """map -> robot (a pose) followed by robot -> mount (a transform): the mount's world pose."""
    p, q = robot.pose.position, robot.pose.orientation
    rq = (q.w, q.x, q.y, q.z)
    t, r = mount.transform.translation, mount.transform.rotation
    offset = q_rotate(rq, (t.x, t.y, t.z))
    return [p.x + offset[0], p.y + offset[1], p.z + offset[2]], list(q_mul(rq, (r.w, r.x, r.y, r.z)))


def same_rotation(a, b) -> bool:
    return abs(abs(float(np.dot(a, b))) - 1.0) < 1e-9


@pytest.mark.parametrize("mapping", ["default", "enu"])
def test_every_mount_is_static_and_chains_to_the_per_pose_frame(mapping, services, ros):
    specs = specs_of(mapping)
    mounts = [spec for name, spec in specs.items() if name.split("[")[0] in MOUNT_RULES]
    assert {spec.name.split("[")[0] for spec in mounts} == set(MOUNT_RULES)
    robot_rule = next(spec for name, spec in specs.items() if name.startswith("actual_pose[Drone1"))
    for spec in mounts:
        bridge = build(spec, services)
        assert isinstance(bridge, MountTransform)
        bridge.start()
        sent = ros.static_transforms[spec.tf.child]
        assert (sent.header.frame_id, sent.child_frame_id) == (robot_rule.tf.child, spec.tf.child)
        assert spec.tf.parent == robot_rule.tf.child  # the robot's frame, which actual_pose moves
        for seed in range(20):
            message = robot_pose(seed)
            robot = registry.get("pose")(message, bridge.ctx)
            expected = bridge.convert(message, bridge.ctx).pose  # what the per-pose converter gives
            position, q = chained(robot, sent)
            e = expected.orientation
            assert position == pytest.approx([expected.position.x, expected.position.y, expected.position.z])
            assert same_rotation(q, (e.w, e.x, e.y, e.z)), spec.name
    assert not ros.transforms  # nothing on /tf: no pose message was needed


def test_a_camera_pose_command_sends_the_cameras_frames_again_and_stop_removes_them(services, ros):
    specs = specs_of("default")
    frame = next(spec for name, spec in specs.items() if name.startswith("camera_tf[Drone1/DownCamera/"))
    other = next(spec for name, spec in specs.items() if name.startswith("camera_tf[Drone1/Chase/"))
    bridge, unmoved = build(frame, services), build(other, services)
    bridge.start()
    unmoved.start()
    before = ros.static_transforms[other.tf.child]
    half_turn = (0.0, 0.0, 0.0, 1.0)  # w, x, y, z: 180 degrees about z
    services.mounts.set(
        camera_pose_key("Drone1", "DownCamera"), (np.array([0.5, 0.25, 0.1]), np.array(half_turn))
    )
    moved = ros.static_transforms[frame.tf.child].transform
    assert [moved.translation.x, moved.translation.y, moved.translation.z] == [0.5, 0.25, 0.1]
    assert abs(moved.rotation.z) == pytest.approx(1.0) and bridge.stats.messages == 2
    assert ros.static_transforms[other.tf.child] is before and unmoved.stats.messages == 1
    services.mounts.clear()  # the simulator restarted: the camera is back on its config origin
    assert ros.static_transforms[frame.tf.child].transform.translation.x != 0.5
    assert bridge.stats.messages == 3 and unmoved.stats.messages == 1
    bridge.stop()
    assert frame.tf.child not in ros.static_transforms
    services.mounts.set(camera_pose_key("Drone1", "DownCamera"), (np.zeros(3), np.array([1.0, 0, 0, 0])))
    assert frame.tf.child not in ros.static_transforms and bridge.stats.messages == 3


def test_the_pose_stream_feeds_no_camera_or_sensor_frame(services):
    """Per pose message only the robot's own bridges run (pose, tf, odometry, clock, camera poses), and
    without subscribers only the robot's pose and tf."""
    specs = specs_of("default")
    pose_topic = next(s.sim for n, s in specs.items() if n.startswith("actual_pose[Drone1"))
    fed = [
        name.split("[")[0]
        for name, spec in specs.items()
        if spec.sim == pose_topic and isinstance(build(spec, services), SimToRos)
    ]
    assert set(fed) == {"actual_pose", "camera_pose", "clock", "odometry"}
    eager = {
        name.split("[")[0] for name, spec in specs.items() if spec.sim == pose_topic and not spec.options.lazy
    }
    assert eager == {"actual_pose"}
