"""`make screenshot`: RViz on the live stack under Xvfb, captured to a PNG.

Starts Xvfb on a display it picks itself, a private roscore, and `launch/rviz.launch` (headless server,
bridge + hello mission, radar markers, RViz with `rviz/airsim_mapper.rviz`). It waits until RViz has
subscribed to every topic of its config and images, lidar clouds and radar markers are flowing, lets RViz
render for a few seconds, waits (30 s at most) until the drone is on its way out to the ball, then copies
the X screen (Xvfb's `-fbdir` framebuffer, an XWD file) to a PNG. Everything it started is stopped at
the end, whatever happened. `--report` writes what it saw (from the master and from real messages) as JSON.
"""

from __future__ import annotations

import argparse
import contextlib
import json
import os
import re
import shutil
import sys
import tempfile
import time
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from tools.rig import ROOT
from tools.screenshot.errors import ChildExited, ScreenshotError
from tools.screenshot.rviz_config import config_topics
from tools.screenshot.stack import RvizStack, wait_for
from tools.screenshot.watch import IMAGE_TOPIC, LIDAR_TOPIC, MARKER_TOPIC, ODOM_TOPIC, Watch

TF_TOPICS = ("/tf", "/tf_static")


@dataclass
class Options:
    """The command line: where to write, how long to wait, the screen size."""

    out: Path
    report: Path | None = None
    settle_s: float = 6.0
    away_m: float = 8.0
    timeout_s: float = 120.0
    width: int = 1280
    height: int = 800
    keep: Path | None = None


def take(options: Options) -> dict[str, Any]:
    """Run the stack, wait for the data and for RViz, capture the screen; return the report."""
    workdir = options.keep or Path(tempfile.mkdtemp(prefix="airsim-mapper-rviz-"))
    wanted = config_topics()
    ok = False
    try:
        with RvizStack(workdir, options.width, options.height) as stack:
            print(
                f"screenshot: Xvfb {stack.display}, roscore {stack.master_uri}, logs in {workdir}", flush=True
            )
            os.environ.update(
                {k: stack.env[k] for k in ("ROS_MASTER_URI", "ROS_HOSTNAME", "ROS_LOG_DIR", "ROS_HOME")}
            )
            import rospy

            rospy.init_node("rviz_screenshot", anonymous=True, disable_signals=True)
            watch = Watch()
            flowing = (IMAGE_TOPIC, LIDAR_TOPIC, MARKER_TOPIC, ODOM_TOPIC)
            watch.start(flowing)
            needed = set(wanted) | set(TF_TOPICS)

            def ready() -> bool:
                stack.check_running()
                return watch.flowing(flowing, 3) and needed <= stack.subscriptions_of("/rviz")

            wait_for(ready, options.timeout_s, "RViz's subscriptions and images, lidar and radar markers")
            print(f"screenshot: data flowing; letting RViz render for {options.settle_s:.0f} s", flush=True)
            time.sleep(options.settle_s)
            # Mid-flight looks best: wait (briefly) until the drone is on its way out to the ball.
            if options.away_m > 0:
                with contextlib.suppress(ScreenshotError):
                    wait_for(lambda: watch.away(options.away_m), 30, f"the drone {options.away_m:.0f} m out")
            # on a busy host llvmpipe's first frame can come seconds after the data
            with contextlib.suppress(ScreenshotError):
                wait_for(stack.drawn, RENDER_WAIT_S, "RViz's first frame of its 3D view")
            stack.check_running()
            stats = stack.capture(options.out)
            report = {
                "png": str(options.out),
                "size": [options.width, options.height],
                "display": stack.display,
                "master_uri": stack.master_uri,
                "sim_ports": [stack.sim_ports.topics, stack.sim_ports.services],
                "rviz_alive": stack.rviz_alive(),
                "rviz_subscriptions": sorted(stack.subscriptions_of("/rviz")),
                "config_topics": wanted,
                "marker_publishers": stack.publishers_of(MARKER_TOPIC),
                "messages": dict(watch.counts),
                "radar_marker_points": watch.marker_points,
                "radar_marker_frame": watch.marker_frame,
                "drone_position_ned": list(watch.position),
                "image": stats,
            }
            rospy.signal_shutdown("screenshot taken")
        ok = True
    finally:
        if options.keep is None and ok:  # a failed run keeps its logs for the error message
            shutil.rmtree(workdir, ignore_errors=True)
    if options.report is not None:
        options.report.parent.mkdir(parents=True, exist_ok=True)
        options.report.write_text(json.dumps(report, indent=2) + "\n")
    return report


