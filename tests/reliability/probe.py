"""Probe node for the reliability tests (run as a subprocess; prints what it sees, one line each).

probe.py watch TOPIC           print "MSG <wall time>" for every message on TOPIC (any type)
probe.py status NODE           print "STATUST <wall time>" and "STATUS <json>" for every status message of
                               bridge node NODE
probe.py diagnostics NODE      print "DIAG <json>" for every /diagnostics entry of NODE's simulator
probe.py twist TOPIC N VX [FRAME]   publish N geometry_msgs/Twist at 10 Hz (VX may be nan, inf),
                               then print "LAST <wall time>" and keep the publisher until killed
probe.py pose TOPIC X Y Z QW QX QY QZ [FRAME]   publish one PoseStamped 3 times, print "SENT"
probe.py trials TOPIC N VX SERVICESPORT ROBOT   watchdog trials: print "TRIAL <seconds>" per trial
probe.py bad ROBOT_PREFIX CAMERA  publish malformed cmd_vel and desired_pose messages, print "SENT <n>"
probe.py strings TOPIC [--every S] DATA...  publish each DATA as a std_msgs/String, S s apart (0.5 unless
                               told), then print "SENT"
probe.py huge TOPIC N SIZE      publish N distinct std_msgs/String of SIZE characters, 0.05 s apart, "SENT"
probe.py stamped TOPIC...      print "T <index> <monotonic time> <stamp>" for every message on each TOPIC (any
                               type with a header first, or /clock); the stamp is read from the raw bytes
"""

from __future__ import annotations

import json
import math
import sys
import time

import rospy


def connected(pub: rospy.Publisher, timeout: float = 20.0) -> None:
    deadline = time.monotonic() + timeout
    while pub.get_num_connections() == 0:
        if time.monotonic() > deadline:
            raise SystemExit(f"nobody subscribed to {pub.name}")
        time.sleep(0.05)


def watch(topic: str) -> None:
    rospy.Subscriber(topic, rospy.AnyMsg, lambda _m: print(f"MSG {time.time():.4f}", flush=True))
    print("READY", flush=True)
    rospy.spin()


def stamped(topics: list[str]) -> None:
    """Receive times and stamps of any stamped message, without deserializing it (images included)."""
    import struct

    def on_message(index: int, offset: int):
        def show(message: rospy.AnyMsg) -> None:
            secs, nsecs = struct.unpack_from("<II", message._buff, offset)
            print(f"T {index} {time.monotonic():.6f} {secs + nsecs * 1e-9:.6f}", flush=True)

        return show

    for index, topic in enumerate(topics):
        offset = 0 if topic.endswith("/clock") else 4  # Clock is the time itself; a Header has seq first
        rospy.Subscriber(topic, rospy.AnyMsg, on_message(index, offset), queue_size=100, tcp_nodelay=True)
    print("READY", flush=True)
    rospy.spin()


def status(node: str) -> None:
    from std_msgs.msg import String

    def show(message: String) -> None:
        print(f"STATUST {time.time():.4f}\nSTATUS {message.data}", flush=True)

    rospy.Subscriber(f"/airsim_mapper/{node}/status", String, show)
    rospy.spin()


def diagnostics(node: str) -> None:
    from diagnostic_msgs.msg import DiagnosticArray

    def show(array: DiagnosticArray) -> None:
        for entry in array.status:
            if entry.name == f"{node}: simulator":
                values = {kv.key: kv.value for kv in entry.values}
                report = {"level": entry.level, "message": entry.message, "values": values}
                print(f"DIAG {json.dumps(report)}", flush=True)

    rospy.Subscriber("/diagnostics", DiagnosticArray, show)
    rospy.spin()


def twist(topic: str, count: int, vx: float, frame: str | None = None) -> rospy.Publisher:
    from geometry_msgs.msg import Twist

    pub = rospy.Publisher(topic, Twist, queue_size=10)
    connected(pub)
    msg = Twist()
    msg.linear.x = vx
    for _ in range(count):
        pub.publish(msg)
        time.sleep(0.1)
    print(f"LAST {time.time():.4f}", flush=True)
    return pub


def pose(topic: str, values: list[float], frame: str) -> None:
    from geometry_msgs.msg import PoseStamped

    pub = rospy.Publisher(topic, PoseStamped, queue_size=10)
    connected(pub)
    msg = PoseStamped()
    msg.header.frame_id = frame
    p, q = msg.pose.position, msg.pose.orientation
    p.x, p.y, p.z, q.w, q.x, q.y, q.z = values
    for _ in range(3):
        pub.publish(msg)
        time.sleep(0.1)
    print("SENT", flush=True)
    rospy.spin()


def strings(topic: str, items: list[str], every: float = 0.5) -> None:
    from std_msgs.msg import String

    pub = rospy.Publisher(topic, String, queue_size=10)
    connected(pub)
    for item in items:
        pub.publish(String(data=item))
        time.sleep(every)
    print("SENT", flush=True)
    rospy.spin()


