"""Surviving a ROS master restart: rospy registers a node with the master only once, at start.

A restarted master knows nothing of the node, so its topics and services go deaf for every peer that
appears afterwards. `MasterWatch` asks the master once a second whether it knows this node
(`lookupNode`); a master that answers but does not know it is a new master, whatever its pid (in a
container every rosmaster has the same pid). A changed pid counts too. Then `register_all`
repeats what rospy's RegManager does at start-up: every publication, subscription and service of this
process is registered again with the node's XML-RPC URI, and each subscription is told its current
publishers (through the node's own `publisherUpdate`, exactly as the master would tell it).
"""

from __future__ import annotations

import threading
import xmlrpc.client
from collections.abc import Callable
from dataclasses import dataclass

from airsim_mapper.common.logs import ros_logger
from airsim_mapper.engine.errors import EngineError

log = ros_logger("airsim_mapper.master")
POLL_PERIOD_S = 1.0
MASTER_CALLER = "/master"


class ReregisterError(EngineError):
    """The master refused a registration."""

    def __init__(self, kind: str, name: str, message: str) -> None:
        super().__init__(f"the master refused to register {kind} {name}: {message}")


@dataclass(frozen=True)
class Registered:
    publishers: int
    subscribers: int
    services: int

    def __str__(self) -> str:
        return f"{self.publishers} publishers, {self.subscribers} subscribers, {self.services} services"


def _check(kind: str, name: str, reply: list) -> list:
    code, message, value = reply
    if code != 1:
        raise ReregisterError(kind, name, message)
    return value


def register_all(master_uri: str, caller_id: str, node_uri: str) -> Registered:
    """Register every topic and service of this process with the master at `master_uri`."""
    from rospy.impl.registration import get_service_manager, get_topic_manager

    master = xmlrpc.client.ServerProxy(master_uri)
    node = xmlrpc.client.ServerProxy(node_uri)
    topics, services = get_topic_manager(), get_service_manager()
    publications, subscriptions = topics.get_publications(), topics.get_subscriptions()
    for name, data_type in publications:
        _check("publisher", name, master.registerPublisher(caller_id, name, data_type, node_uri))
    for name, data_type in subscriptions:
        reply = master.registerSubscriber(caller_id, name, data_type, node_uri)
        publishers = _check("subscriber", name, reply)
        node.publisherUpdate(MASTER_CALLER, name, publishers)
    service_list = services.get_services()
    for name, service_uri in service_list:
        _check("service", name, master.registerService(caller_id, name, service_uri, node_uri))
    return Registered(len(publications), len(subscriptions), len(service_list))


def ask_master(
    master: xmlrpc.client.ServerProxy, caller_id: str, node_uri: str
) -> tuple[bool, int | None] | None:
    """Whether the master has `caller_id` registered at `node_uri`, and its pid; None when it does not
    answer. One request (`system.multicall`, which rosmaster serves): the watch asks every second.

    A node with any publication, subscription or service (every rospy node publishes /rosout) is known
    to the master it registered with; a restarted master answers "unknown node".
    """
    try:
        calls = xmlrpc.client.MultiCall(master)
        calls.lookupNode(caller_id, caller_id)
        calls.getPid(caller_id)
        (code, _message, uri), (pid_code, _pid_message, pid) = tuple(calls())
    except Exception:
        return None
    return code == 1 and uri == node_uri, pid if pid_code == 1 else None


def needs_registration(known: bool | None, pid: int | None, last_pid: int | None) -> bool:
    """Whether an answering master needs this node's registrations: it does not know the node (a
    restarted master, whatever its pid), or its pid changed. A master that does not answer needs nothing
    yet."""
    if known is None or pid is None:
        return False
    return not known or pid != last_pid


class MasterWatch:
    """A thread, from `start`, that re-registers this node whenever a new master answers (it does not
    know the node, or its pid changed)."""

    def __init__(
        self, period: float = POLL_PERIOD_S, on_reregistered: Callable[[Registered], None] | None = None
    ) -> None:
        import rospy

        self.master_uri = _master_uri()
        self.caller_id = rospy.get_caller_id()
        self.node_uri = rospy.get_node_uri()
        self.period = period
        self.count = 0
        self._on_reregistered = on_reregistered
        self._stop = threading.Event()
        # One HTTP/1.1 connection, kept open between polls (rosmaster keeps it alive): no connect per poll.
        self._master = xmlrpc.client.ServerProxy(self.master_uri)
        answer = ask_master(self._master, self.caller_id, self.node_uri)
        self._pid = None if answer is None else answer[1]  # the master this node registered with
        self._thread = threading.Thread(target=self._run, name="master-watch", daemon=True)

    def start(self) -> None:
        self._thread.start()

    def _new_master(self) -> int | None:
        """The pid of a master that needs our registrations, or None (no answer, or it has them)."""
        answer = ask_master(self._master, self.caller_id, self.node_uri)
        if answer is None:
            self._master = xmlrpc.client.ServerProxy(self.master_uri)  # a new connection next time
            return None
        known, pid = answer
        return pid if needs_registration(known, pid, self._pid) else None

    def _run(self) -> None:
        while not self._stop.wait(self.period):
            pid = self._new_master()
            if pid is None:
                continue
            try:
                registered = register_all(self.master_uri, self.caller_id, self.node_uri)
            except (OSError, xmlrpc.client.Error, ReregisterError) as exc:
                log.warning("the ROS master restarted; registering again failed (%s); will retry", exc)
                continue
            self._pid = pid
            self.count += 1
            log.warning("the ROS master restarted (pid %d); registered again: %s", pid, registered)
            if self._on_reregistered is not None:
                self._on_reregistered(registered)

    def stop(self) -> None:
        self._stop.set()
        if self._thread.is_alive() and threading.current_thread() is not self._thread:
            self._thread.join(timeout=5)


def _master_uri() -> str:
    import rosgraph

    return rosgraph.get_master_uri()
