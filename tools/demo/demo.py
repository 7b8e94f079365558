"""`make demo`: roscore + headless server + bridge + hello mission, a live rate table, a picture and a bag.

Everything runs as real processes on free ports; the demo itself is a ROS node that watches every
topic the bridge publishes. At the end it writes out/demo.png and out/demo.bag and stops what it started;
Ctrl-C, SIGTERM and SIGHUP (`kill` of `make demo`'s process group, a closed terminal) stop it all too.
"""

from __future__ import annotations

import os
import signal
import sys
import threading
import time
from collections import deque
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from tools.rig import ROOT, Child, Rig, RigError, published_topics

OUT = Path(os.environ.get("DEMO_OUT", ROOT / "out"))
# rosbag connects to its ~35 topics one at a time: against a plain rospy node publishing 35 topics the last
# one delivered its first message 1.7-2.5 s after `rosbag record` started, against the busy bridge up to 4 s
BAG_SECONDS = 6
BAG_EXCLUDE = "(.*/Chase/.*)|(/airsim_streaming_camera/.*)"
ROBOT, CAMERA, LIDAR = "Drone1", "DownCamera", "lidar1"


@dataclass
class Rates:
    """Message arrival times per topic, for a rate over the last few seconds."""

    window_s: float = 3.0
    times: dict[str, deque] = field(default_factory=dict)
    totals: dict[str, int] = field(default_factory=dict)
    lock: threading.Lock = field(default_factory=threading.Lock)

    def tick(self, topic: str) -> None:
        now = time.monotonic()
        with self.lock:
            self.times.setdefault(topic, deque(maxlen=2000)).append(now)
            self.totals[topic] = self.totals.get(topic, 0) + 1

    def table(self, types: dict[str, str]) -> str:
        now = time.monotonic()
        rows = []
        with self.lock:
            for topic in sorted(types):
                stamps = [t for t in self.times.get(topic, ()) if now - t <= self.window_s]
                rate = (len(stamps) - 1) / (stamps[-1] - stamps[0]) if len(stamps) > 1 else 0.0
                rows.append((topic, types[topic], rate, self.totals.get(topic, 0)))
        width = max((len(r[0]) for r in rows), default=10)
        lines = [f"{'topic':<{width}}  {'type':<28} {'rate Hz':>8} {'msgs':>7}"]
        lines += [f"{t:<{width}}  {ty:<28} {r:8.1f} {n:7d}" for t, ty, r, n in rows]
        return "\n".join(lines)