def parse_args(argv: Sequence[str] | None) -> Options:
    parser = argparse.ArgumentParser(prog="python -m tools.screenshot", description=__doc__.splitlines()[0])
    parser.add_argument(
        "--out", type=Path, default=ROOT / "out" / "rviz.png", help="the PNG (default out/rviz.png)"
    )
    parser.add_argument("--report", type=Path, help="also write what was seen as JSON")
    parser.add_argument("--settle", type=float, default=6.0, help="seconds of rendering before the capture")
    parser.add_argument(
        "--away", type=float, default=8.0, help="then wait (30 s at most) until the drone is this far out, m"
    )
    parser.add_argument("--timeout", type=float, default=120.0, help="seconds to wait for RViz and the data")
    parser.add_argument("--size", default="1280x800", help="screen size WIDTHxHEIGHT")
    parser.add_argument(
        "--keep", type=Path, help="keep the logs in this folder (default: a removed temp dir)"
    )
    args = parser.parse_args(argv)
    width, height = (int(v) for v in args.size.lower().split("x"))
    return Options(args.out, args.report, args.settle, args.away, args.timeout, width, height, args.keep)


RENDER_WAIT_S = 60.0  # after the settle time, for RViz's first drawn frame of its 3D view
RETRIED_ENV = "AIRSIM_MAPPER_SCREENSHOT_RETRIED"  # how many times RViz crashed at start-up so far
RVIZ_STARTS = 3  # RViz start-ups tried before a crash counts as an error
_RVIZ_CRASH = re.compile(r"REQUIRED process \[rviz-\d+\] has died!.*?exit code -\d+", re.S)


def rviz_crashed(error: str) -> bool:
    """roslaunch reports that RViz itself was killed by a signal (a fault in RViz or its OpenGL driver)."""
    return _RVIZ_CRASH.search(error) is not None


def crashed_rviz(exc: ScreenshotError) -> bool:
    """The pipeline stopped because RViz crashed: judged on the whole log of the process that exited, since
    what roslaunch prints after RViz dies (the mission's own shutdown) can push it out of the message."""
    return isinstance(exc, ChildExited) and rviz_crashed(exc.log_text())


def crashes_so_far(environ: Mapping[str, str]) -> int:
    """RViz start-up crashes counted by earlier attempts of this run (RETRIED_ENV)."""
    value = environ.get(RETRIED_ENV, "")
    return int(value) if value.isdigit() else 0


def main(argv: Sequence[str] | None = None) -> int:
    args = list(sys.argv[1:] if argv is None else argv)
    options = parse_args(args)
    try:
        report = take(options)
    except ScreenshotError as exc:
        crashes = crashes_so_far(os.environ) + 1
        if crashed_rviz(exc) and crashes < RVIZ_STARTS:
            # RViz under Xvfb and Mesa's software renderer occasionally aborts at start-up ("corrupted
            # size vs. prev_size" in one CI run; twice in a row in another). Nothing of ours is involved:
            # start again afresh, up to RVIZ_STARTS start-ups in all.
            print("screenshot: RViz crashed at start-up; trying once more from scratch", file=sys.stderr)
            sys.stderr.flush()
            os.environ[RETRIED_ENV] = str(crashes)
            os.execv(sys.executable, [sys.executable, "-m", "tools.screenshot", *args])
        print(f"screenshot: error: {exc}", file=sys.stderr)
        return 1
    except KeyboardInterrupt:
        return 130
    print(
        f"screenshot: wrote {report['png']} ({report['size'][0]}x{report['size'][1]}, "
        f"{report['image']['colours']} colours); radar markers: {report['radar_marker_points']} points"
    )
    return 0
