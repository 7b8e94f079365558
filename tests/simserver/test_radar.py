"""Radar: detections of known objects (range, angles, radial velocity), masks, stable track ids."""

from __future__ import annotations

import math

import numpy as np
import pytest
from simconfigs import EXAMPLES, PROJECT, both_configs, robot_sensors

from airsim_mapper.common.geometry import quat_from_rpy
from airsim_mapper.simserver.sensors.radar_model import RadarError, RadarModel
from airsim_mapper.simserver.world.world import World
from airsim_mapper.simserver.world.world_file import load_world

FACING_EAST = quat_from_rpy(0.0, 0.0, math.pi / 2)
STILL = np.zeros(3)
# static radar masts: +-0.785 rad in azimuth, +-0.524 in elevation, 1 m range cells, one mask each
TOWER_ROBOT = {PROJECT: "robot_radar_tower.jsonc", EXAMPLES: "radar_tower.jsonc"}
# what each radar's config says: range-max, rcs-adjust-factor, track-interval, mask elevations, mount
EXPECTED_MODEL = {
    PROJECT: (300.0, 0.2, 0.25, (-0.6, -0.3), [0.5, 0.0, 0.0]),
    EXAMPLES: (500.0, 0.1, 0.2, (-0.8, -0.2), [0.6, 0.0, 0.0]),
}


@pytest.fixture(scope="module")
def world() -> World:
    return load_world()


@pytest.fixture(scope="module", params=both_configs())
def real_tower_radar(request: pytest.FixtureRequest) -> tuple[str, dict]:
    """The project's radar mast, and the example radar tower where present."""
    return request.param, next(s for s in robot_sensors(request.param, TOWER_ROBOT) if s["type"] == "radar")


@pytest.fixture
def tower_radar(real_tower_radar) -> dict:
    return dict(real_tower_radar[1])


@pytest.fixture
def radar(tower_radar) -> RadarModel:
    """The radar of a real radar tower config."""
    return RadarModel.from_config(tower_radar)


def ball_detection(world: World, detections: list[dict], radar: RadarModel) -> dict:
    rcs = math.pi * radar.rcs_adjust_factor  # the ball's radius is 1 m
    found = [d for d in detections if d["rcs_sqm"] == pytest.approx(rcs)]
    assert len(found) == 1, detections
    return found[0]


def test_the_model_reads_the_real_radar_config(real_tower_radar):
    source, config = real_tower_radar
    range_max, rcs_adjust, track_interval, mask_elevation, mount = EXPECTED_MODEL[source]
    radar = RadarModel.from_config(config)
    assert (radar.azimuth_min, radar.azimuth_max) == (-0.785, 0.785)
    assert (radar.elevation_min, radar.elevation_max) == (-0.524, 0.524)
    assert radar.range_max == range_max and radar.range_resolution == 1.0
    assert radar.rcs_adjust_factor == rcs_adjust and radar.track_interval == track_interval
    assert len(radar.masks) == 1 and radar.masks[0].bounds["elevation"] == mask_elevation
    assert np.allclose(radar.mount_position, mount)


def test_a_ball_dead_ahead_is_detected_at_its_surface_range_with_zero_angles(world, radar):
    # ball centre (20, 20, -3), radius 1; radar 10 m west of it, facing east
    detections = radar.detect(world, np.array([20.0, 10.0, -3.0]), FACING_EAST, STILL, 0)
    ball = ball_detection(world, detections, radar)
    assert ball["range"] == pytest.approx(9.0)
    assert ball["azimuth"] == pytest.approx(0.0, abs=1e-6)
    assert ball["elevation"] == pytest.approx(0.0, abs=1e-6)
    assert ball["velocity"] == 0.0
    assert set(ball) == {"range", "azimuth", "elevation", "velocity", "rcs_sqm"}


def test_an_object_right_and_above_has_positive_azimuth_and_elevation(world, radar):
    position = np.array([25.0, 8.0, -1.0])  # ball is 12 m east, 5 m south (right), 2 m above
    ball = ball_detection(world, radar.detect(world, position, FACING_EAST, STILL, 0), radar)
    forward, right, down = 12.0, 5.0, -2.0
    distance = math.sqrt(forward**2 + right**2 + down**2)
    assert ball["azimuth"] == pytest.approx(math.atan2(right, forward), abs=1e-6)
    assert ball["elevation"] == pytest.approx(math.asin(-down / distance), abs=1e-6)
    assert ball["range"] == pytest.approx(round(distance - 1.0), abs=1e-9)


def test_radial_velocity_is_negative_when_closing_and_positive_when_opening(world, radar):
    position = np.array([20.0, 10.0, -3.0])
    closing = ball_detection(
        world, radar.detect(world, position, FACING_EAST, np.array([0, 4.0, 0]), 0), radar
    )
    opening = ball_detection(
        world, radar.detect(world, position, FACING_EAST, np.array([0, -4.0, 0]), 0), radar
    )
    sideways = ball_detection(
        world, radar.detect(world, position, FACING_EAST, np.array([3.0, 0, 0]), 0), radar
    )
    assert closing["velocity"] == -4.0 and opening["velocity"] == 4.0
    assert sideways["velocity"] == 0.0


