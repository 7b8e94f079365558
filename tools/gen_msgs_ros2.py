"""Build the ROS 2 message packages that PyPI has no wheel for (tf2_msgs, radar_msgs) into .venv-ros2.

Each package under msg/ros2/ is an ordinary ament_cmake package (package.xml, CMakeLists.txt, msg/). It is
configured, built and installed by CMake with the rosidl generators from the venv's wheels, with the venv
itself as the install prefix, so that its pieces land where the wheels' own message packages are:

    lib/lib<pkg>__rosidl_*.so                    the C/C++ type supports (the wheels' bootstrapper puts lib/
                                                 on LD_LIBRARY_PATH when the venv's Python starts)
    lib/python3.11/site-packages/<pkg>/          the Python classes and their C extension
    share/<pkg>/msg/*.msg, *.idl, *.json         the definitions and type descriptions (with the RIHS01 hash)
    share/ament_index/resource_index/...         what ament's index finds

The generated hashes are checked against the upstream ones (computed by the same generators from
upstream's .msg files; for TFMessage the hash a Jazzy install reports), so a definition that would not
match a user's ROS 2 install on the wire fails here. Run by `make setup` with the venv's interpreter;
rebuilt only when the definitions, the wheels or this file change.
"""

from __future__ import annotations

import argparse
import hashlib
import json
import os
import shutil
import subprocess
import sys
import sysconfig
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
MSG_ROOT = ROOT / "msg" / "ros2"
PACKAGES = ("tf2_msgs", "radar_msgs")
EXPECTED_RIHS01 = {
    "tf2_msgs/msg/TFMessage": "RIHS01_e369d0f05a23ae52508854b66f6aa0437f3449d652e8cbf22d5abe85d020f087",
    "radar_msgs/msg/RadarReturn": "RIHS01_d2faa185f22c2cf578cf2dfd69e05ce6262d1a716f2fd3ea219e9db31e1ed2f0",
    "radar_msgs/msg/RadarScan": "RIHS01_9d270e9c9d9e2509e93e7c688fd8a813d75e43a6a37ef982e63e24e80e535cdc",
    "radar_msgs/msg/RadarTrack": "RIHS01_d86db60d39b58cd7422505ca7aa1609ada6d9701c3648f499ff0dc2a96801043",
    "radar_msgs/msg/RadarTracks": "RIHS01_3bd7d07e46d13682e4d9fa9fdb2c5f4ed9b1c4ebb08a34b31dbfc2c3ff601889",
}
# The wheels were built in a manylinux image: their exported CMake targets name that image's Python and
# numpy headers, which CMake refuses as missing paths. They are pointed at this interpreter's.
WHEEL_PYTHON_INCLUDE = "/opt/python/cp311-cp311/include/python3.11"
WHEEL_NUMPY_INCLUDE = "/opt/python/cp311-cp311/lib/python3.11/site-packages/numpy/_core/include"
STAMP_NAME = ".airsim-mapper-ros2-msgs"


class GenerationError(RuntimeError):
    """The messages could not be generated or do not match upstream."""


def prefix() -> Path:
    """The venv this interpreter runs in: the install prefix of the generated packages."""
    return Path(sys.prefix)


def digest(venv: Path) -> str:
    """What the packages are made from: the definitions, the installed wheels and this file."""
    h = hashlib.sha256()
    for path in sorted(MSG_ROOT.rglob("*")):
        if path.is_file():
            h.update(path.relative_to(MSG_ROOT).as_posix().encode())
            h.update(path.read_bytes())
    site = Path(sysconfig.get_paths()["purelib"])
    h.update(" ".join(sorted(p.name for p in site.glob("ros_*.dist-info"))).encode())
    h.update(Path(__file__).read_bytes())
    h.update(str(venv).encode())
    return h.hexdigest()


def fix_wheel_paths(venv: Path) -> int:
    """Point the wheels' exported CMake targets at this interpreter's headers; returns the files changed."""
    import numpy

    python_include = sysconfig.get_paths()["include"]
    changed = 0
    for path in venv.glob("share/*/cmake/*.cmake"):
        text = path.read_text()
        if WHEEL_PYTHON_INCLUDE in text or WHEEL_NUMPY_INCLUDE in text:
            text = text.replace(WHEEL_PYTHON_INCLUDE, python_include)
            path.write_text(text.replace(WHEEL_NUMPY_INCLUDE, numpy.get_include()))
            changed += 1
    return changed


