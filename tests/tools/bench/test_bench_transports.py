"""The bench's image_transport rows and targets: each window's rate, latency, CPU per message and bytes,
the issue's rate targets, the JPEG converter against the library's own encode, pose p99 with a subscriber."""

from __future__ import annotations

from tools.bench import encoders, host, scenes, tables, targets, transports


def window(rates: dict[str, float], cores: float = 0.3) -> dict:
    topics = {
        name: {"rate_hz": rate, "latency_p50_ms": 5.0, "latency_p99_ms": 9.0, "message_bytes": 1000}
        for name, rate in rates.items()
    }
    return {"topics": topics, "bridge_cpu_cores": cores}


def test_the_rows_judge_the_rates_and_show_bytes_per_message():
    result = {
        "compressed": window({transports.compressed_topic(): 30.0, scenes.pose_topic(1): 100.0}),
        "compressed_depth": window({transports.depth_topic(): 12.0}),
    }
    raw = {
        "camera": window({scenes.image_topic(1): 30.0, scenes.pose_topic(1): 100.0}),
        "depth": window({"d": 30.0}),
    }
    lines = transports.table(result, raw).splitlines()
    assert lines[0].split()[:3] == ["image_transport,", "1080p", "@30"]
    assert lines[1].split() == [
        "compressed",
        "(JPEG",
        "q80)",
        "30.0",
        "5.00",
        "9.00",
        "10.00",
        "1000",
        "met",
        ">=",
        "29",
    ]
    assert lines[3].split()[-3:] == ["MISSED", ">=", "15"]
    assert [line.split()[0] for line in lines[4:]] == ["raw", "raw"]


def encoded(jpeg_ratio: float) -> dict:
    """The encoders' converter rows as `make bench` keeps them."""
    rows = {
        encoders.RAW: {"converter_ms": 1.0, "wire_bytes": 6220857},
        encoders.RAW_DEPTH: {"converter_ms": 2.0, "wire_bytes": 8294457},
        encoders.JPEG: {"converter_ms": 10.0 * jpeg_ratio, "library_ms": 10.0, "wire_bytes": 150000},
        encoders.PNG: {"converter_ms": 40.0, "library_ms": 39.0, "wire_bytes": 2500000},
        encoders.COMPRESSED_DEPTH: {"converter_ms": 30.0, "library_ms": 29.0, "wire_bytes": 900000},
    }
    for row in rows.values():
        if "library_ms" in row:
            row["ratio"] = row["converter_ms"] / row["library_ms"]
    return rows


def by_name(rows: list[dict]) -> dict[str, dict]:
    return {row["target"]: row for row in rows}


def test_the_jpeg_converter_is_judged_against_the_librarys_encode_with_the_bytes_of_every_transport():
    met = by_name(targets.transport_targets({"encoders": encoded(1.1)}))
    (row,) = met.values()
    assert row["target"].startswith("1080p JPEG encode CPU per frame / the library's own")
    assert (round(row["value"], 6), row["limit"], row["met"]) == (1.1, 1.2, True)
    for name, size in (("raw Image bgr8", 6220857), ("compressed jpeg", 150000), ("compressed png", 2500000)):
        assert f"{name} {size}" in row["note"]
    assert "compressedDepth 900000" in row["note"]
    (missed,) = targets.transport_targets({"encoders": encoded(1.3)})
    assert missed["met"] is False


def end_to_end(jpeg_hz: float, depth_hz: float, pose_p99: float) -> dict:
    pose = scenes.pose_topic(1)
    compressed = window({transports.compressed_topic(): jpeg_hz, pose: 100.0})
    compressed["topics"][pose]["latency_p99_ms"] = pose_p99
    floor = window({scenes.image_topic(1): 30.0, pose: 100.0})
    floor["topics"][pose]["latency_p99_ms"] = 10.0
    return {
        "transports": {
            "compressed": compressed,
            "compressed_depth": window({transports.depth_topic(): depth_hz}),
        },
        "bridge": {"camera": floor},
        "pose": {},
        "scale": {},
        "forwarder": {"camera": floor},
        "rounds": {
            "camera": [
                {"bridge": floor, "forwarder": floor_of(30.0)},
                {"bridge": floor, "forwarder": floor_of(12.0)},
            ]
        },
    }


def floor_of(pose_p99: float) -> dict:
    result = window({scenes.image_topic(1): 30.0, scenes.pose_topic(1): 100.0})
    result["topics"][scenes.pose_topic(1)]["latency_p99_ms"] = pose_p99
    return result


def test_the_compressed_rates_and_pose_p99_are_judged_with_the_raw_cameras_p99_limit():
    rows = by_name(targets.transport_targets({"e2e": end_to_end(29.5, 16.0, 7.0)}))
    jpeg = rows["1080p @30 BGR with a /compressed subscriber delivered"]
    depth = rows["1080p @30 depth with a /compressedDepth subscriber delivered"]
    pose = rows["pose p99 under a 1080p camera @30 with a /compressed subscriber / the forwarder's"]
    assert (jpeg["value"], jpeg["limit"], jpeg["met"]) == (29.5, 29.0, True)
    assert (depth["value"], depth["limit"], depth["met"]) == (16.0, 15.0, True)
    assert "16.0 Hz" in depth["note"] and "1000 bytes/msg" in depth["note"]
    # the forwarder's p99 is the median of its rounds under the raw camera: 10, 30 and 12 ms
    assert (pose["value"], pose["limit"], pose["met"]) == (7.0 / 12.0, targets.CAMERA_P99_RATIO, True)
    assert (
        pose["note"]
        == "bridge 7.00 ms, bare forwarder 12.00 ms (the median of its 3 rounds under the raw camera)"
    )
    missed = by_name(targets.transport_targets({"e2e": end_to_end(25.0, 12.0, 10.0)}))
    assert [row["met"] for row in missed.values()] == [False, False, False]


def test_a_costs_only_run_judges_the_encoder_alone_and_prints_it_among_the_targets():
    results = {"costs": {}, "encoders": encoded(1.0)}
    rows = targets.transport_targets(results)
    assert len(rows) == 1
    assert "1080p JPEG encode CPU per frame" in tables.targets_table(rows)


def test_the_converter_table_shows_every_transports_bytes():
    lines = encoders.converter_table(encoded(1.0)).splitlines()
    assert [line[:22].strip() for line in lines[1:]] == [
        "raw Image bgr8",
        "raw Image 32FC1",
        "compressed jpeg",
        "compressed png",
        "compressedDepth",
    ]
    assert lines[3].split()[-2:] == ["1.00", "150000"] and lines[1].split()[-1] == "6220857"


def test_a_bare_forwarder_under_the_compressed_rate_is_called_out_as_the_hosts():
    slow = end_to_end(25.0, 16.0, 7.0)
    slow["forwarder"]["camera"]["topics"][scenes.image_topic(1)]["rate_hz"] = 27.5
    warning = host.forwarder_under_compressed_rate(slow)
    assert warning is not None and "27.5 Hz, under the 29 Hz" in warning
    assert host.forwarder_under_compressed_rate(end_to_end(25.0, 16.0, 7.0)) is None
    assert host.forwarder_under_compressed_rate({}) is None
