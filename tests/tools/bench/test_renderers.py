"""The bench's renderer section: a short real run of both renderers, its table and its targets."""

from __future__ import annotations

from tools.bench import renderers, results, targets


def test_a_short_run_measures_both_renderers_and_reports_them_side_by_side(monkeypatch):
    small = {name: (64, 48, types) for name, (_, _, types) in renderers.CASES.items()}
    monkeypatch.setattr(renderers, "CASES", small)
    results = renderers.run(gl_renders=3, raycast_renders=2)
    assert results["gl_renderer"] and "gl_error" not in results
    for engine in ("gl", "raycast"):
        assert set(results[engine]) == set(small)
        for figures in results[engine].values():
            assert figures["renders_per_s"] > 0 and figures["wall_ms"] > 0 and figures["cpu_ms"] >= 0
    table = renderers.table(results)
    assert all(name in table for name in small) and "GL/raycast" in table
    rows = [r for r in targets.targets({"costs": _costs(), "renderers": results}) if r["unit"] == "/s"]
    assert [r["limit"] for r in rows] == list(renderers.TARGETS.values())
    assert all(r["met"] == (r["value"] >= r["limit"]) for r in rows)


def test_targets_are_not_applicable_without_a_gl_context():
    results = {"gl": {}, "raycast": {}, "gl_error": "cannot create an OpenGL 4.1 context: no EGL"}
    assert {value for _, value, _ in renderers.targets(results)} == {None}


def _costs() -> dict:
    """The converter-cost entries targets.targets reads, with passing values."""
    lidar = {"bridge_ms": 1.0, "speedup_vs_reference": 20.0}
    return {
        results.LIDAR: lidar,
        results.DEPTH: {"bridge_ms": 1.0},
        results.BGR: {"ratio_to_bare_serialize": 1.0},
    }
