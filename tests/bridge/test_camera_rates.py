"""The shipped demo scene delivers every camera at its configured rate while the bridge runs.

As `make demo` runs it: the headless server (cameras rendered with OpenGL in its render worker),
scripts/hello_ros.py flying Drone1 over scene_drone_sensors.jsonc with the bridge in the same process, and
every sensor of the robot streaming. Each camera image topic the bridge publishes must arrive here at no
less than (1 - RATE_TOLERANCE) times its camera's configured rate, 1 / capture-interval, over WINDOW_S.
"""

from __future__ import annotations

import time
from pathlib import Path

import commentjson
from bridgeharness import published_topics, wait_topic
from harness import ROOT, SIM_CONFIG, wait_until

from tools.rig import descendants
from tools.soak.cpu import cpu_mark

SCENE, ROBOT = "scene_drone_sensors.jsonc", "Drone1"
RATE_TOLERANCE = 0.1  # the arrival rate measured here, over WINDOW_S, may be this much below the config
WARMUP_S, WINDOW_S = 3.0, 10.0


def configured_rates() -> dict[str, tuple[float, int]]:
    """Camera id -> (configured Hz, number of capture-enabled image types), from the scene's robot."""
    scene = commentjson.loads((SIM_CONFIG / SCENE).read_text())
    robot = next(a for a in scene["actors"] if a["name"] == ROBOT)["robot-config"]
    sensors = commentjson.loads((SIM_CONFIG / robot).read_text())["sensors"]
    return {
        s["id"]: (
            1.0 / s["capture-interval"],
            sum(c.get("capture-enabled", False) for c in s["capture-settings"]),
        )
        for s in sensors
        if s["type"] == "camera" and s.get("enabled", True)
    }


def render_worker_of(server_pid: int) -> int:
    """The pid of the server's render worker."""
    for pid in descendants({server_pid}):
        if "render_worker" in Path(f"/proc/{pid}/cmdline").read_text():
            return pid
    raise AssertionError(f"the server {server_pid} has no render worker")


def cpu_seconds(pid: int) -> float:
    mark = cpu_mark("render_worker", pid)
    assert mark is not None, f"process {pid} has gone"
    return mark.seconds


def test_the_demo_scene_delivers_every_camera_at_its_configured_rate(rig_factory):
    import rospy

    rig = rig_factory()
    mission = rig.launcher.python(
        "hello_ros",
        [
            str(ROOT / "scripts" / "hello_ros.py"),
            *rig.sim.ports.args(),
            "--scene",
            SCENE,
            "--nodename",
            "camera_rates",
            "--seconds",
            "60",
        ],
    )
    wait_topic(f"/airsim_node/{ROBOT}/actual_pose", mission)
    cameras = configured_rates()
    assert cameras, "the demo scene has cameras"

    def image_topics() -> dict[str, str]:
        return {
            topic: topic.split("/")[3]
            for topic, kind in published_topics().items()
            if kind == "sensor_msgs/Image" and topic.startswith(f"/airsim_node/{ROBOT}/")
        }

    want = sum(n for _, n in cameras.values())
    wait_until(lambda: len(image_topics()) >= want, 30, interval=0.2, what=f"{want} camera image topics")
    topics = image_topics()
    assert set(topics.values()) == set(cameras)
    arrivals: dict[str, list[float]] = {topic: [] for topic in topics}
    subscribers = [
        rospy.Subscriber(t, rospy.AnyMsg, lambda _m, t=t: arrivals[t].append(time.monotonic()), queue_size=20)
        for t in topics
    ]
    try:
        time.sleep(WARMUP_S)
        worker = render_worker_of(rig.sim.process.pid)
        assert "libEGL" in Path(f"/proc/{worker}/maps").read_text(), "the cameras are not rendered with GL"
        worker_cpu = cpu_seconds(worker)
        start = time.monotonic()
        time.sleep(WINDOW_S)
        end = time.monotonic()
        worker_cpu = (cpu_seconds(worker) - worker_cpu) / (end - start)
        assert mission.alive(), mission.output()
    finally:
        for subscriber in subscribers:
            subscriber.unregister()
    rates = {t: sum(start <= s < end for s in arrivals[t]) / (end - start) for t in topics}
    report = "\n".join(
        f"{rates[t]:6.1f} Hz (configured {cameras[topics[t]][0]:g}) {t}" for t in sorted(topics)
    )
    report += f"\nrender worker: {worker_cpu:.0%} of one core"
    print(report)
    slow = [t for t in topics if rates[t] < (1.0 - RATE_TOLERANCE) * cameras[topics[t]][0]]
    assert not slow, f"cameras below their configured rate:\n{report}"
    mission.stop()
