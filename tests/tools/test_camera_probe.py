"""The camera probe runs the server's own camera path and reports its frame times in `make bench`."""

from __future__ import annotations

from tools import camera_probe
from tools.bench import results, targets

# the converter-cost entries targets.targets reads (passing values; not what this test is about)
COSTS = {
    results.LIDAR: {"bridge_ms": 1.0, "speedup_vs_reference": 20.0},
    results.DEPTH: {"bridge_ms": 1.0},
    results.BGR: {"ratio_to_bare_serialize": 1.0},
}


def test_a_short_probe_captures_delivers_every_type_and_reports_its_frame_times() -> None:
    result = camera_probe.run(seconds=1.5, hz=10.0, width=160, height=120)
    assert 3.0 <= result["captures_per_s"] <= 11.0  # 10 Hz asked, on a possibly busy machine
    assert len(result["delivered_hz"]) == 7 and result["delivered_min_hz"] > 0.0
    assert result["render_ms_p50"] > 0.0 and result["frame_ms_p50"] >= result["render_ms_p50"]
    assert result["server_cpu_ms_per_capture"] > 0.0 and result["worker_cpu_ms_per_capture"] > 0.0
    assert "delivered Hz: scene_camera" in camera_probe.table(result)
    rows = targets.targets({"costs": COSTS, "server_camera": result})
    row = next(r for r in rows if r["target"].startswith("camera 1280x720, all seven types"))
    assert row["value"] == result["delivered_min_hz"] and row["unit"] == "Hz"
