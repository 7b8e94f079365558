"""The node's settings: command line, then private parameter, then default; --namespace as a ROS name;
the launch files agree with the node's SETTINGS and the default ports."""

from __future__ import annotations

import os
import xml.etree.ElementTree as ET
from pathlib import Path

import pytest
from harness import ROOT, SIM_CONFIG

from airsim_mapper.cli.node import SETTINGS, SettingError, given_settings, parse_args, resolve_settings
from airsim_mapper.common.ports import SERVICES_PORT, TOPICS_PORT
from airsim_mapper.mapping.names import resolve_namespace

LAUNCH = ROOT / "launch"
# launch defaults that differ from the node's on purpose: roslaunch finds the package's own sim_config
LAUNCH_OWN_DEFAULTS = {"simconfigpath": "$(find projectairsim_ros)/sim_config"}


def params(**values):
    def get(name: str):
        return values[name.removeprefix("~")]  # KeyError when unset, as rospy.get_param

    return get


def given(argv: list[str]) -> dict:
    return given_settings(parse_args(argv))


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
    with pytest.raises(SettingError, match=r"parameter ~topicsport: 'abc' is not a valid port"):
        resolve_settings(given([]), params(topicsport="abc"))


@pytest.mark.parametrize("value", ["0", "-1", "65536", "70000"])
def test_a_port_out_of_range_is_refused_as_a_switch_and_as_a_parameter(value, capsys) -> None:
    with pytest.raises(SystemExit) as exited:
        parse_args(["--topicsport", value])
    assert exited.value.code == 2
    assert f"argument --topicsport: invalid port value: '{value}'" in capsys.readouterr().err
    with pytest.raises(SettingError, match=rf"parameter ~servicesport: {int(value)} is not a valid port"):
        resolve_settings(given([]), params(servicesport=int(value)))
    assert (
        resolve_settings(given(["--topicsport", "65535"]), params(servicesport=1))["servicesport"].value == 1
    )


def test_the_default_sim_config_falls_back_to_the_package_s_own(tmp_path, monkeypatch) -> None:
    monkeypatch.chdir(tmp_path)  # rosrun from $HOME: no ./sim_config
    resolved = resolve_settings(given([]), params())["simconfigpath"]
    assert Path(resolved.value) == SIM_CONFIG
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


def launch_args(name: str) -> tuple[dict[str, str], dict[str, str]]:
    """A launch file's top-level <arg> defaults, and the <param>s of its nodes (name -> value)."""
    root = ET.parse(LAUNCH / name).getroot()
    args = {arg.get("name"): arg.get("default") for arg in root.findall("arg")}
    params = {param.get("name"): param.get("value") for param in root.iter("param")}
    return args, params


def test_projectairsim_launch_passes_every_setting_as_a_parameter_with_the_nodes_default() -> None:
    args, params = launch_args("projectairsim.launch")
    names = [setting.name for setting in SETTINGS]
    assert sorted(set(names) - set(args)) == [], "settings the launch file has no <arg> for"
    assert sorted(set(args) - {*names, "nodename"}) == [], "launch <arg>s that are no setting"
    assert {name: params.get(name) for name in names} == {name: f"$(arg {name})" for name in names}
    expected = {s.name: LAUNCH_OWN_DEFAULTS.get(s.name, str(s.default)) for s in SETTINGS}
    assert {name: args[name] for name in names} == expected


@pytest.mark.parametrize("name", sorted(path.name for path in LAUNCH.glob("*.launch")))
def test_every_launch_file_defaults_to_the_default_ports(name: str) -> None:
    args, _params = launch_args(name)
    ports = (args.get("topicsport"), args.get("servicesport"))
    assert ports == (str(TOPICS_PORT), str(SERVICES_PORT))


def test_the_node_knows_its_final_name_before_init_node_as_rospy_will_make_it() -> None:
    from airsim_mapper.cli.node import node_identity

    name, namespace = node_identity(None, ["node.py"])
    assert name.startswith(f"projectairsim_{os.getpid()}_") and namespace == "/"
    assert node_identity("bridge", ["node.py"])[0] == "bridge"
    assert node_identity("bridge", ["node.py", "__name:=renamed", "__ns:=/fleet"]) == ("renamed", "/fleet/")


