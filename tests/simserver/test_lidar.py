"""Lidar: the configured scan pattern, points on known surfaces, stateful azimuth, config errors."""

from __future__ import annotations

import math

import numpy as np
import pytest
from simconfigs import EXAMPLES, PROJECT, both_configs, robot_sensors

from airsim_mapper.common.geometry import quat_from_rpy, quat_to_matrix
from airsim_mapper.simserver.sensors.lidar_model import LidarError, LidarModel
from airsim_mapper.simserver.sensors.sensor_streams import LIDAR_MIN_SEGMENT_NS
from airsim_mapper.simserver.world.world import World
from airsim_mapper.simserver.world.world_file import load_world

LEVEL = np.array([1.0, 0.0, 0.0, 0.0])
TENTH_S = 100_000_000
# robot configs with a 16-channel lidar sweeping from the horizon straight down (6 degrees apart)
SURVEY_ROBOT = {
    PROJECT: "robot_quadrotor_survey.jsonc",
    EXAMPLES: "robot_quadrotor_fastphysics_sensors.jsonc",
}
# what each lidar's config says: channels, range (m), points per second, rotation (Hz), mount (m)
EXPECTED_MODEL = {
    PROJECT: (16, 90.0, 80000, 10, [0.0, 0.0, 0.15]),
    EXAMPLES: (16, 100.0, 100000, 10, [0.0, 0.0, 0.2]),
}


@pytest.fixture(scope="module")
def world() -> World:
    return load_world()


@pytest.fixture(scope="module", params=both_configs())
def real_lidar_config(request: pytest.FixtureRequest) -> tuple[str, dict]:
    """The project's survey lidar, and the example sensor quadrotor's where present."""
    return request.param, next(s for s in robot_sensors(request.param, SURVEY_ROBOT) if s["type"] == "lidar")


@pytest.fixture
def lidar_config(real_lidar_config) -> dict:
    """A copy of a real lidar config: 16 channels from 0 to -90 deg, 10 Hz; the range and the points per
    second differ (90 m and 80k pts/s for the project's, 100 m and 100k pts/s for the example's)."""
    return dict(real_lidar_config[1])


def columns_per_rotation(config: dict) -> int:
    return int(config["points-per-second"]) // int(config["horizontal-rotation-frequency"]) // 16


def world_points(scan: dict, position, orientation) -> np.ndarray:
    local = scan["point_cloud"].reshape(-1, 3).astype(float)
    return local @ quat_to_matrix(orientation).T + position


def test_the_model_reads_the_real_config(real_lidar_config):
    source, config = real_lidar_config
    channels, range_m, points_per_second, rotation_hz, mount = EXPECTED_MODEL[source]
    model = LidarModel.from_config(config)
    assert model.channels == channels and model.range_m == range_m
    assert model.points_per_second == points_per_second and model.rotation_hz == rotation_hz
    assert np.allclose(model.elevations_deg, np.linspace(0.0, -90.0, 16))
    assert np.allclose(model.mount_position, mount)
    assert model.column_step_deg == pytest.approx(360 * rotation_hz * channels / points_per_second)


def test_one_rotation_fires_points_per_second_over_frequency_rays_in_column_order(world, lidar_config):
    model = LidarModel.from_config(lidar_config)
    position = np.array([-40.0, 40.0, -4.0])  # open ground, nothing around
    scan = model.scan(world, position, LEVEL, 0, TENTH_S)
    lasers = scan["laser_index_cloud"]
    columns = columns_per_rotation(lidar_config)
    counts = np.bincount(lasers, minlength=16)
    # every channel looking down by more than asin(4 / range) reaches the ground within range (90 m or more)
    assert (counts[1:] == columns).all()
    assert 0 < counts[0] < columns  # the horizontal channel reaches only the blocks, 46-82 m away
    assert scan["point_cloud"].dtype == np.float32 and scan["point_cloud"].size == 3 * lasers.size
    assert scan["intensity_cloud"].shape == scan["segmentation_cloud"].shape == lasers.shape
    assert scan["segmentation_cloud"].dtype == np.int32 and lasers.dtype == np.int32
    below = lasers[lasers > 0].reshape(columns, 15)
    assert (np.diff(below, axis=1) == 1).all()  # column after column, each with its channels in order


