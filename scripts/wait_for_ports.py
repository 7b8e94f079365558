#!/usr/bin/env python3
"""wait_for_ports: a roslaunch `launch-prefix` that waits until TCP ports accept connections, then runs
the node.

    launch-prefix="wait_for_ports.py 127.0.0.1:8989,8990 --"

roslaunch starts every node at once; a node that connects to the simulator only once (like
scripts/hello_ros.py) would otherwise fail while the headless server is still starting. Exit status 1,
without running the node, if the ports do not open within --timeout seconds.
"""

from __future__ import annotations

import argparse
import os
import socket
import sys
import time


def is_open(host: str, port: int) -> bool:
    with socket.socket() as sock:
        sock.settimeout(1.0)
        return sock.connect_ex((host, port)) == 0


def main(argv: list[str]) -> int:
    if "--" not in argv:
        print(
            "usage: wait_for_ports.py [--timeout S] HOST:PORT[,PORT...] -- COMMAND [ARGS...]", file=sys.stderr
        )
        return 2
    split = argv.index("--")
    parser = argparse.ArgumentParser(description="Wait for TCP ports, then exec a command.")
    parser.add_argument("--timeout", type=float, default=60.0)
    parser.add_argument("where", help="HOST:PORT[,PORT...]")
    args = parser.parse_args(argv[:split])
    command = argv[split + 1 :]
    host, _, ports = args.where.rpartition(":")
    wanted = [int(p) for p in ports.split(",")]
    deadline = time.monotonic() + args.timeout
    while not all(is_open(host or "127.0.0.1", port) for port in wanted):
        if time.monotonic() > deadline:
            print(f"wait_for_ports: {args.where} not open after {args.timeout:.0f} s", file=sys.stderr)
            return 1
        time.sleep(0.2)
    if not command:
        return 0
    os.execvp(command[0], command)
    return 1  # not reached


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
