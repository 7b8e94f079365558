"""A network link between two network namespaces, emulated in user space (run as root by a test).

    wire.py NS_A ADDR_A NS_B ADDR_B DELAY_MS LOSS_PERCENT

Makes one TUN device in each namespace (`ip link set ... netns`), gives it its address with the other end
as its point-to-point peer, and forwards IP packets between the two, each way after DELAY_MS and dropping
LOSS_PERCENT of them at random, as `tc netem delay DELAY_MS loss LOSS_PERCENT` on both ends would. The
impairment starts off: SIGUSR1 switches it on and off, SIGUSR2 takes the link down (every packet dropped,
as a pulled cable) and up again. Prints READY once both devices are up, and a count of forwarded and
dropped packets on SIGINT.

It exists because a kernel without the netem qdisc (CONFIG_NET_SCH_NETEM) cannot delay a veth pair; a TUN
device needs only CONFIG_TUN.
"""

from __future__ import annotations

import collections
import fcntl
import os
import random
import select
import signal
import struct
import subprocess
import sys
import time

TUNSETIFF = 0x400454CA
IFF_TUN = 0x0001
IFF_NO_PI = 0x1000
MTU = 1500


def tun(name: str, namespace: str, address: str, peer: str) -> int:
    """A TUN device `name` moved into `namespace`, up with `address` and `peer`; its file descriptor."""
    fd = os.open("/dev/net/tun", os.O_RDWR)
    fcntl.ioctl(fd, TUNSETIFF, struct.pack("16sH", name.encode(), IFF_TUN | IFF_NO_PI))
    for argv in (
        ["ip", "link", "set", name, "netns", namespace],
        ["ip", "-n", namespace, "addr", "add", address, "peer", peer, "dev", name],
        ["ip", "-n", namespace, "link", "set", name, "up", "mtu", str(MTU)],
        ["ip", "-n", namespace, "link", "set", "lo", "up"],
    ):
        subprocess.run(argv, check=True)
    os.set_blocking(fd, False)
    return fd


def main(argv: list[str]) -> int:
    ns_a, addr_a, ns_b, addr_b, delay_ms, loss_percent = argv
    delay, loss = float(delay_ms) / 1000.0, float(loss_percent) / 100.0
    suffix = str(os.getpid() % 100000)
    fds = (tun(f"wa{suffix}", ns_a, addr_a, addr_b), tun(f"wb{suffix}", ns_b, addr_b, addr_a))
    state = {"impaired": False, "down": False, "stop": False}
    counts = collections.Counter()

    def toggle(key: str) -> None:
        state[key] = not state[key]
        print(f"{key.upper()} {state[key]} {time.monotonic():.4f}", flush=True)

    signal.signal(signal.SIGUSR1, lambda *_: toggle("impaired"))
    signal.signal(signal.SIGUSR2, lambda *_: toggle("down"))
    signal.signal(signal.SIGINT, lambda *_: state.update(stop=True))
    signal.signal(signal.SIGTERM, lambda *_: state.update(stop=True))
    queues = {fds[0]: collections.deque(), fds[1]: collections.deque()}  # per destination: (due, packet)
    other = {fds[0]: fds[1], fds[1]: fds[0]}
    print("READY", flush=True)
    while not state["stop"]:
        now = time.monotonic()
        due = [q[0][0] for q in queues.values() if q]
        timeout = max(0.0, min(due) - now) if due else 0.2
        try:
            readable, _, _ = select.select(list(fds), [], [], timeout)
        except InterruptedError:
            continue
        now = time.monotonic()
        for fd in readable:
            while True:
                try:
                    packet = os.read(fd, 65536)
                except BlockingIOError:
                    break
                except OSError:  # the device went away with its namespace
                    state["stop"] = True
                    break
                if state["down"] or (state["impaired"] and random.random() < loss):
                    counts["dropped"] += 1
                    continue
                queues[other[fd]].append((now + (delay if state["impaired"] else 0.0), packet))
        for fd, queue in queues.items():
            while queue and queue[0][0] <= now:
                _, packet = queue.popleft()
                try:
                    os.write(fd, packet)
                    counts["forwarded"] += 1
                except OSError:  # the device's queue is full: lost, as on a real link
                    counts["dropped"] += 1
    print(f"FORWARDED {counts['forwarded']} DROPPED {counts['dropped']}", flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
