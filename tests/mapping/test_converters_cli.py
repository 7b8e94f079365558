"""airsim-mapper converters: the converter catalogue as Markdown, and docs/converters.md generated from it."""

from __future__ import annotations

import re

from harness import ROOT

from airsim_mapper.cli.main import main
from airsim_mapper.convert.catalog import (
    CONVERTERS,
    PUBLISH,
    ROS_TO_SIM,
    SERVE,
    SIM_TO_ROS,
    ConverterInfo,
    converters_markdown,
)

BEGIN, END = "<!-- converters:begin -->", "<!-- converters:end -->"


DOC = ROOT / "docs" / "converters.md"


def documented_table() -> str:
    """The text between the converter-table markers of docs/converters.md, without the blank lines
    around it."""
    text = DOC.read_text(encoding="utf-8")
    assert text.count(BEGIN) == 1 and text.count(END) == 1, f"{DOC} needs one {BEGIN} and one {END}"
    return text.split(BEGIN, 1)[1].split(END, 1)[0].strip("\n") + "\n"


def test_the_documented_converter_table_equals_the_catalogue():
    assert documented_table() == converters_markdown(), (
        "docs/converters.md is out of date: `python -m tools.catalogue` regenerates the lines between "
        f"{BEGIN} and {END} (the output of `airsim-mapper converters`)"
    )


def test_converters_prints_the_table_and_exits_0(capsys):
    assert main(["converters"]) == 0
    assert capsys.readouterr().out == converters_markdown()


def test_the_table_has_one_row_per_converter_in_catalogue_order():
    lines = converters_markdown().splitlines()
    assert lines[0] == "| converter | direction | ROS types | runs on | ROS 2 QoS | what it does |"
    assert lines[1] == "|---|---|---|---|---|---|"
    names = [re.match(r"\| `([a-z_]+)` \|", line).group(1) for line in lines[2:]]
    assert names == list(CONVERTERS)


def test_a_row_names_the_direction_every_ros_type_the_thread_the_qos_and_escapes_bars_in_the_summary():
    services = ("std_srvs/Trigger", "std_srvs/Empty")
    two_types = ConverterInfo("x", ROS_TO_SIM, services, SERVE, "m", "f", "a | b", qos="services")
    one_type = ConverterInfo("y", SIM_TO_ROS, ("sensor_msgs/Image",), PUBLISH, "m", "f", "s")
    light = ConverterInfo(
        "z", SIM_TO_ROS, ("sensor_msgs/Imu",), PUBLISH, "m", "f", "t", inline=True, qos="sensor_data"
    )
    rows = converters_markdown([two_types, one_type, light]).splitlines()[2:]
    assert rows == [
        "| `x` | ROS → sim | `std_srvs/Trigger`, `std_srvs/Empty` | rospy's callback | `services` "
        "| a \\| b |",
        "| `y` | sim → ROS | `sensor_msgs/Image` | its topic's worker | `default` | s |",
        "| `z` | sim → ROS | `sensor_msgs/Imu` | receive thread | `sensor_data` | t |",
    ]


def test_only_light_converters_run_on_the_receive_thread():
    """An image, cloud or radar conversion on the receive thread would hold every other frame behind it."""
    heavy = {"sensor_msgs/PointCloud2", "sensor_msgs/CameraInfo", "radar_msgs/RadarScan"}
    heavy.add("radar_msgs/RadarTracks")
    inline = {name for name, info in CONVERTERS.items() if info.inline}
    assert "pose" in inline and "imu" in inline
    for name in inline:
        info = CONVERTERS[name]
        assert info.direction == SIM_TO_ROS and not info.max_pixels and not heavy & set(info.ros_types), name
