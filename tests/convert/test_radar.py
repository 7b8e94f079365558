"""Radar detections and tracks: amplitude in dB with a floor, REP-103 signs, uuid from id, covariances."""

from __future__ import annotations

import math

import pytest

from airsim_mapper.convert.context import ConvertContext
from airsim_mapper.convert.errors import ConversionError
from airsim_mapper.convert.radar import AMPLITUDE_FLOOR_DB, radar_scan, radar_tracks, track_uuid

CTX = ConvertContext(frame_id="airsim_node/Drone1/radar1")
POSE = {"position": {"x": 0, "y": 0, "z": 0}, "orientation": {"w": 1, "x": 0, "y": 0, "z": 0}}


def detection(rng=10.0, azimuth=0.1, elevation=0.2, velocity=-1.5, rcs=1.0):
    return {"range": rng, "azimuth": azimuth, "elevation": elevation, "velocity": velocity, "rcs_sqm": rcs}


def scan(*detections):
    return {"time_stamp": 5_000_000_000, "radar_detections": list(detections), "pose": POSE}


def track(track_id=7, position=(10.0, 2.0, -1.0), velocity=(1.0, -1.0, 0.5), accel=(0.0, 0.1, 0.2)):
    return {
        "id": track_id,
        "azimuth_est": 0.2,
        "elevation_est": 0.1,
        "range_est": 10.2,
        "position_est": dict(zip("xyz", position)),
        "velocity_est": dict(zip("xyz", velocity)),
        "accel_est": dict(zip("xyz", accel)),
        "rcs_sqm": 2.0,
    }


def tracks(*items):
    return {"time_stamp": 1, "radar_tracks": list(items), "pose": POSE}


def test_detections_become_returns_with_amplitude_in_db(roundtrip):
    msg = radar_scan(scan(detection(rcs=100.0), detection(rng=3.0, azimuth=-0.5, rcs=0.01)), CTX)
    first, second = msg.returns
    assert (first.range, first.azimuth, first.elevation, first.doppler_velocity) == (10.0, 0.1, 0.2, -1.5)
    assert first.amplitude == pytest.approx(20.0)
    assert second.amplitude == pytest.approx(-20.0)
    assert second.azimuth == -0.5
    assert msg.header.frame_id == CTX.frame_id and msg.header.stamp.secs == 5
    copy = roundtrip(msg)
    assert [r.range for r in copy.returns] == [10.0, 3.0]


@pytest.mark.parametrize("rcs", [0.0, -3.0])
def test_zero_or_negative_rcs_gives_the_floor_amplitude_instead_of_a_math_error(rcs):
    msg = radar_scan(scan(detection(rcs=rcs)), CTX)
    assert msg.returns[0].amplitude == pytest.approx(AMPLITUDE_FLOOR_DB)
    assert math.isfinite(msg.returns[0].amplitude)


def test_enu_flips_the_azimuth_sign_and_keeps_elevation():
    msg = radar_scan(scan(detection(azimuth=0.3, elevation=0.2)), ConvertContext(convention="enu"))
    assert msg.returns[0].azimuth == pytest.approx(-0.3)
    assert msg.returns[0].elevation == pytest.approx(0.2)


def test_empty_scan_has_no_returns():
    assert radar_scan(scan(), CTX).returns == []


def test_detection_missing_a_field_is_rejected():
    bad = detection()
    del bad["rcs_sqm"]
    with pytest.raises(ConversionError, match=r"radar_scan: radar_detections: an entry has no 'rcs_sqm'"):
        radar_scan(scan(bad), CTX)


def test_detection_with_nan_is_rejected():
    with pytest.raises(ConversionError, match=r"radar_scan: radar_detections: fields .* must be finite"):
        radar_scan(scan(detection(rng=float("nan"))), CTX)


def test_detection_with_a_string_value_is_rejected():
    with pytest.raises(ConversionError, match=r"radar_scan: radar_detections: fields .* must be numbers"):
        radar_scan(scan(detection(velocity="fast")), CTX)


def test_detections_that_are_not_a_list_are_rejected():
    with pytest.raises(ConversionError, match=r"radar_scan: radar_detections must be a list, got dict"):
        radar_scan({"time_stamp": 0, "radar_detections": {}}, CTX)


def test_tracks_carry_vectors_uuid_and_nominal_covariances(roundtrip):
    msg = radar_tracks(tracks(track()), CTX)
    (out,) = msg.tracks
    assert (out.position.x, out.position.y, out.position.z) == (10.0, 2.0, -1.0)
    assert (out.velocity.x, out.velocity.y, out.velocity.z) == (1.0, -1.0, 0.5)
    assert (out.acceleration.x, out.acceleration.y, out.acceleration.z) == (0.0, 0.1, 0.2)
    assert bytes(out.uuid.uuid) == bytes(15) + b"\x07"
    assert list(out.position_covariance) == [1.0, 0, 0, 1.0, 0, 1.0]
    assert list(out.velocity_covariance) == [0.25, 0, 0, 0.25, 0, 0.25]
    assert list(out.size_covariance) == [0.0] * 6
    assert (out.size.x, out.size.y, out.size.z) == (0.0, 0.0, 0.0)
    assert out.classification == out.NO_CLASSIFICATION
    copy = roundtrip(msg)
    assert bytes(copy.tracks[0].uuid.uuid) == bytes(15) + b"\x07"
    assert copy.tracks[0].position.x == 10.0


def test_track_uuid_is_reversible_and_handles_negative_ids():
    for value in (0, 1, -1, 2**63 - 1, -(2**63)):
        uuid = bytes(track_uuid(value).uuid)
        assert len(uuid) == 16
        assert int.from_bytes(uuid[8:], "big", signed=True) == value


def test_covariances_can_be_set_per_rule():
    ctx = ConvertContext(params={"position_variance": 4.0})
    assert list(radar_tracks(tracks(track()), ctx).tracks[0].position_covariance) == [4.0, 0, 0, 4.0, 0, 4.0]


def test_enu_tracks_are_in_flu():
    msg = radar_tracks(tracks(track()), ConvertContext(convention="enu"))
    p = msg.tracks[0].position
    assert (p.x, p.y, p.z) == (10.0, -2.0, 1.0)


def test_track_id_too_large_is_rejected():
    with pytest.raises(
        ConversionError, match=r"radar_tracks: id 18446744073709551616 does not fit in 64 bits"
    ):
        radar_tracks(tracks(track(track_id=2**64)), CTX)


def test_track_id_that_is_not_an_integer_is_rejected():
    with pytest.raises(ConversionError, match=r"radar_tracks: id must be an integer, got 1.5"):
        radar_tracks(tracks(track(track_id=1.5)), CTX)


def test_track_missing_a_vector_is_rejected():
    bad = track()
    del bad["accel_est"]
    with pytest.raises(ConversionError, match=r"radar_tracks: radar_tracks entry has no 'accel_est'"):
        radar_tracks(tracks(bad), CTX)


def test_track_vector_with_inf_is_rejected():
    with pytest.raises(ConversionError, match=r"radar_tracks: velocity_est: fields x, y, z must be finite"):
        radar_tracks(tracks(track(velocity=(float("inf"), 0.0, 0.0))), CTX)
