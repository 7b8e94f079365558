"""Lock-step stepping with the real client: with the scene paused, every step publishes each camera image
and lidar scan its time calls for, before the step's reply, so that no single step loses a frame."""

from __future__ import annotations

import time

from projectairsim import World

from simserver.clientkit import load_world, settle, subscribe

STEP_NS = 3_000_000  # scene_drone_sensors' clock step
CAMERA_PERIOD_NS = 50_000_000  # Chase: capture-interval 0.05
LIDAR_PERIOD_NS = 100_000_000  # lidar1: 10 Hz rotation


class Watch:
    """One stream's arrivals, checked after each step: a sample that was due has already been sent."""

    def __init__(self, inbox, period_ns: int, since_ns: int) -> None:
        self.inbox, self.period_ns = inbox, period_ns
        self.last = since_ns  # the newest sample seen (or when watching began: one is due within a period)

    def stamps(self) -> list[int]:
        return [m["time_stamp"] for m in self.inbox.messages]

    def after_step(self, now_ns: int) -> None:
        if now_ns - self.last >= self.period_ns + STEP_NS:
            # a sample was due by now: it must come (the client may still be reading it off the socket)
            newer = self.inbox.wait_for(where=lambda m: self.last < m["time_stamp"] <= now_ns, timeout=5.0)
            self.last = max(m["time_stamp"] for m in newer)
        elif self.inbox.messages:
            self.last = max(self.last, *self.stamps())

    def check_spacing(self) -> None:
        stamps = self.stamps()
        gaps = {b - a for a, b in zip(stamps, stamps[1:])}
        assert stamps == sorted(set(stamps)), "samples repeated or out of order"
        assert gaps and all(abs(g - self.period_ns) < STEP_NS for g in gaps), sorted(gaps)


def test_paused_stepping_never_loses_a_camera_image_or_lidar_scan(client):
    world: World = load_world(client, "scene_drone_sensors.jsonc")
    world.pause()
    sensors = f"{world.parent_topic}/robots/Drone1/sensors"
    start = world.get_sim_time()
    camera = Watch(subscribe(client, f"{sensors}/Chase/scene_camera"), CAMERA_PERIOD_NS, start)
    lidar = Watch(subscribe(client, f"{sensors}/lidar1/lidar"), LIDAR_PERIOD_NS, start)
    battery = subscribe(client, f"{sensors}/Battery/battery")
    settle(client, f"{world.parent_topic}/robots/Drone1/actual_pose")
    now = start
    for _ in range(200):
        now = world.continue_for_single_step(wait_until_complete=True)
        camera.after_step(now)
        lidar.after_step(now)
    assert now == start + 200 * STEP_NS
    # the battery publishes once per physics step, as the real sensor does
    steps = {start + k * STEP_NS for k in range(1, 201)}
    battery.wait_for(where=lambda m: m["time_stamp"] == now)
    assert steps <= {m["time_stamp"] for m in battery.messages}
    for n_steps in (2, 5, 7, 17, 33) * 4:
        before = now
        now = world.continue_for_n_steps(n_steps, wait_until_complete=True)
        assert now == before + n_steps * STEP_NS
        camera.after_step(now)
        lidar.after_step(now)
    assert world.is_paused() is True
    camera.check_spacing()
    lidar.check_spacing()
    assert len(camera.stamps()) >= (now - start) // (CAMERA_PERIOD_NS + STEP_NS)
    for message in camera.inbox.messages:  # every image was taken at a step's time
        assert (message["time_stamp"] - start) % STEP_NS == 0
    world.resume()


