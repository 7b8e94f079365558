"""The processes of a screenshot: Xvfb, a private roscore and launch/rviz.launch in one rig."""

from __future__ import annotations

import contextlib
import os
import select
import shutil
import time
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from tools.rig import ROOT, Child, Rig, SimPorts, descendants, wait_until
from tools.screenshot.errors import ChildExited, ScreenshotError
from tools.screenshot.images import background_share, image_stats, read_xwd, write_png
from tools.screenshot.rviz_config import config_background

LAUNCH = ROOT / "launch" / "rviz.launch"
TOOLS = ("Xvfb", "roscore", "roslaunch", "rviz")
QT_OVERRIDES = ("QT_QPA_PLATFORM_PLUGIN_PATH", "QT_PLUGIN_PATH", "QT_QPA_FONTDIR", "QT_QPA_PLATFORM")


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


def wait_for(predicate: Any, timeout: float, what: str, child: Child | None = None) -> None:
    """`wait_until`, failing at once if `child` exits meanwhile."""

    def ready() -> bool:
        if child is not None and not child.alive():
            raise ChildExited(child.name, child.log_path)
        return predicate()

    wait_until(ready, timeout, what, 0.25, ScreenshotError)