class Demo:
    def __init__(self, seconds: float) -> None:
        self.seconds = seconds
        self.rig = Rig(OUT / "demo_logs")
        self.rates = Rates()
        self.latest: dict[str, object] = {}
        self.track: list[tuple[float, float, float]] = []

    def run(self) -> int:
        master = self.rig.roscore()
        os.environ.update({k: self.rig.env[k] for k in ("ROS_MASTER_URI", "ROS_HOSTNAME", "ROS_LOG_DIR")})
        print(f"demo: roscore on port {master.port} (ROS_MASTER_URI={master.uri})")
        sim = self.rig.simserver()
        print(f"demo: headless Project AirSim server on ports {sim.topics_port}/{sim.services_port}")
        print(f"demo: bridge + hello mission for {self.seconds:.0f} s (logs in {self.rig.workdir})")
        argv = [str(ROOT / "scripts" / "hello_ros.py"), *sim.ports.args(), "--nodename", "projectairsim"]
        mission = self.rig.python("hello_ros", [*argv, "--seconds", str(self.seconds + 10)])
        return self.watch(mission)

    def watch(self, mission: Child) -> int:
        import rospy

        rospy.init_node("demo_monitor", disable_signals=True)
        types = self.wait_for_topics(mission)
        self.subscribe(types)
        started = time.monotonic()
        bag_started = False
        tty = sys.stdout.isatty()
        while time.monotonic() - started < self.seconds:
            mission.check_alive()
            if not bag_started and time.monotonic() - started > max(1.0, self.seconds - BAG_SECONDS - 2):
                self.record_bag()
                bag_started = True
            time.sleep(2.0)
            table = self.rates.table(types)
            elapsed = time.monotonic() - started
            if tty:
                sys.stdout.write("\x1b[2J\x1b[H")
            print(
                f"demo: t = {elapsed:4.0f} s of {self.seconds:.0f} s, drone at {self.position()}\n{table}\n",
                flush=True,
            )
        if not bag_started:
            self.record_bag()
        time.sleep(BAG_SECONDS + 1)
        self.picture()
        rospy.signal_shutdown("demo finished")
        silent = [t for t in types if self.rates.totals.get(t, 0) == 0 and "desired_pose" not in t]
        print(f"demo: wrote {OUT / 'demo.png'} and {OUT / 'demo.bag'}")
        if silent:
            print("demo: topics that carried no message: " + ", ".join(silent))
        return 0

    def wait_for_topics(self, mission: Child) -> dict[str, str]:
        """The bridge's topics and their types, once its pose and lidar are published."""
        self.rig.wait_topics(
            [f"/airsim_node/{ROBOT}/actual_pose", f"/airsim_node/{ROBOT}/{LIDAR}/lidar"], mission
        )
        time.sleep(1.0)  # the rest of the scene's bridges come up with them
        topics = published_topics(self.rig.env["ROS_MASTER_URI"])
        prefixes = ("/airsim_node/", "/airsim_streaming_camera/", "/tf")
        return {topic: ros_type for topic, ros_type in topics.items() if topic.startswith(prefixes)}

    def subscribe(self, types: dict[str, str]) -> None:
        """One subscriber per topic (rospy shares one connection per topic and process): typed for what
        the picture needs, AnyMsg (no deserialisation) for the rest."""
        import rospy
        from geometry_msgs.msg import PoseStamped
        from sensor_msgs.msg import Image, PointCloud2

        pose_topic = f"/airsim_node/{ROBOT}/actual_pose"
        for topic, ros_type in types.items():
            if topic == pose_topic:
                cls = PoseStamped
            elif ros_type == "sensor_msgs/Image" and f"/{CAMERA}/" in topic:
                cls = Image
            elif ros_type == "sensor_msgs/PointCloud2":
                cls = PointCloud2
            else:
                cls = rospy.AnyMsg
            rospy.Subscriber(topic, cls, self.on_message, callback_args=topic, queue_size=1)

    def on_message(self, msg: object, topic: str) -> None:
        self.rates.tick(topic)
        if topic.endswith("/actual_pose"):
            p = msg.pose.position
            self.track.append((p.x, p.y, p.z))
        elif not isinstance(msg, __import__("rospy").AnyMsg):
            self.latest[topic] = msg

    def position(self) -> str:
        if not self.track:
            return "(no pose yet)"
        x, y, z = self.track[-1]
        return f"N {x:6.1f}  E {y:6.1f}  D {z:6.1f}"

    def record_bag(self) -> None:
        print(f"demo: recording {BAG_SECONDS} s to {OUT / 'demo.bag'}")
        self.rig.start(
            "rosbag",
            [
                "rosbag",
                "record",
                "-q",
                "-a",
                "-x",
                BAG_EXCLUDE,
                f"--duration={BAG_SECONDS}",
                "-O",
                str(OUT / "demo.bag"),
            ],
        )

    def picture(self) -> None:
        from tools.demo.picture import draw

        draw(OUT / "demo.png", self.latest, np.array(self.track or [(0.0, 0.0, 0.0)]), ROBOT, CAMERA)


STOP_SIGNALS = (signal.SIGTERM, signal.SIGHUP)


class Stopped(Exception):
    """SIGTERM or SIGHUP: the demo ends as Ctrl-C ends it, stopping everything it started."""

    def __init__(self, number: int) -> None:
        super().__init__(signal.Signals(number).name)
        self.number = number


def _stop(number: int, _frame: object) -> None:
    for sig in STOP_SIGNALS:  # a second signal must not cut the clean-up short
        signal.signal(sig, signal.SIG_IGN)
    raise Stopped(number)


def main() -> int:
    seconds = float(os.environ.get("DEMO_SECONDS", "30"))
    OUT.mkdir(exist_ok=True)
    for sig in STOP_SIGNALS:
        signal.signal(sig, _stop)
    demo = Demo(seconds)
    try:
        return demo.run()
    except RigError as exc:
        print(f"demo: error: {exc}", file=sys.stderr)
        return 1
    except KeyboardInterrupt:
        return 130
    except Stopped as stop:
        print(f"demo: {stop}: stopping everything it started", file=sys.stderr)
        return 128 + stop.number
    finally:
        demo.rig.stop_all()
