"""The node's settings: command line, then private parameter, then default; --namespace as a ROS name."""

from __future__ import annotations

from pathlib import Path

import pytest

from airsim_mapper.cli.node import SettingError, parse_args, resolve_settings
from airsim_mapper.mapping.names import resolve_namespace


def params(**values):
    def get(name: str):
        return values[name.removeprefix("~")]  # KeyError when unset, as rospy.get_param

    return get


def given(argv: list[str]) -> dict:
    args = parse_args(argv)
    return {
        name: getattr(args, name)
        for name in (
            "address",
            "topicsport",
            "servicesport",
            "simconfigpath",
            "mapping",
            "scene",
            "namespace",
        )
    }


def test_the_command_line_wins_then_the_parameter_then_the_default(tmp_path, monkeypatch) -> None:
    monkeypatch.chdir(tmp_path)
    (tmp_path / "sim_config").mkdir()
    resolved = resolve_settings(
        given(["--scene", "a.jsonc", "--topicsport", "9000"]),
        params(scene="b.jsonc", mapping="enu", servicesport="9001"),
    )
    assert resolved["scene"].value == "a.jsonc" and resolved["scene"].source == "command line"
    assert resolved["topicsport"].value == 9000
    assert (resolved["mapping"].value, resolved["mapping"].source) == ("enu", "parameter ~mapping")
    assert (resolved["servicesport"].value, resolved["servicesport"].source) == (
        9001,
        "parameter ~servicesport",
    )
    assert (resolved["address"].value, resolved["address"].source) == ("127.0.0.1", "default")
    assert resolved["simconfigpath"].value == "sim_config/"


def test_a_parameter_of_the_wrong_type_is_an_error() -> None:
    with pytest.raises(SettingError, match=r"parameter ~topicsport: 'abc' is not a valid int"):
        resolve_settings(given([]), params(topicsport="abc"))


def test_the_default_sim_config_falls_back_to_the_package_s_own(tmp_path, monkeypatch) -> None:
    monkeypatch.chdir(tmp_path)  # rosrun from $HOME: no ./sim_config
    resolved = resolve_settings(given([]), params())["simconfigpath"]
    assert Path(resolved.value) == Path(__file__).resolve().parent.parent / "sim_config"
    assert "does not exist here, so the package's own" in resolved.source
    explicit = resolve_settings(given(["--simconfigpath", "sim_config/"]), params())["simconfigpath"]
    assert explicit.value == "sim_config/"  # given on purpose: kept, and its absence reported later


@pytest.mark.parametrize(
    ("namespace", "node_namespace", "expected"),
    [
        ("", "/", ""),
        ("", "/sim1/", "/sim1"),
        ("sim1", "/", "/sim1"),
        ("sim1", "/fleet/", "/fleet/sim1"),
        ("/sim1", "/fleet/", "/sim1"),
        ("/sim1/", "/", "/sim1"),
        ("a/b", "/x", "/x/a/b"),
    ],
)
def test_namespace_resolves_like_a_ros_name(namespace, node_namespace, expected) -> None:
    assert resolve_namespace(namespace, node_namespace) == expected
