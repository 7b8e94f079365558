"""The ROS 2 node's executor loop (`ros2_node.spin`) with a callback that fails once, run by .venv-ros2's
Python: prints one JSON line with how many times a 20 Hz timer ran in a second, and whether the loop's thread
still runs."""

from __future__ import annotations

import json
import sys
import threading
import time

import rclpy
from rclpy.executors import MultiThreadedExecutor

from airsim_mapper.engine.ros2_node import spin


def main() -> int:
    rclpy.init()
    node = rclpy.create_node("spin_ros2")
    ticks: list[float] = []

    def tick() -> None:
        ticks.append(time.monotonic())
        if len(ticks) == 3:
            raise RuntimeError("a callback fails")

    node.create_timer(0.05, tick)
    executor = MultiThreadedExecutor(num_threads=2)
    executor.add_node(node)
    done = threading.Event()
    spinner = threading.Thread(target=spin, args=(executor, node.context, done), daemon=True)
    spinner.start()
    time.sleep(1.0)
    print(json.dumps({"ticks": len(ticks), "spinning": spinner.is_alive()}), flush=True)
    done.set()
    executor.wake()
    spinner.join(timeout=2.0)
    executor.shutdown(timeout_sec=1.0)
    node.destroy_node()
    rclpy.try_shutdown()
    return 0


if __name__ == "__main__":
    sys.exit(main())