def huge(topic: str, count: int, size: int) -> None:
    from std_msgs.msg import String

    pub = rospy.Publisher(topic, String, queue_size=count)
    connected(pub)
    for index in range(count):
        pub.publish(String(data=f"{index:04d}" + "x" * (size - 4)))
        time.sleep(0.05)
    print("SENT", flush=True)
    rospy.spin()


def bad(prefix: str, camera: str) -> None:
    """Every kind of malformed command the bridge must keep from the simulator."""
    from geometry_msgs.msg import PoseStamped, Twist

    nan, inf = float("nan"), float("inf")
    cmd_vel = rospy.Publisher(f"{prefix}/cmd_vel", Twist, queue_size=20)
    pose = rospy.Publisher(f"{prefix}/desired_pose", PoseStamped, queue_size=20)
    cam = rospy.Publisher(f"{prefix}/{camera}/desired_pose", PoseStamped, queue_size=20)
    for pub in (cmd_vel, pose, cam):
        connected(pub)
    twists = [Twist(), Twist(), Twist()]
    twists[0].linear.x, twists[1].angular.z, twists[2].linear.z = nan, -inf, inf

    def stamped(xyz: tuple, wxyz: tuple, frame: str = "map") -> PoseStamped:
        msg = PoseStamped()
        msg.header.frame_id = frame
        msg.pose.position.x, msg.pose.position.y, msg.pose.position.z = xyz
        q = msg.pose.orientation
        q.w, q.x, q.y, q.z = wxyz
        return msg

    poses = [
        stamped((nan, 0.0, -5.0), (1.0, 0.0, 0.0, 0.0)),
        stamped((1.0, inf, -5.0), (1.0, 0.0, 0.0, 0.0)),
        stamped((1.0, 0.0, -5.0), (0.0, 0.0, 0.0, 0.0)),
        stamped((1.0, 0.0, -5.0), (3.0, 0.0, 0.0, 0.0)),  # norm 3: not a rotation
        stamped((1.0, 0.0, -5.0), (nan, 0.0, 0.0, 0.0)),
        stamped((1.0, 0.0, -5.0), (1.0, 0.0, 0.0, 0.0), frame="base_link"),
    ]
    for msg in twists:
        cmd_vel.publish(msg)
        time.sleep(0.05)
    for msg in poses:
        pose.publish(msg)
        time.sleep(0.05)
    for msg in poses[:5]:
        cam.publish(msg)
        time.sleep(0.05)
    print(f"SENT {len(twists)} {len(poses)} 5", flush=True)
    rospy.spin()


def trials(topic: str, count: int, vx: float, services_port: int, robot: str) -> None:
    """Per trial: drive, stop publishing, and time until the ground truth stops moving (10 ms polls)."""
    from geometry_msgs.msg import Twist
    from projectairsim import ProjectAirSimClient

    client = ProjectAirSimClient("127.0.0.1", 0, services_port)
    client.connect_services()

    def position() -> tuple[float, float, float]:
        t = client.request({"method": f"{robot}/GetGroundTruthPose", "params": {}, "version": 1.0})
        return (t["translation"]["x"], t["translation"]["y"], t["translation"]["z"])

    pub = rospy.Publisher(topic, Twist, queue_size=10)
    connected(pub)
    msg = Twist()
    msg.linear.x = vx
    for _ in range(count):
        for _ in range(3):
            pub.publish(msg)
            last = time.monotonic()
            time.sleep(0.1)
        previous, moving_until = position(), last
        while time.monotonic() - moving_until < 0.25 and time.monotonic() - last < 10:
            time.sleep(0.01)
            now, current = time.monotonic(), position()
            if math.dist(previous, current) > 1e-4:
                moving_until = now
            previous = current
        print(f"TRIAL {moving_until - last:.4f}", flush=True)
    client.socket_services.close()


def main(argv: list[str]) -> None:
    rospy.init_node("probe", anonymous=True, disable_signals=False)
    mode, args = argv[0], argv[1:]
    if mode == "watch":
        watch(args[0])
    elif mode == "status":
        status(args[0])
    elif mode == "diagnostics":
        diagnostics(args[0])
    elif mode == "twist":
        twist(args[0], int(args[1]), float(args[2]))
        rospy.spin()
    elif mode == "pose":
        pose(args[0], [float(v) for v in args[1:8]], args[8] if len(args) > 8 else "map")
    elif mode == "bad":
        bad(args[0], args[1])
    elif mode == "huge":
        huge(args[0], int(args[1]), int(args[2]))
    elif mode == "strings" and args[1:2] == ["--every"]:
        strings(args[0], args[3:], float(args[2]))
    elif mode == "strings":
        strings(args[0], args[1:])
    elif mode == "stamped":
        stamped(args)
    elif mode == "trials":
        trials(args[0], int(args[1]), float(args[2]), int(args[3]), args[4])
    else:
        raise SystemExit(f"unknown mode {mode!r}: " + json.dumps(argv))


if __name__ == "__main__":
    main(rospy.myargv(sys.argv)[1:])