def test_the_start_scene_is_read_and_expanded_once_when_the_final_name_is_the_early_one(monkeypatch) -> None:
    from airsim_mapper.cli.node import prepare_node
    from airsim_mapper.mapping import pipeline

    calls = {"expand": 0, "read_scene": 0}

    def counted(name, real):
        def call(*args, **kwargs):
            calls[name] += 1
            return real(*args, **kwargs)

        return call

    monkeypatch.setattr(pipeline, "expand", counted("expand", pipeline.expand))
    monkeypatch.setattr(pipeline, "read_scene", counted("read_scene", pipeline.read_scene))
    settings = {"mapping": "default", "scene": "scene_basic_drone.jsonc", "simconfigpath": str(SIM_CONFIG)}
    early = prepare_node(settings, "projectairsim_1_2", "")
    final = prepare_node(settings, "projectairsim_1_2", "", early)
    assert final.specs is early.specs and calls == {"expand": 1, "read_scene": 1}
    renamed = prepare_node(settings, "other", "", early)  # a __name:= the early look could not know
    assert renamed.scene is early.scene and calls == {"expand": 2, "read_scene": 1}
    # the namespace rosgraph gives early ("/fleet/") and the one rospy's name gives later ("/fleet") are one
    fleet = prepare_node(settings, "other", "", renamed, "/fleet/")
    assert calls["expand"] == 3
    assert prepare_node(settings, "other", "", fleet, "/fleet").specs is fleet.specs and calls["expand"] == 3


def test_the_node_resolves_relative_rule_names_in_its_own_namespace(tmp_path) -> None:
    """A relative name is the node's namespace's: under /fleet it collides with the default mapping's
    /fleet/airsim_node/<robot_name>/actual_pose (the --namespace default is the node's namespace)."""
    from airsim_mapper.cli.node import config_problem

    mine = tmp_path / "mine.yaml"
    mine.write_text(
        "version: 1\nextends: default\nrules:\n  - name: odometry\n"
        "    ros: airsim_node/<robot_name>/actual_pose\n"
    )
    settings = {"mapping": str(mine), "scene": "scene_basic_drone.jsonc", "simconfigpath": str(SIM_CONFIG)}
    prepared, problem = config_problem(settings, "bridge", "/fleet", None, "/fleet/")
    assert prepared is None
    same = "(that is, '/fleet/airsim_node/Drone1/actual_pose') is also used by actual_pose[Drone1]"
    assert same in problem
    prepared, problem = config_problem(settings, "bridge", "/sim2", None, "/fleet/")  # --namespace /sim2
    assert problem is None and prepared is not None


def test_the_master_is_waited_for_by_a_bounded_tcp_connect_first() -> None:
    import socket

    from airsim_mapper.cli.node import listening

    with socket.socket() as server:
        server.bind(("127.0.0.1", 0))
        server.listen()
        port = server.getsockname()[1]
        assert listening(f"http://127.0.0.1:{port}/", timeout=1.0)
    assert not listening(f"http://127.0.0.1:{port}/", timeout=1.0)  # closed now
    assert not listening("http://localhost:notaport/", timeout=1.0)


def test_a_private_parameter_the_node_does_not_read_is_named_with_what_was_meant() -> None:
    from airsim_mapper.cli.settings import SWITCHES_ONLY, unread_parameters

    names = [
        "/fleet/bridge/mapping",  # read
        "/fleet/bridge/mapings",
        "/fleet/bridge/max_frame_mb",
        "/fleet/bridge/extra/nested",
        "/fleet/bridge/Drone1/cam/scene_camera/image/compressed/jpeg_quality",  # its bridge reads it
        "/fleet/other/scene",  # another node's
        "/rosdistro",
    ]
    assert unread_parameters(names, "/fleet/bridge") == [
        "parameter ~extra is not one the node reads",
        "parameter ~mapings is not one the node reads (did you mean 'mapping'?)",
        "parameter ~max_frame_mb is not one the node reads; --max-frame-mb is a command-line switch only",
    ]
    options = {dest.replace("_", "-") for dest in vars(parse_args([]))}
    assert set(SWITCHES_ONLY) <= options  # each is a switch of the node
