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
import math
import os
import re
import select
import shutil
import struct
import sys
import tempfile
import threading
import time
import zlib
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from tools.rig import ROOT, Child, Rig, SimPorts, descendants, wait_until

CONFIG = ROOT / "rviz" / "airsim_mapper.rviz"
LAUNCH = ROOT / "launch" / "rviz.launch"
IMAGE_TOPIC = "/airsim_node/Drone1/Chase/scene_camera/image"
LIDAR_TOPIC = "/airsim_node/Drone1/lidar1/lidar"
MARKER_TOPIC = "/airsim_node/Drone1/radar1/radar_markers"
ODOM_TOPIC = "/airsim_node/Drone1/odom"
TF_TOPICS = ("/tf", "/tf_static")
TOOLS = ("Xvfb", "roscore", "roslaunch", "rviz")
QT_OVERRIDES = ("QT_QPA_PLATFORM_PLUGIN_PATH", "QT_PLUGIN_PATH", "QT_QPA_FONTDIR", "QT_QPA_PLATFORM")


class ScreenshotError(RuntimeError):
    """The screenshot could not be taken (the message says which part failed)."""


class ChildExited(ScreenshotError):
    """A process of the pipeline exited early; the message ends with the tail of its log."""

    def __init__(self, name: str, log: Path) -> None:
        self.log = log
        super().__init__(f"{name} exited early; see {log}:\n{tail(log)}")

    def log_text(self) -> str:
        with contextlib.suppress(OSError):
            return self.log.read_text(errors="replace")
        return ""


# -- images -----------------------------------------------------------------------------------------------


