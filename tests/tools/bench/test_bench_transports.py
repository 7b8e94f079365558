"""The bench's image_transport rows: each window's rate, latency, CPU per message and bytes, with the
issue's rate targets judged."""

from __future__ import annotations

from tools.bench import scenes, transports


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