def test_objects_outside_the_field_of_view_or_range_are_not_detected(world, tower_radar):
    radar = RadarModel.from_config(tower_radar)
    facing_west = quat_from_rpy(0.0, 0.0, -math.pi / 2)
    behind = radar.detect(world, np.array([20.0, 10.0, -3.0]), facing_west, STILL, 0)
    assert all(d["rcs_sqm"] != pytest.approx(math.pi * radar.rcs_adjust_factor) for d in behind)
    short = RadarModel.from_config(tower_radar | {"range-max": 5.0})
    assert short.detect(world, np.array([20.0, 10.0, -3.0]), FACING_EAST, STILL, 0) == []


def test_the_ground_gives_no_returns(world, radar):
    looking_down = quat_from_rpy(0.0, -0.4, math.pi)  # over open ground, south, pitched down
    assert radar.detect(world, np.array([-40.0, 40.0, -10.0]), looking_down, STILL, 0) == []


def test_a_mask_suppresses_detections_inside_all_of_its_bounds(world, tower_radar):
    position = np.array([20.0, 10.0, -3.0])
    mask = {"range-min": 5.0, "range-max": 12.0, "velocity-min": -1.0, "velocity-max": 1.0}
    masked = RadarModel.from_config(tower_radar | {"masks": [mask]})
    assert all(d["range"] > 12.0 for d in masked.detect(world, position, FACING_EAST, STILL, 0))
    # moving faster than the mask's velocity bound brings the ball back
    moving = masked.detect(world, position, FACING_EAST, np.array([0.0, 3.0, 0.0]), 0)
    assert any(d["range"] == 9.0 for d in moving)


def test_tracks_keep_their_ids_across_calls_and_estimate_the_object_centre(world, radar):
    position = np.array([25.0, 8.0, -1.0])  # as above: ball 12 m ahead, 5 m right, 2 m up
    first = radar.track(world, position, FACING_EAST, STILL, 0)
    second = radar.track(world, position, FACING_EAST, np.array([0.0, 2.0, 0.0]), 200_000_000)
    assert len(first) >= 2
    ids_first = {round(t["range_est"], 3): t["id"] for t in first}
    ids_second = {round(t["range_est"], 3): t["id"] for t in second}
    assert ids_first == ids_second
    assert len(set(ids_first.values())) == len(first)
    ball = next(t for t in second if t["rcs_sqm"] == pytest.approx(math.pi * radar.rcs_adjust_factor))
    assert ball["position_est"] == pytest.approx({"x": 12.0, "y": 5.0, "z": -2.0})
    assert ball["range_est"] == pytest.approx(math.sqrt(173.0))
    assert ball["azimuth_est"] == pytest.approx(math.atan2(5.0, 12.0))
    assert ball["elevation_est"] == pytest.approx(math.asin(2.0 / math.sqrt(173.0)))
    assert ball["velocity_est"] == pytest.approx({"x": -2.0, "y": 0.0, "z": 0.0}, abs=1e-9)
    assert ball["accel_est"] == pytest.approx({"x": -10.0, "y": 0.0, "z": 0.0}, abs=1e-9)
    keys = {"id", "azimuth_est", "elevation_est", "range_est", "position_est", "velocity_est", "accel_est"}
    assert set(ball) == keys | {"rcs_sqm"}


def test_an_object_seen_again_later_keeps_its_id_and_new_objects_get_new_ids(world, radar):
    east = np.array([20.0, 10.0, -3.0])
    first = {t["id"] for t in radar.track(world, east, FACING_EAST, STILL, 0)}
    facing_north = quat_from_rpy(0.0, 0.0, 0.0)
    other = {t["id"] for t in radar.track(world, np.array([20.0, 0.0, -5.0]), facing_north, STILL, 10**8)}
    again = {t["id"] for t in radar.track(world, east, FACING_EAST, STILL, 2 * 10**8)}
    assert again == first
    assert other and other.isdisjoint(first)


@pytest.mark.parametrize(
    ("override", "message"),
    [
        (
            {"fov": {"azimuth-min": 0.5, "azimuth-max": 0.5}},
            "radar 'radar1': 'fov.azimuth-min' must be below 'fov.azimuth-max'",
        ),
        (
            {"fov": {"elevation-resolution": 0}},
            "radar 'radar1': 'fov.elevation-resolution' must be positive, got 0",
        ),
        ({"range-max": -1}, "radar 'radar1': 'range-max' must be positive, got -1"),
        ({"fov": []}, "radar 'radar1': 'fov' must be a mapping, got []"),
        (
            {"masks": [{"range-min": "near"}]},
            "radar 'radar1': 'masks[0].range-min' must be a finite number, got 'near'",
        ),
        ({"masks": {}}, "radar 'radar1': 'masks' must be a list, got {}"),
    ],
)
def test_invalid_radar_configs_are_refused_naming_sensor_and_key(tower_radar, override, message):
    with pytest.raises(RadarError) as caught:
        RadarModel.from_config(tower_radar | override)
    assert str(caught.value) == message