def build_env(venv: Path) -> dict[str, str]:
    """ament's index and the wheels' libraries for CMake and the generators it runs; no ROS1 paths."""
    env = {k: v for k, v in os.environ.items() if not k.startswith(("ROS_", "AMENT_", "CMAKE_PREFIX"))}
    env.pop("PYTHONPATH", None)
    env["AMENT_PREFIX_PATH"] = str(venv)
    env["LD_LIBRARY_PATH"] = os.pathsep.join(filter(None, [str(venv / "lib"), env.get("LD_LIBRARY_PATH")]))
    return env


def build_package(pkg: str, venv: Path, build_root: Path) -> None:
    """Configure, build and install one package into the venv."""
    source = MSG_ROOT / pkg
    build = build_root / pkg
    shutil.rmtree(build, ignore_errors=True)
    configure = [
        "cmake", "-S", str(source), "-B", str(build),
        f"-DCMAKE_PREFIX_PATH={venv}", f"-DCMAKE_INSTALL_PREFIX={venv}",
        f"-DPython3_EXECUTABLE={venv / 'bin' / 'python'}", "-DBUILD_TESTING=OFF",
    ]  # fmt: skip
    steps = (configure, ["cmake", "--build", str(build), "-j2"], ["cmake", "--install", str(build)])
    log = build_root / f"{pkg}.log"
    with log.open("w") as out:
        for step in steps:
            run = subprocess.run(step, stdout=out, stderr=subprocess.STDOUT, env=build_env(venv))
            if run.returncode != 0:
                tail = "".join(log.read_text().splitlines(keepends=True)[-30:])
                raise GenerationError(f"{' '.join(step[:2])} failed for {pkg} (log: {log}):\n{tail}")


def generated_hashes(venv: Path) -> dict[str, str]:
    """The RIHS01 hash of every generated message, from its type description."""
    hashes = {}
    for pkg in PACKAGES:
        for path in sorted((venv / "share" / pkg / "msg").glob("*.json")):
            for entry in json.loads(path.read_text())["type_hashes"]:
                if entry["type_name"].startswith(f"{pkg}/"):
                    hashes[entry["type_name"]] = entry["hash_string"]
    return hashes


def verify(venv: Path) -> None:
    """Every expected type is generated with its upstream hash and its Python class imports."""
    actual = generated_hashes(venv)
    for name, expected in EXPECTED_RIHS01.items():
        if actual.get(name) != expected:
            raise GenerationError(f"{name} type hash {actual.get(name)} differs from upstream {expected}")
    code = "".join(f"from {n.split('/')[0]}.msg import {n.split('/')[2]}\n" for n in EXPECTED_RIHS01)
    run = subprocess.run([str(venv / "bin" / "python"), "-c", code], capture_output=True, text=True)
    if run.returncode != 0:
        raise GenerationError(f"the generated messages do not import:\n{run.stderr}")


def setup_venv(venv: Path, force: bool = False) -> str:
    """`make setup`'s step: build the packages when their sources changed, verify them; says what it did."""
    stamp = venv / STAMP_NAME
    want = digest(venv)
    if not force and stamp.is_file() and stamp.read_text() == want:
        verify(venv)
        return f"{', '.join(PACKAGES)}: up to date in {venv.name}"
    fixed = fix_wheel_paths(venv)
    build_root = venv / "build"
    build_root.mkdir(exist_ok=True)
    for pkg in PACKAGES:
        build_package(pkg, venv, build_root)
    verify(venv)
    stamp.write_text(want)
    note = f"; {fixed} wheel CMake files pointed at this Python" if fixed else ""
    return f"generated {', '.join(PACKAGES)} into {venv.name} (type hashes match upstream{note})"


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--force", action="store_true", help="rebuild even when nothing changed")
    args = parser.parse_args(argv)
    try:
        print(f"setup: {setup_venv(prefix(), args.force)}")
    except GenerationError as exc:
        print(f"setup: error: {exc}", file=sys.stderr)
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
