"""The RViz screenshot tool: its X framebuffer decoding, its crash detection, and the whole pipeline live."""

from __future__ import annotations

import json
import os
import subprocess
import sys

import numpy as np
import pytest
from harness import ROOT

from tools.screenshot import images, rviz_config, watch

RADAR_FRAME = "airsim_node/Drone1/radar1"


def test_xwd_pixels_are_decoded_with_the_files_masks(tmp_path):
    rgb = np.zeros((2, 3, 3), np.uint8)
    rgb[0, 0], rgb[1, 2] = (255, 0, 0), (1, 2, 3)
    words = (rgb[..., 0].astype("<u4") << 16) | (rgb[..., 1].astype("<u4") << 8) | rgb[..., 2]
    # XWD 7 header (25 big-endian words), ZPixmap, 32 bpp, LSB-first pixels, 4 bytes/line of padding
    head = [104, 7, 2, 24, 3, 2, 0, 0, 32, 0, 32, 32, 16, 4, 0xFF0000, 0xFF00, 0xFF, 8, 0, 0, 3, 2, 0, 0, 0]
    body = np.zeros((2, 4), "<u4")
    body[:, :3] = words
    path = tmp_path / "screen.xwd"
    path.write_bytes(np.array(head, ">u4").tobytes() + b"name" + body.tobytes())
    assert (images.read_xwd(path) == rgb).all()


# -- end to end on the real stack -------------------------------------------------------------------------


@pytest.mark.live
def test_screenshot_pipeline_shows_live_data_in_rviz_and_stops_everything(tmp_path):
    from PIL import Image

    png, report_path = tmp_path / "rviz.png", tmp_path / "report.json"
    run = subprocess.run(
        [
            sys.executable,
            "-m",
            "tools.screenshot",
            "--out",
            str(png),
            "--report",
            str(report_path),
            "--settle",
            "3",
            "--away",
            "0",
            "--timeout",
            "180",
            "--keep",
            str(tmp_path / "logs"),
        ],
        cwd=ROOT,
        capture_output=True,
        text=True,
        timeout=400,
    )
    logs = "\n".join(
        f"--- {p.name}\n{p.read_text(errors='replace')[-3000:]}"
        for p in sorted((tmp_path / "logs").glob("*.log"))
    )
    assert run.returncode == 0, run.stdout[-3000:] + run.stderr[-3000:] + logs
    report = json.loads(report_path.read_text())

    # RViz ran and subscribed (per the master) to every topic of its config, and to tf
    assert report["rviz_alive"] is True
    wanted = set(rviz_config.config_topics()) | {"/tf", "/tf_static"}
    assert wanted <= set(report["rviz_subscriptions"])
    # real data flowed: camera images, lidar clouds, and radar markers from the marker node
    assert report["messages"][watch.IMAGE_TOPIC] >= 3
    assert report["messages"][watch.LIDAR_TOPIC] >= 3
    assert report["marker_publishers"] == ["/radar_markers"]
    assert report["radar_marker_points"] > 0
    assert report["radar_marker_frame"] == RADAR_FRAME

    # the picture is the X screen with RViz on it, not a blank frame
    with Image.open(png) as image:
        assert image.size == (1280, 800) and image.mode == "RGB"
        pixels = np.asarray(image)
    assert pixels.std() > 20
    colours = np.unique(pixels.reshape(-1, 3), axis=0)
    assert len(colours) > 300
    background = images.background_share(pixels, rviz_config.config_background())  # the 3D view drawn
    assert 0.05 < background < 0.9

    # everything it started is gone: the display, the master and the simulator's ports
    display = report["display"].lstrip(":")
    assert not os.path.exists(f"/tmp/.X11-unix/X{display}")
    port = report["master_uri"].rsplit(":", 1)[1]
    for pattern in (f"roscore -p {port}", f"--topicsport {report['sim_ports'][0]}", str(tmp_path / "logs")):
        leftovers = subprocess.run(["pgrep", "-f", "--", pattern], capture_output=True, text=True)
        assert leftovers.returncode == 1, f"{pattern}: {leftovers.stdout}"


def test_the_capture_knows_the_3d_view_is_drawn_by_the_configs_background_colour():
    colour = rviz_config.config_background()
    assert colour == (40, 40, 48)  # rviz/airsim_mapper.rviz's Global Options
    black = np.zeros((4, 6, 3), np.uint8)  # RViz's 3D view before llvmpipe's first frame
    assert images.background_share(black, colour) == 0.0
    black[:2] = colour
    assert images.background_share(black, colour) == 0.5


def test_a_crash_of_rviz_itself_is_told_from_other_early_exits():
    from tools.screenshot.screenshot import rviz_crashed

    crashed = (
        "roslaunch exited early; see roslaunch.log:\n"
        "corrupted size vs. prev_size\n"
        "================================================================================"
        "REQUIRED process [rviz-4] has died!\n"
        "process has died [pid 5282, exit code -6, cmd /usr/lib/rviz/rviz -d airsim_mapper.rviz]\n"
        "Initiating shutdown!\n"
    )
    assert rviz_crashed(crashed)
    assert not rviz_crashed(crashed.replace("exit code -6", "exit code 1"))  # RViz quit: a real error
    assert not rviz_crashed(crashed.replace("[rviz-4]", "[headless_sim-1]"))
    assert not rviz_crashed("roslaunch exited early; see roslaunch.log:\nRLException: cannot launch node")


def test_an_rviz_crash_is_found_in_the_whole_log_even_when_later_output_pushed_it_out_of_the_message(
    tmp_path,
):
    from tools.screenshot.errors import ChildExited, ScreenshotError
    from tools.screenshot.screenshot import crashed_rviz

    log = tmp_path / "roslaunch.log"
    crash = "REQUIRED process [rviz-4] has died!\nprocess has died [pid 21007, exit code -6, cmd rviz]\n"
    after = "".join(f"[projectairsim-2] shutting down, line {i}\n" for i in range(40))
    log.write_text("free(): invalid next size (fast)\n" + crash + after)
    exited = ChildExited("roslaunch", log)
    message = str(exited)
    assert "REQUIRED process" not in message and "line 39" in message
    assert crashed_rviz(exited)
    log.write_text(crash.replace("exit code -6", "exit code 1") + after)
    assert not crashed_rviz(ChildExited("roslaunch", log))
    assert not crashed_rviz(ScreenshotError(crash))  # only an exited process's log counts


def test_rviz_start_up_crashes_are_counted_across_the_restarts():
    from tools.screenshot.screenshot import RETRIED_ENV, crashes_so_far

    assert crashes_so_far({}) == 0
    assert crashes_so_far({RETRIED_ENV: "2"}) == 2
    assert crashes_so_far({RETRIED_ENV: "junk"}) == 0
