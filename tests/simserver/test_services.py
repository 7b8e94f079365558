"""Service dispatch: the real server's error codes and messages, and results double-encoded."""

from __future__ import annotations

import msgpack
import pytest

from airsim_mapper.simserver.wire import protocol
from airsim_mapper.simserver.wire.services import MethodTable, ServiceError, dispatch


def request(method: str, params: dict, request_id: int = 5) -> bytes:
    packed = {"method": method.encode(), "params": {"data": msgpack.packb(params, use_bin_type=True)}}
    return msgpack.packb({**packed, "version": 1.0, "id": request_id}, use_bin_type=True)


def reply(raw: bytes) -> tuple[str, object]:
    outer = msgpack.unpackb(raw, raw=False)
    key = "result" if "result" in outer else "error"
    return key, msgpack.unpackb(outer[key]["data"], raw=False)


@pytest.fixture
def table() -> MethodTable:
    methods = MethodTable()
    methods.register("/Sim/Add", ("a", "b"), lambda p: p["a"] + p["b"])
    methods.register("/Sim/Fail", (), lambda p: (_ for _ in ()).throw(ServiceError("went wrong")))
    methods.register("/Sim/Bug", (), lambda p: 1 / 0)
    methods.register("/Sim/Odd", (), lambda p: object())
    return methods


def test_a_known_method_replies_with_its_result(table):
    assert reply(dispatch(table, request("/Sim/Add", {"a": 2, "b": 3, "extra": 1}))) == ("result", 5)


def test_an_unknown_method_gets_code_1_with_the_real_message(table):
    assert reply(dispatch(table, request("/Sim/Nope", {}))) == (
        "error",
        {
            "code": 1.0,
            "message": "Requested ServiceMethod /Sim/Nope is not supported by Request-Response Service",
        },
    )


def test_a_missing_parameter_gets_code_3_naming_it(table):
    kind, error = reply(dispatch(table, request("/Sim/Add", {"a": 2})))
    assert kind == "error"
    assert error == {
        "code": 3.0,
        "message": "Required parameter 'b' not provided when calling:/Sim/Add. Provided parameters:{\"a\":2}",
    }


def test_a_handler_error_gets_code_1_with_its_message(table):
    assert reply(dispatch(table, request("/Sim/Fail", {}))) == (
        "error",
        {"code": 1.0, "message": "went wrong"},
    )


def test_an_unexpected_exception_gets_code_2(table):
    assert reply(dispatch(table, request("/Sim/Bug", {}))) == (
        "error",
        {"code": 2.0, "message": "ZeroDivisionError: division by zero"},
    )


def test_a_result_that_cannot_be_packed_gets_code_2(table):
    kind, error = reply(dispatch(table, request("/Sim/Odd", {})))
    assert kind == "error" and error["code"] == 2.0
    assert error["message"].startswith("result could not be packed:")


def test_garbage_bytes_get_a_msgpack_error_reply_not_plain_text(table):
    outer = msgpack.unpackb(dispatch(table, b"\x00\xffnot msgpack"), raw=False)
    assert outer["id"] == -1
    error = msgpack.unpackb(outer["error"]["data"], raw=False)
    assert error["code"] == 2.0 and error["message"].startswith(
        "Got bad request message: request is not msgpack"
    )


def test_replace_group_swaps_scene_methods_atomically(table):
    table.replace_group(["/Sim/Add"], [protocol_method("/Sim/New")])
    assert table.get("/Sim/Add") is None
    assert table.get("/Sim/New") is not None
    assert "/Sim/New" in table.names()


def protocol_method(name: str):
    from airsim_mapper.simserver.wire.services import Method

    return Method(name, (), lambda p: True)


def test_reply_ids_echo_the_request_id(table):
    outer = msgpack.unpackb(dispatch(table, request("/Sim/Add", {"a": 1, "b": 1}, request_id=42)), raw=False)
    assert outer["id"] == 42 and outer["version"] == protocol.API_VERSION
