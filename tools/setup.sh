#!/usr/bin/env bash
# Idempotent, complete setup: Debian's ROS1 packages, the venv, the project and its pinned dependencies,
# and the message space devel/ (radar_msgs/uuid_msgs for the venv and, sourced, for ROS's own tools). A second run with everything present changes nothing.
# Then .venv-ros2 for the ROS 2 flavour (tools/setup_ros2.sh).
set -euo pipefail
cd "$(dirname "$0")/.."

say() { printf 'setup: %s\n' "$*"; }

# 1. Debian packages (apt only when something is missing).
mapfile -t packages < <(grep -v '^#' tools/apt-packages.txt | grep -v '^$')
missing=()
for p in "${packages[@]}"; do
    dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q 'install ok installed' || missing+=("$p")
done
if ((${#missing[@]})); then
    if [ "$(id -u)" != 0 ]; then
        echo "setup: missing Debian packages: ${missing[*]}" >&2
        echo "setup: run as root: apt-get update && DEBIAN_FRONTEND=noninteractive apt-get install -y --no-install-recommends ${missing[*]}" >&2
        exit 1
    fi
    say "installing ${#missing[@]} Debian packages: ${missing[*]}"
    apt-get update -q >/dev/null
    DEBIAN_FRONTEND=noninteractive apt-get install -y -q --no-install-recommends "${missing[@]}" >/dev/null
else
    say "Debian packages: all ${#packages[@]} present"
fi

# 2. The venv, from the system interpreter so that it sees Debian's rospy.
if [ ! -x .venv/bin/python ]; then
    say "creating .venv"
    /usr/bin/python3 -m venv --system-site-packages .venv
fi

# 3. The project, editable, with its pinned dependencies (only when pyproject.toml changed).
stamp=.venv/.airsim-mapper-deps
want="$(sha256sum pyproject.toml | cut -d' ' -f1) $(pwd)"
if [ "$(cat "$stamp" 2>/dev/null)" != "$want" ] || ! .venv/bin/python -c 'import airsim_mapper, projectairsim' 2>/dev/null; then
    say "installing the project and its dependencies into .venv (log: .venv/pip.log)"
    if ! .venv/bin/python -m pip install -e '.[test]' >.venv/pip.log 2>&1; then
        tail -n 30 .venv/pip.log >&2
        echo "setup: pip install failed (full log: .venv/pip.log)" >&2
        exit 1
    fi
    echo "$want" >"$stamp"
else
    say "Python dependencies: up to date"
fi

# 4. radar_msgs / uuid_msgs, generated from msg/ into devel/ (source devel/setup.bash for rostopic, rosbag,
#    rosmsg), md5sums verified; a .pth file puts their Python on the venv's path.
.venv/bin/python tools/gen_msgs.py

# 5. ROS 2: .venv-ros2 with the ROS 2 wheels, the project, and tf2_msgs/radar_msgs generated into it.
bash tools/setup_ros2.sh
