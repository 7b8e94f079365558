"""The receive floor: the simulator's poses taken by the bridge's own receive loop, with no ROS at all.

The real projectairsim client connects and loads the scene; the bridge's `SimLink` receives (its loop, its
decoding), and each robot's `actual_pose` callback only notes the latency (receive time - the message's
`time_stamp`). With `--camera` each robot's scene camera is subscribed too and dropped on arrival, so the
socket carries what it carries for the bridge. What the server and one Python receive thread cost before
any publisher is involved: no bridge and no forwarder can deliver a pose sooner.

It prints `measuring` and `done` as the probe does, and writes the probe's JSON (the topics named as the
bridge names them, so the report treats both alike) with its own CPU as `receiver_cpu_cores`.

    python -m tools.bench.receive_floor --topicsport P --servicesport S --simconfigpath DIR --scene FILE
        --out FILE [--camera] [--warmup S] [--duration S]
"""

from __future__ import annotations

import os
import threading
import time
from typing import Any

from tools.bench import scenes
from tools.bench.forwarder import load_scene, scene_arguments
from tools.bench.probe import TopicRecord, summary, write_result


def main(argv: list[str] | None = None) -> int:
    from airsim_mapper.engine.sim_link import SimLink

    parser = scene_arguments(__doc__.splitlines()[0])
    parser.add_argument("--out", required=True)
    parser.add_argument("--camera", action="store_true", help="also receive each robot's scene image")
    parser.add_argument("--warmup", type=float, default=2.0)
    parser.add_argument("--duration", type=float, default=8.0)
    args = parser.parse_args(argv)
    client, scene = load_scene(args)
    link = SimLink(client)
    records: dict[str, TopicRecord] = {}
    recording = threading.Event()

    def note_latency(record: TopicRecord) -> Any:
        def callback(_topic: Any, msg: dict) -> None:
            now_ns = time.time_ns()
            record.seen += 1
            if recording.is_set():
                record.latencies_ms.append((now_ns - msg["time_stamp"]) / 1e6)

        return callback

    for number, actor in enumerate(scene["actors"], start=1):
        sim = f"/Sim/{scene['id']}/robots/{actor['name']}"
        record = records[scenes.pose_topic(number)] = TopicRecord()
        link.subscribe(f"{sim}/actual_pose", note_latency(record))
        if args.camera:
            link.subscribe(f"{sim}/sensors/Cam/scene_camera", lambda _topic, _msg: None)
    while any(r.seen == 0 for r in records.values()):
        time.sleep(0.05)
    time.sleep(args.warmup)
    recording.set()
    started, cpu_started = time.monotonic(), time.process_time()
    print("measuring", flush=True)
    time.sleep(args.duration)
    recording.clear()
    seconds, cpu = time.monotonic() - started, time.process_time() - cpu_started
    print("done", flush=True)
    result = {
        "seconds": seconds,
        "topics": {topic: summary(record, seconds) for topic, record in records.items()},
        "receiver_cpu_cores": cpu / seconds,
    }
    write_result(args.out, result)
    os._exit(0)  # the client's threads are not for the measurement to wait on


if __name__ == "__main__":
    raise SystemExit(main())
