"""The bench's replay server keeps its render cache where the rendering happens: in its own process."""

from __future__ import annotations

from airsim_mapper.simserver.render import camera_model, rendering
from airsim_mapper.simserver.render.camera_model import RenderRequest
from airsim_mapper.simserver.sensors import lidar_model
from tools.bench import replay_server


def test_the_replay_server_renders_in_its_own_process_with_the_cache(monkeypatch) -> None:
    seen: list[list[str]] = []
    monkeypatch.setattr(replay_server, "server_main", lambda argv: seen.append(list(argv)) or 0)
    # install_replay's patches, undone after the test
    monkeypatch.setattr(rendering, "render", rendering.render)
    monkeypatch.setattr(lidar_model.LidarModel, "scan", lidar_model.LidarModel.scan)
    assert replay_server.main(["--topicsport", "1"]) == 0
    # a render worker is a child process without the cache: 1080p would be ray cast for real (8 Hz)
    assert seen == [["--topicsport", "1", "--render-in-process"]]
    assert rendering.render.__name__ == "render" and rendering.render.__qualname__.startswith("cached_render")


def test_the_render_cache_takes_a_render_request_and_renders_each_size_once(monkeypatch) -> None:
    calls: list[tuple] = []

    def real(world, request):
        calls.append((request.width, request.height, request.max_depth_vis))
        pixels = bytes(request.width * request.height * 3)
        return {0: camera_model.RenderedImage("BGR", request.width, request.height, pixels)}

    render = replay_server.cached_render(real)
    for _ in range(3):  # as CameraStream calls it: with the depth-visualisation range after the types
        frames = render(None, RenderRequest(None, None, 1920, 1080, 90.0, [0], 100.0))
    assert calls == [(320, 180, 100.0)]  # once, at a sixth of the size (under 320x240)
    image = frames[0]
    assert (image.width, image.height, len(image.data)) == (1920, 1080, 1920 * 1080 * 3)


def test_the_scan_cache_replays_one_rotation_a_ticks_worth_at_a_time() -> None:
    import numpy as np

    calls = []

    def real(model, world, position, orientation, start_ns, end_ns):
        calls.append(end_ns - start_ns)
        n = np.arange(100)
        return {
            "point_cloud": np.repeat(n, 3).astype(np.float32),
            "segmentation_cloud": n.astype(np.int32),
            "intensity_cloud": n.astype(np.float32),
            "laser_index_cloud": n.astype(np.int32),
            "azimuth_elevation_range_cloud": np.zeros(0, dtype=np.float32),
        }

    model = type("Model", (), {"rotation_hz": 10.0})()
    scan = replay_server.cached_scan(real)
    tenth = [scan(model, None, None, None, t, t + 10_000_000) for t in range(0, 120_000_000, 10_000_000)]
    assert calls == [100_000_000]  # one rotation cast, once
    assert [s["segmentation_cloud"].tolist() for s in tenth[:2]] == [list(range(10)), list(range(10, 20))]
    assert tenth[10]["segmentation_cloud"].tolist() == list(range(10))  # round again
    assert tenth[3]["point_cloud"].tolist() == np.repeat(np.arange(30, 40), 3).tolist()