def test_ground_returns_lie_on_the_plane_z_zero_in_world_coordinates(world, lidar_config):
    model = LidarModel.from_config(lidar_config)
    position, orientation = np.array([-30.0, 30.0, -6.0]), quat_from_rpy(0.1, -0.05, 1.0)
    scan = model.scan(world, position, orientation, 0, TENTH_S)
    ground = scan["segmentation_cloud"] == world.ground_segmentation_id
    assert ground.sum() > 5000
    assert np.allclose(world_points(scan, position, orientation)[ground, 2], 0.0, atol=1e-3)
    intensity = scan["intensity_cloud"]
    assert ((intensity >= 0) & (intensity <= 1)).all() and intensity.max() > 0.5


def test_box_returns_lie_on_the_visible_box_face(world, lidar_config):
    config = lidar_config | {"vertical-fov-upper-deg": 10.0, "vertical-fov-lower-deg": -10.0}
    model = LidarModel.from_config(config)
    position = np.array([20.0, 0.0, -5.0])  # 8 m south of BlockNorth's face x = 28
    scan = model.scan(world, position, LEVEL, 0, TENTH_S)
    on_block = scan["segmentation_cloud"] == world.object_named("BlockNorth").segmentation_id
    assert on_block.sum() > 100
    points = world_points(scan, position, LEVEL)[on_block]
    assert np.allclose(points[:, 0], 28.0, atol=1e-3)
    assert (np.abs(points[:, 1]) <= 4.0 + 1e-3).all()


def test_only_returns_within_range_are_reported(world, lidar_config):
    model = LidarModel.from_config(lidar_config | {"range": 10.0})
    scan = model.scan(world, np.array([-40.0, 40.0, -4.0]), LEVEL, 0, TENTH_S)
    distances = np.linalg.norm(scan["point_cloud"].reshape(-1, 3), axis=1)
    assert distances.max() <= 10.0 + 1e-4
    assert np.bincount(scan["laser_index_cloud"], minlength=16)[1] == 0  # -6 deg reaches ground at 38 m


def test_azimuth_elevation_range_follows_the_frame_conventions(world, lidar_config):
    model = LidarModel.from_config(lidar_config | {"report-azimuth-elevation-range": True})
    scan = model.scan(world, np.array([-40.0, 40.0, -4.0]), LEVEL, 0, TENTH_S)
    aer = scan["azimuth_elevation_range_cloud"].reshape(-1, 3)
    points = scan["point_cloud"].reshape(-1, 3)
    rng = np.linalg.norm(points, axis=1)
    assert np.allclose(aer[:, 2], rng, rtol=1e-5)
    assert np.allclose(np.sin(aer[:, 0]), np.sin(np.arctan2(points[:, 1], points[:, 0])), atol=1e-4)
    assert np.allclose(aer[:, 1], np.arcsin(-points[:, 2] / rng), atol=1e-4)
    elevations = np.degrees(np.unique(aer[:, 1]))
    assert np.allclose(np.sort(elevations), np.sort(np.linspace(0, -90, 16)), atol=1e-4)


