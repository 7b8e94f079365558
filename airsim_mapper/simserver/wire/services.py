"""The services channel: a Rep0 socket served by N worker contexts that dispatch to a method table.

Each worker owns one NNG context (recv -> handle -> send), so a long motion command occupies only its
worker while the others keep answering (protocol.md §1.2, §3.3). Error replies use the real server's
codes: 1 unknown method or handler error, 2 other exception or unparseable request, 3 missing parameter.
"""

from __future__ import annotations

import logging
import threading
from collections.abc import Callable, Iterable
from dataclasses import dataclass
from typing import Any

import pynng

from airsim_mapper.simserver.errors import SimServerError
from airsim_mapper.simserver.wire import protocol

LOG = logging.getLogger("airsim_mapper.simserver.services")

Handler = Callable[[dict[str, Any]], Any]

UNKNOWN_METHOD = 1.0
HANDLER_ERROR = 1.0
INTERNAL_ERROR = 2.0
MISSING_PARAMETER = 3.0


class ServiceError(SimServerError):
    """An error reply a handler wants sent back (code 1 = the real server's `Error`)."""

    def __init__(self, message: str, code: float = HANDLER_ERROR) -> None:
        super().__init__(message)
        self.code = code
        self.message = message


@dataclass(frozen=True)
class Method:
    name: str
    params: tuple[str, ...]
    handler: Handler


class MethodTable:
    """Thread-safe registry of service methods, looked up by exact name."""

    def __init__(self) -> None:
        self._methods: dict[str, Method] = {}
        self._lock = threading.Lock()

    def register(self, name: str, params: Iterable[str], handler: Handler) -> None:
        with self._lock:
            self._methods[name] = Method(name, tuple(params), handler)

    def replace_group(self, old_names: Iterable[str], methods: Iterable[Method]) -> None:
        """Atomically drop `old_names` and register `methods` (a scene swap)."""
        with self._lock:
            for name in old_names:
                self._methods.pop(name, None)
            for method in methods:
                self._methods[method.name] = method

    def get(self, name: str) -> Method | None:
        with self._lock:
            return self._methods.get(name)

    def names(self) -> list[str]:
        with self._lock:
            return sorted(self._methods)


def unknown_method_message(method: str) -> str:
    return f"Requested ServiceMethod {method} is not supported by Request-Response Service"


def missing_parameter_message(param: str, method: str, params: dict[str, Any]) -> str:
    return (
        f"Required parameter '{param}' not provided when calling:{method}. "
        f"Provided parameters:{protocol.dump_params(params)}"
    )


def dispatch(table: MethodTable, raw: bytes) -> bytes:
    """The reply bytes for one raw request (never raises)."""
    try:
        request = protocol.decode_request(raw)
    except protocol.BadRequestError as exc:
        return protocol.encode_error(-1, INTERNAL_ERROR, f"Got bad request message: {exc}")
    method = table.get(request.method)
    if method is None:
        return protocol.encode_error(request.id, UNKNOWN_METHOD, unknown_method_message(request.method))
    for param in method.params:
        if param not in request.params:
            message = missing_parameter_message(param, request.method, request.params)
            return protocol.encode_error(request.id, MISSING_PARAMETER, message)
    try:
        result = method.handler(request.params)
    except ServiceError as exc:
        return protocol.encode_error(request.id, exc.code, exc.message)
    except Exception as exc:  # a handler bug must not kill the worker; report it like the C++ server
        LOG.exception("handler for %s failed", request.method)
        return protocol.encode_error(request.id, INTERNAL_ERROR, f"{type(exc).__name__}: {exc}")
    try:
        return protocol.encode_result(request.id, result)
    except Exception as exc:
        LOG.exception("result of %s could not be packed", request.method)
        return protocol.encode_error(request.id, INTERNAL_ERROR, f"result could not be packed: {exc}")


class ServiceServer:
    """Rep0 listener with `workers` contexts, each served by its own thread."""

    def __init__(self, table: MethodTable, address: str, port: int, workers: int = 32) -> None:
        self.table = table
        self.url = f"tcp://{address}:{port}"
        self._socket = pynng.Rep0(listen=self.url, send_timeout=5000)
        self._contexts = [self._socket.new_context() for _ in range(workers)]
        self._threads = [
            threading.Thread(target=self._serve, args=(context,), name=f"svc-{i}", daemon=True)
            for i, context in enumerate(self._contexts)
        ]
        self._stopping = threading.Event()

    def start(self) -> None:
        for thread in self._threads:
            thread.start()

    def _serve(self, context: pynng.Context) -> None:
        while not self._stopping.is_set():
            try:
                raw = context.recv()
            except pynng.Closed:
                return
            except pynng.NNGException as exc:
                LOG.debug("services recv failed: %s", exc)
                continue
            reply = dispatch(self.table, raw)
            try:
                context.send(reply)
            except pynng.Closed:
                return
            except pynng.NNGException as exc:
                LOG.warning("services reply could not be sent: %s", exc)

    def stop(self) -> None:
        self._stopping.set()
        for context in self._contexts:
            context.close()  # aborts a pending recv; closing contexts before the socket avoids late errors
        for thread in self._threads:
            thread.join(timeout=2.0)
        self._socket.close()