def test_paused_steps_publish_every_instrument_and_a_lidar_segment_per_physics_step(client):
    """Without `report-frequency` the lidar reports each step's segment, and every instrument publishes
    once per step, as the real server does."""
    import copy

    from simserver.clientkit import scene_config

    config = copy.deepcopy(scene_config("scene_drone_sensors.jsonc"))
    sensors_cfg = config["actors"][0]["robot-config"]["sensors"]
    next(s for s in sensors_cfg if s["id"] == "lidar1").pop("report-frequency")
    world = World(client)
    world.load_scene(config)
    world.pause()
    sensors = f"{world.parent_topic}/robots/Drone1/sensors"
    leaves = {
        "IMU1": "imu_kinematics",
        "GPS": "gps",
        "Barometer": "barometer",
        "Magnetometer": "magnetometer",
        "DistanceSensor": "distance_sensor",
        "Airspeed": "airspeed",
        "lidar1": "lidar",
    }
    inboxes = {sensor: subscribe(client, f"{sensors}/{sensor}/{leaf}") for sensor, leaf in leaves.items()}
    settle(client, f"{world.parent_topic}/robots/Drone1/actual_pose")
    start = world.get_sim_time()
    now = start
    for _ in range(30):
        now = world.continue_for_single_step(wait_until_complete=True)
    steps = {start + k * STEP_NS for k in range(1, 31)}
    for sensor, inbox in inboxes.items():
        inbox.wait_for(where=lambda m: m["time_stamp"] == now)
        assert steps <= {m["time_stamp"] for m in inbox.messages}, sensor
    scans = [m for m in inboxes["lidar1"].messages if m["time_stamp"] in steps]
    assert len(scans) == 30
    # 50,000 points/s over 16 channels: 9 or 10 columns of 16 rays in a 3 ms step (upward rays may miss);
    # the first step's segment also covers the time from the last free-running tick to the pause
    for scan in scans:
        n = len(scan["segmentation_cloud"])
        assert len(scan["point_cloud"]) == 3 * n and len(scan["laser_index_cloud"]) == n
    assert all(len(scan["segmentation_cloud"]) <= 10 * 16 for scan in scans[1:])
    assert sum(len(s["segmentation_cloud"]) for s in scans) > 0
    world.resume()


def test_a_subscription_after_a_paused_step_gets_that_steps_sample(client):
    """Subscribe and step go on different sockets, so a subscription can reach the server after the step
    it preceded: the sample it then gets is the step's own (sensors sample whether or not anyone
    listens), never an older one."""
    world: World = load_world(client, "scene_drone_sensors.jsonc")
    world.pause()
    now = world.continue_for_single_step(wait_until_complete=True)
    sensors = f"{world.parent_topic}/robots/Drone1/sensors"
    for topic in (
        "IMU1/imu_kinematics",
        "Airspeed/airspeed",
        "Battery/battery",
        "DistanceSensor/distance_sensor",
    ):
        first = subscribe(client, f"{sensors}/{topic}").wait_for(1, timeout=5.0)[0]
        assert first["time_stamp"] == now, topic
    # lidar1 reports at 10 Hz: its first sample is the newest report, a whole scan, made on subscription
    scan = subscribe(client, f"{sensors}/lidar1/lidar").wait_for(1, timeout=5.0)[0]
    assert now - LIDAR_PERIOD_NS - STEP_NS < scan["time_stamp"] <= now
    assert len(scan["segmentation_cloud"]) > 100 and len(scan["point_cloud"]) == 3 * len(
        scan["segmentation_cloud"]
    )
    world.resume()


def test_a_paused_clock_sends_no_pose_and_each_step_sends_one(client):
    world: World = load_world(client, "scene_drone_sensors.jsonc")
    world.pause()
    paused_at = world.get_sim_time()
    poses = subscribe(client, f"{world.parent_topic}/robots/Drone1/actual_pose")
    poses.wait_for(where=lambda m: m["time_stamp"] == paused_at)  # the pose of the paused state
    before = list(poses.messages)
    time.sleep(0.5)  # paused: no physics tick, no new pose (the free-running rate is 100 Hz)
    assert poses.messages == before
    steps = [world.continue_for_single_step(wait_until_complete=True) for _ in range(10)]
    poses.wait_for(where=lambda m: m["time_stamp"] == steps[-1])
    time.sleep(0.3)
    assert [m["time_stamp"] for m in poses.messages[len(before) :]] == steps  # one pose per step