def test_azimuth_is_state_so_two_half_scans_continue_one_another(world, lidar_config):
    config = lidar_config | {"report-azimuth-elevation-range": True}
    whole = LidarModel.from_config(config).scan(world, np.array([-40.0, 40.0, -4.0]), LEVEL, 0, TENTH_S)
    model = LidarModel.from_config(config)
    first = model.scan(world, np.array([-40.0, 40.0, -4.0]), LEVEL, 0, TENTH_S // 2)
    due = columns_per_rotation(config) / 2  # 250 columns (project) or 312.5 (example) in half a scan
    assert model.azimuth_deg == pytest.approx(math.floor(due) * model.column_step_deg)
    second = model.scan(world, np.array([-40.0, 40.0, -4.0]), LEVEL, TENTH_S // 2, TENTH_S)
    joined = np.concatenate([first["azimuth_elevation_range_cloud"], second["azimuth_elevation_range_cloud"]])
    assert np.allclose(joined, whole["azimuth_elevation_range_cloud"], atol=1e-5)
    azimuths = np.degrees(first["azimuth_elevation_range_cloud"].reshape(-1, 3)[:, 0]) % 360
    assert azimuths.max() <= 180.0 + 1e-4  # half a turn: the first half of the circle


def test_a_fraction_of_a_column_is_carried_to_the_next_scan(world):
    model = LidarModel.from_config(
        {
            "number-of-channels": 1,
            "points-per-second": 500,
            "vertical-fov-upper-deg": -45,
            "vertical-fov-lower-deg": -45,
        }
    )
    position = np.array([-40.0, 40.0, -4.0])
    sizes = [
        model.scan(world, position, LEVEL, t, t + 1_000_000)["laser_index_cloud"].size
        for t in range(0, 4_000_000, 1_000_000)
    ]
    assert sizes == [0, 1, 0, 1]  # half a column per millisecond


def test_the_horizontal_field_of_view_limits_the_azimuths(world, lidar_config):
    config = lidar_config | {"horizontal-fov-start-deg": 0.0, "horizontal-fov-end-deg": 90.0}
    config["report-azimuth-elevation-range"] = True
    scan = LidarModel.from_config(config).scan(world, np.array([-40.0, 40.0, -4.0]), LEVEL, 0, TENTH_S)
    azimuths = np.degrees(scan["azimuth_elevation_range_cloud"].reshape(-1, 3)[:, 0])
    assert azimuths.size > 0 and azimuths.min() >= 0.0 and azimuths.max() <= 90.0 + 1e-6
    points = scan["point_cloud"].reshape(-1, 3)
    assert (points[:, 0] >= -1e-3).all() and (points[:, 1] >= -1e-3).all()  # forward-right quadrant


def test_no_time_elapsed_gives_an_empty_scan(world, lidar_config):
    scan = LidarModel.from_config(lidar_config).scan(world, np.array([0.0, 0.0, -4.0]), LEVEL, 5, 5)
    assert all(v.size == 0 for v in scan.values())


@pytest.mark.parametrize(
    ("override", "message"),
    [
        ({"number-of-channels": 0}, "lidar 'lidar1': 'number-of-channels' must be an integer >= 1, got 0"),
        ({"range": 0}, "lidar 'lidar1': 'range' must be greater than 0, got 0"),
        (
            {"points-per-second": "many"},
            "lidar 'lidar1': 'points-per-second' must be a finite number, got 'many'",
        ),
        (
            {"vertical-fov-upper-deg": -20.0, "vertical-fov-lower-deg": 10.0},
            "lidar 'lidar1': 'vertical-fov-lower-deg' (10) is above 'vertical-fov-upper-deg' (-20)",
        ),
        (
            {"horizontal-fov-start-deg": 90.0, "horizontal-fov-end-deg": 90.0},
            "lidar 'lidar1': 'horizontal-fov-end-deg' (90) must be greater than "
            "'horizontal-fov-start-deg' (90)",
        ),
    ],
)
def test_invalid_lidar_configs_are_refused_naming_sensor_and_key(lidar_config, override, message):
    with pytest.raises(LidarError) as caught:
        LidarModel.from_config(lidar_config | override)
    assert str(caught.value) == message


def test_the_mount_orientation_is_read_from_the_origin(lidar_config):
    model = LidarModel.from_config(lidar_config | {"origin": {"xyz": "0 0 0", "rpy-deg": "0 0 90"}})
    assert np.allclose(model.mount_orientation, quat_from_rpy(0, 0, math.pi / 2))


class EverythingSubscribed:
    """The part of TopicHub a lidar stream uses: every topic subscribed, publishes kept."""

    def __init__(self) -> None:
        self.published: list[dict] = []

    def is_subscribed(self, _path: str) -> bool:
        return True

    def publish(self, _path: str, message: dict) -> None:
        self.published.append(message)


def lidar_stream(world, config: dict, step_ns: int = 3_000_000):
    from airsim_mapper.simserver.motion.motion import Body
    from airsim_mapper.simserver.scene.config import SensorSpec
    from airsim_mapper.simserver.sensors.sensor_streams import LidarStream

    body = Body(np.array([0.0, 0.0, -10.0]), LEVEL, lambda _p: 0.0)
    hub = EverythingSubscribed()
    sensor = SensorSpec("lidar1", "lidar", config, position=np.array([0.0, 0.0, 0.15]))
    return LidarStream(sensor, "/r/sensors/lidar1", body, world, hub, step_ns), hub


def assert_consistent(message: dict) -> int:
    n = message["segmentation_cloud"].size
    assert message["point_cloud"].size == 3 * n
    assert message["intensity_cloud"].size == message["laser_index_cloud"].size == n
    return n


def test_without_report_frequency_the_lidar_reports_each_ticks_segment(world, lidar_config):
    lidar_config.pop("report-frequency", None)
    stream, hub = lidar_stream(world, lidar_config)
    for k in range(1, 35):  # 34 ticks of 3 ms: just over a tenth of a second, a whole rotation's tenth
        assert stream.step(k * 3_000_000) is True
    assert stream.step(34 * 3_000_000) is False  # no new tick, no scan
    assert [m["time_stamp"] for m in hub.published] == [k * 3_000_000 for k in range(1, 35)]
    counts = [assert_consistent(m) for m in hub.published]
    columns = np.concatenate([m["laser_index_cloud"] for m in hub.published])
    # every return of the 102 ms swept (a ray looking down always hits the ground): 16 per column
    assert sum(counts) == columns.size <= 16 * columns_per_rotation(lidar_config) * 102 // 100 + 16
    assert max(counts) <= 16 * math.ceil(int(lidar_config["points-per-second"]) / 16 * 0.003)


def test_with_report_frequency_a_report_carries_every_segment_since_the_last(world, lidar_config):
    every, every_hub = lidar_stream(world, {k: v for k, v in lidar_config.items() if k != "report-frequency"})
    batched, batched_hub = lidar_stream(world, {**lidar_config, "report-frequency": 10})
    scans: list[dict] = []
    spans: list[tuple[int, int]] = []  # (start, end) of each scanned segment
    real_scan = batched.model.scan

    def scan(*args):
        spans.append((args[3], args[4]))
        scans.append(real_scan(*args))
        return scans[-1]

    batched.model.scan = scan
    for k in range(1, 70):
        every.step(k * 3_000_000)
        batched.step(k * 3_000_000)
    stamps = [m["time_stamp"] for m in batched_hub.published]
    assert stamps == [3_000_000, 105_000_000, 204_000_000]  # the first tick, then 10 Hz on average
    first, *later = [assert_consistent(m) for m in batched_hub.published]
    # the first report after subscribing covers a whole report period, as if it had been scanning before
    assert first > 20 * assert_consistent(every_hub.published[0])
    # between reports the segments are contiguous and span at least LIDAR_MIN_SEGMENT_NS, but the one a
    # report closes; the second report holds the segments after the first report, joined in order
    assert all(a[1] == b[0] for a, b in zip(spans, spans[1:]))
    closing = {i for i, (_, end) in enumerate(spans) if end in stamps}
    assert all(
        end - start >= LIDAR_MIN_SEGMENT_NS for i, (start, end) in enumerate(spans) if i not in closing
    )
    second = [i for i, (start, end) in enumerate(spans) if stamps[0] <= start and end <= stamps[1]]
    assert 5 <= len(second) <= 34 // 7 + 1  # 102 ms in segments of 7 ticks and the closing one
    assert np.array_equal(
        batched_hub.published[1]["point_cloud"], np.concatenate([scans[i]["point_cloud"] for i in second])
    )
    between = [assert_consistent(m) for m in every_hub.published if stamps[0] < m["time_stamp"] <= stamps[-1]]
    assert sum(later) == pytest.approx(sum(between), rel=0.01)  # the same sweep, batched