def read_xwd(path: Path) -> np.ndarray:
    """(H, W, 3) uint8 RGB of a 24/32-bit TrueColor XWD file (what Xvfb -fbdir maps)."""
    raw = Path(path).read_bytes()
    if len(raw) < 100:
        raise ScreenshotError(f"{path}: not an XWD file ({len(raw)} bytes)")
    head = struct.unpack(">25I", raw[:100])
    header_size, version, pixmap_format, _depth, width, height = head[:6]
    byte_order, bits_per_pixel, bytes_per_line = head[7], head[11], head[12]
    masks, ncolors = head[14:17], head[19]
    if version != 7 or pixmap_format != 2 or bits_per_pixel != 32:
        raise ScreenshotError(
            f"{path}: unsupported XWD (version {version}, format {pixmap_format}, {bits_per_pixel} bpp)"
        )
    offset = header_size + 12 * ncolors
    if len(raw) < offset + height * bytes_per_line:
        raise ScreenshotError(f"{path}: truncated XWD")
    words = np.frombuffer(
        raw, dtype="<u4" if byte_order == 0 else ">u4", count=height * bytes_per_line // 4, offset=offset
    )
    pixels = words.reshape(height, bytes_per_line // 4)[:, :width]
    channels = []
    for mask in masks:
        shift = (mask & -mask).bit_length() - 1
        channels.append(((pixels & mask) >> shift).astype(np.uint8))
    return np.stack(channels, axis=-1)


def write_png(path: Path, rgb: np.ndarray) -> None:
    """Write an (H, W, 3) uint8 array as an 8-bit RGB PNG (zlib, no filter: small for flat UI images)."""
    height, width, _ = rgb.shape
    rows = np.concatenate(
        [np.zeros((height, 1), np.uint8), np.ascontiguousarray(rgb).reshape(height, -1)], axis=1
    )

    def chunk(kind: bytes, data: bytes) -> bytes:
        return struct.pack(">I", len(data)) + kind + data + struct.pack(">I", zlib.crc32(kind + data))

    header = struct.pack(">IIBBBBB", width, height, 8, 2, 0, 0, 0)
    body = chunk(b"IHDR", header) + chunk(b"IDAT", zlib.compress(rows.tobytes(), 9)) + chunk(b"IEND", b"")
    Path(path).write_bytes(b"\x89PNG\r\n\x1a\n" + body)


def image_stats(rgb: np.ndarray) -> dict[str, float]:
    """How much there is to see: pixel standard deviation and the number of distinct colours."""
    flat = rgb.reshape(-1, 3).astype(np.uint32)
    packed = (flat[:, 0] << 16) | (flat[:, 1] << 8) | flat[:, 2]
    return {"std": float(rgb.std()), "colours": int(np.unique(packed).size)}


# -- the RViz config --------------------------------------------------------------------------------------


def config_topics(path: Path = CONFIG) -> dict[str, str]:
    """Every topic the config's displays subscribe to, with the display class: {topic: class}."""
    import yaml

    config = yaml.safe_load(Path(path).read_text())
    found: dict[str, str] = {}

    def walk(displays: Iterable[Any]) -> None:
        for display in displays or ():
            for key, value in display.items():
                if key.endswith("Topic") and isinstance(value, str) and value:
                    found[value] = display["Class"]
            walk(display.get("Displays", ()))

    walk(config["Visualization Manager"]["Displays"])
    return found


def config_background(path: Path = CONFIG) -> tuple[int, int, int]:
    """The 3D view's background colour in the config (RViz writes it as "R; G; B")."""
    import yaml

    options = yaml.safe_load(Path(path).read_text())["Visualization Manager"]["Global Options"]
    red, green, blue = (int(v) for v in options["Background Color"].split(";"))
    return red, green, blue


def background_share(rgb: np.ndarray, colour: tuple[int, int, int]) -> float:
    """The share of the screen in `colour`: 0 until RViz has drawn its 3D view once."""
    return float(np.all(rgb == np.array(colour, dtype=rgb.dtype), axis=-1).mean())


def config_frames(path: Path = CONFIG) -> set[str]:
    """The tf frames the config's TF displays enable by name, plus the fixed frame."""
    import yaml

    config = yaml.safe_load(Path(path).read_text())
    manager = config["Visualization Manager"]
    frames = {manager["Global Options"]["Fixed Frame"]}
    for display in manager["Displays"]:
        if display["Class"] == "rviz/TF":
            frames |= {
                k for k, v in display.get("Frames", {}).items() if isinstance(v, dict) and v.get("Value")
            }
    return frames


# -- processes --------------------------------------------------------------------------------------------


@dataclass
class RvizStack:
    """Xvfb, a private roscore and launch/rviz.launch in one rig; a context manager that stops all of them."""

    workdir: Path
    width: int = 1280
    height: int = 800
    launch_args: Sequence[str] = ()
    display: str = ""
    sim_ports: SimPorts = field(default_factory=lambda: SimPorts(0, 0))  # the headless server's, once started
    rig: Rig = field(init=False)
    background: tuple[int, int, int] = field(init=False)  # the config's 3D background colour

    def __post_init__(self) -> None:
        self.rig = Rig(self.workdir, cwd=self.workdir)
        self.background = config_background()

    def __enter__(self) -> RvizStack:
        try:
            self.start()
        except BaseException:
            self.stop()
            raise
        return self

    def __exit__(self, *exc: object) -> None:
        self.stop()

    @property
    def framebuffer(self) -> Path:
        return self.workdir / "fb" / "Xvfb_screen0"

    @property
    def children(self) -> list[Child]:
        return self.rig.children

    @property
    def env(self) -> dict[str, str]:
        return self.rig.env

    @property
    def master_uri(self) -> str:
        return self.rig.env.get("ROS_MASTER_URI", "")

    def start(self) -> None:
        missing = [tool for tool in TOOLS if shutil.which(tool) is None]
        if missing:
            raise ScreenshotError(f"missing {', '.join(missing)}: run `make setup`")
        for sub in ("fb", "xdg", "home"):
            (self.workdir / sub).mkdir(mode=0o700, exist_ok=True)
        self.rig.env.update(
            LIBGL_ALWAYS_SOFTWARE="1",
            XDG_RUNTIME_DIR=str(self.workdir / "xdg"),
            HOME=str(self.workdir / "home"),  # RViz keeps its recent-configs file under ~/.rviz
        )
        for key in QT_OVERRIDES:  # e.g. set by importing cv2: would point RViz at opencv's own Qt plugins
            self.rig.env.pop(key, None)
        self.display = self.start_xvfb()
        self.rig.env["DISPLAY"] = self.display
        self.rig.roscore()
        self.sim_ports = SimPorts.free()
        argv = ["roslaunch", str(LAUNCH), f"topicsport:={self.sim_ports.topics}"]
        self.rig.start("roslaunch", [*argv, f"servicesport:={self.sim_ports.services}", *self.launch_args])

    def start_xvfb(self) -> str:
        """Xvfb on a display it chooses itself (-displayfd), its screen mapped to a file (-fbdir)."""
        read_fd, write_fd = os.pipe()
        try:
            xvfb = self.rig.start(
                "xvfb",
                [
                    "Xvfb",
                    "-displayfd",
                    str(write_fd),
                    "-screen",
                    "0",
                    f"{self.width}x{self.height}x24",
                    "-fbdir",
                    str(self.workdir / "fb"),
                    "-nolisten",
                    "tcp",
                    "-nocursor",
                    "-noreset",
                ],
                pass_fds=(write_fd,),
            )
            os.close(write_fd)
            write_fd = -1
            data = b""
            deadline = time.monotonic() + 30
            while not data.endswith(b"\n") and time.monotonic() < deadline:  # "<number>\n", maybe in parts
                ready, _, _ = select.select([read_fd], [], [], max(0.0, deadline - time.monotonic()))
                chunk = os.read(read_fd, 64) if ready else b""
                if not chunk:
                    break
                data += chunk
            number = data.decode().strip()
        finally:
            os.close(read_fd)
            if write_fd >= 0:
                os.close(write_fd)
        if not number.isdigit():
            raise ScreenshotError(f"Xvfb did not start; see {xvfb.log_path}")
        return f":{number}"

    def system_state(self) -> tuple[list, list, list]:
        import rosgraph

        return rosgraph.Master("/rviz_screenshot", master_uri=self.master_uri).getSystemState()

    def subscriptions_of(self, node_prefix: str = "/rviz") -> set[str]:
        """The topics a node (by name prefix) subscribes to, from the master."""
        _, subscribers, _ = self.system_state()
        return {topic for topic, nodes in subscribers if any(n.startswith(node_prefix) for n in nodes)}

    def publishers_of(self, topic: str) -> list[str]:
        publishers, _, _ = self.system_state()
        return next((nodes for name, nodes in publishers if name == topic), [])

    def rviz_alive(self) -> bool:
        """The RViz process is running (pgrep on this stack's display would also find other sessions)."""
        launch = next(c for c in self.children if c.name == "roslaunch")
        for pid in descendants({launch.popen.pid}):
            with contextlib.suppress(OSError):
                if Path(f"/proc/{pid}/comm").read_text().strip() == "rviz":
                    return True
        return False

    def check_running(self) -> None:
        for child in self.children:
            if not child.alive():
                raise ChildExited(child.name, child.log_path)

    def drawn(self) -> bool:
        """RViz has drawn its 3D view once: the config's background colour is on the screen (before
        llvmpipe's first frame the view is black)."""
        return background_share(read_xwd(self.framebuffer), self.background) > 0

    def capture(self, out: Path) -> dict[str, float]:
        """The X screen as a PNG; returns its image statistics."""
        rgb = read_xwd(self.framebuffer)
        out.parent.mkdir(parents=True, exist_ok=True)
        write_png(out, rgb)
        return {**image_stats(rgb), "background": background_share(rgb, self.background)}

    def stop(self) -> None:
        """SIGINT (roslaunch then stops its nodes), wait, then SIGKILL whatever is left of each tree."""
        self.rig.stop_all(timeout=30.0)


def tail(path: Path, lines: int = 25) -> str:
    with contextlib.suppress(OSError):
        return "\n".join(path.read_text(errors="replace").splitlines()[-lines:])
    return ""


def wait_for(predicate: Any, timeout: float, what: str, child: Child | None = None) -> None:
    """`wait_until`, failing at once if `child` exits meanwhile."""

    def ready() -> bool:
        if child is not None and not child.alive():
            raise ChildExited(child.name, child.log_path)
        return predicate()

    wait_until(ready, timeout, what, 0.25, ScreenshotError)


# -- watching the data ------------------------------------------------------------------------------------


@dataclass
class Watch:
    """Counts messages on the topics RViz shows; keeps the latest radar marker and drone position."""

    counts: dict[str, int] = field(default_factory=dict)
    marker_points: int = 0
    marker_frame: str = ""
    position: tuple[float, float, float] = (0.0, 0.0, 0.0)
    receding: bool = False  # the last odometry message was farther from the pad than the one before
    lock: threading.Lock = field(default_factory=threading.Lock)

    def start(self, topics: Iterable[str]) -> None:
        import rospy
        from nav_msgs.msg import Odometry
        from visualization_msgs.msg import MarkerArray

        for topic in topics:
            cls = {MARKER_TOPIC: MarkerArray, ODOM_TOPIC: Odometry}.get(topic, rospy.AnyMsg)
            rospy.Subscriber(topic, cls, self.on_message, callback_args=topic, queue_size=1)

    def on_message(self, msg: Any, topic: str) -> None:
        with self.lock:
            self.counts[topic] = self.counts.get(topic, 0) + 1
            if topic == MARKER_TOPIC:
                points = sum(len(m.points) for m in msg.markers)
                if points:
                    self.marker_points = points
                    self.marker_frame = msg.markers[0].header.frame_id
            elif topic == ODOM_TOPIC:
                p = msg.pose.pose.position
                self.receding = math.hypot(p.x, p.y) > math.hypot(*self.position[:2])
                self.position = (p.x, p.y, p.z)

    def away(self, metres: float) -> bool:
        """The drone is at least `metres` from the pad (horizontally) and still flying away from it."""
        with self.lock:
            return math.hypot(*self.position[:2]) >= metres and self.receding

    def flowing(self, topics: Iterable[str], at_least: int) -> bool:
        with self.lock:
            return all(self.counts.get(t, 0) >= at_least for t in topics) and self.marker_points > 0


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
