"""The ROS 2 flavour's foundation in .venv-ros2: messages cross between two rclpy processes over Fast DDS,
and the generated tf2_msgs and radar_msgs are upstream's."""

from __future__ import annotations

import json
import re
import subprocess
from pathlib import Path

import commentjson
import pytest
from ros2kit import PEER, ROOT, ros2_env, start_peer

from tools.gen_msgs_ros2 import EXPECTED_RIHS01, MSG_ROOT, generated_hashes

pytestmark = pytest.mark.live  # starts rclpy processes

# rosidl's names for the .msg primitive types that differ from their .msg spelling
IDL_NAMES = {"float32": "float", "float64": "double", "byte": "octet", "char": "uint8"}


def idl_type(msg_type: str, package: str) -> str:
    """The type as `get_fields_and_field_types()` spells it for a .msg field type."""
    match = re.fullmatch(r"([\w/]+)(\[(\d*)\])?", msg_type)
    base, array, size = match.group(1), match.group(2), match.group(3)
    if base in IDL_NAMES:
        base = IDL_NAMES[base]
    elif base[0].isupper():
        base = f"{package}/{base}"
    if array is None:
        return base
    return f"{base}[{size}]" if size else f"sequence<{base}>"


def msg_fields(path: Path) -> dict[str, str]:
    """The fields of a .msg file (constants and comments left out), as rosidl names their types."""
    fields = {}
    for line in path.read_text().splitlines():
        line = line.split("#", 1)[0].strip()
        if line and "=" not in line:
            msg_type, name = line.split()
            fields[name] = idl_type(msg_type, path.parent.parent.name)
    return fields


def exchange(python: Path, domain: int, kind: str) -> dict:
    sub = start_peer(python, domain, "sub", kind)
    pub = start_peer(python, domain, "pub", kind)
    try:
        sub_out, sub_err = sub.communicate(timeout=60)
        _, pub_err = pub.communicate(timeout=60)
    finally:
        for proc in (sub, pub):
            if proc.poll() is None:
                proc.kill()
                proc.wait()
    assert sub.returncode == 0, sub_err
    assert pub.returncode == 0, pub_err
    return json.loads(sub_out)


@pytest.mark.parametrize(
    ("kind", "type_name", "size"),
    [("tf", "TFMessage", 2), ("radar", "RadarScan", 5), ("image", "Image", 1920 * 1080 * 3)],
)
def test_a_message_crosses_between_two_rclpy_processes_field_for_field(
    ros2_python, ros_domain, kind, type_name, size
):
    received = exchange(ros2_python, ros_domain, kind)
    assert received == {"kind": kind, "type": type_name, "equal": True, "size": size}


def test_the_generated_types_have_the_fields_of_the_repos_definitions(ros2_python, ros_domain):
    run = subprocess.run(
        [str(ros2_python), str(PEER), "fields"],
        env=ros2_env(ros_domain),
        capture_output=True,
        text=True,
        timeout=60,
    )
    assert run.returncode == 0, run.stderr
    generated = json.loads(run.stdout)
    definitions = sorted(MSG_ROOT.glob("*/msg/*.msg"))
    expected = {f"{path.parent.parent.name}/{path.stem}": msg_fields(path) for path in definitions}
    assert generated == expected
    assert generated["radar_msgs/RadarTrack"]["uuid"] == "unique_identifier_msgs/UUID"


def test_the_generated_type_hashes_are_upstreams(ros2_python):
    assert generated_hashes(ros2_python.parent.parent) == EXPECTED_RIHS01


def test_the_venv_sees_no_ros1_package_and_reads_the_sample_scenes_as_the_main_venv(ros2_python, ros_domain):
    code = (
        "import json, sys, commentjson, std_msgs\n"
        "print(json.dumps([std_msgs.__file__, [commentjson.loads(open(p).read()) for p in sys.argv[1:]]]))\n"
    )
    scenes = sorted(str(p) for p in (ROOT / "sim_config").rglob("*.jsonc"))
    run = subprocess.run(
        [str(ros2_python), "-c", code, *scenes], env=ros2_env(ros_domain), capture_output=True, text=True
    )
    assert run.returncode == 0, run.stderr
    std_msgs_file, parsed = json.loads(run.stdout)
    assert std_msgs_file.startswith(str(ros2_python.parent.parent))
    assert scenes and parsed == [commentjson.loads(Path(p).read_text()) for p in scenes]
    assert (
        "/usr/lib/python3/dist-packages"
        not in subprocess.run(
            [str(ros2_python), "-c", "import sys; print(sys.path)"], capture_output=True, text=True
        ).stdout
    )
