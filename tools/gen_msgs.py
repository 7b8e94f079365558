"""Build the message space: radar_msgs and uuid_msgs from msg/, laid out the way ROS1 finds packages.

Debian ships ROS1 but not these two packages. Debian's own genpy generator turns the .msg files into
Python, checked against the upstream ROS1 md5sums so that a wrong definition fails loudly. A message space
is a catkin-style devel space holding only these two packages:

    setup.bash                          sourced: extends ROS_PACKAGE_PATH and PYTHONPATH with the two below
    share/<pkg>/package.xml, msg/*.msg  what rospack, rosmsg and rosbag's definitions find
    lib/python3/dist-packages/<pkg>/    the generated Python that rostopic, rqt and any node import

`make setup` builds it at devel/ of the checkout and points the venv at its Python with a .pth file; the
wheel's build hook (setup.py) builds it inside the package (airsim_mapper/ros/) with a .pth file of its own.
Either way the bridge imports the same generated modules that Debian's tools see once setup.bash is sourced.
"""

from __future__ import annotations

import argparse
import hashlib
import shutil
import subprocess
import sys
import sysconfig
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
MSG_ROOT = ROOT / "msg"
GENERATOR = Path("/usr/lib/genpy/genmsg_py.py")
# -E: a build environment's PYTHONPATH (pip's build isolation hides dist-packages) must not reach genpy;
# -B: no bytecode in the space
SYSTEM_PYTHON = ("/usr/bin/python3", "-E", "-B")
PACKAGES = ("uuid_msgs", "radar_msgs")  # in dependency order
INCLUDES = {
    "std_msgs": Path("/usr/share/std_msgs/msg"),
    "geometry_msgs": Path("/usr/share/geometry_msgs/msg"),
}
# Upstream ROS1 md5sums: a definition that differs from upstream on the wire fails here.
EXPECTED_MD5 = {
    "radar_msgs/RadarScan": "6dfacef1e665538dbd8e159d5ce7a97a",
    "radar_msgs/RadarTrack": "3344659e36aff40bd4f09e82be663ec5",
    "radar_msgs/RadarTracks": "d068321616577632690aba69b8985e75",
}
PYTHON_DIR = Path("lib", "python3", "dist-packages")
SETUP_FILE = "setup.bash"
STAMP_NAME = ".airsim-mapper-msgs"
PTH_NAME = "airsim_mapper_msgs.pth"
CHECKOUT_SPACE = ROOT / "devel"
SETUP_BASH = """\
# airsim-mapper's message space: source it (bash) so that ROS's own tools and nodes (rostopic, rosbag,
# rosmsg, rqt) find radar_msgs and uuid_msgs. Sourcing it twice changes nothing.
_airsim_mapper_space="$(cd "$(dirname "${BASH_SOURCE[0]:-$0}")" && pwd)"
case ":${ROS_PACKAGE_PATH:-}:" in
    *":$_airsim_mapper_space/share:"*) ;;
    *) export ROS_PACKAGE_PATH="$_airsim_mapper_space/share${ROS_PACKAGE_PATH:+:$ROS_PACKAGE_PATH}" ;;
esac
case ":${PYTHONPATH:-}:" in
    *":$_airsim_mapper_space/%(python)s:"*) ;;
    *) export PYTHONPATH="$_airsim_mapper_space/%(python)s${PYTHONPATH:+:$PYTHONPATH}" ;;
esac
unset _airsim_mapper_space
"""


class GenerationError(RuntimeError):
    """The messages could not be generated or do not match upstream."""


def definitions_digest() -> str:
    """What the space is made from: the definitions, the generator and this file."""
    digest = hashlib.sha256()
    for path in sorted(MSG_ROOT.rglob("*")):
        if path.is_file():
            digest.update(path.relative_to(MSG_ROOT).as_posix().encode())
            digest.update(path.read_bytes())
    digest.update(GENERATOR.read_bytes() if GENERATOR.exists() else b"")
    digest.update(Path(__file__).read_bytes())
    return digest.hexdigest()


def include_args() -> list[str]:
    args = [f"-I{name}:{path}" for name, path in INCLUDES.items()]
    args += [f"-I{pkg}:{MSG_ROOT / pkg / 'msg'}" for pkg in PACKAGES]
    return args


def generate_python(out_root: Path) -> None:
    """The Python of every package under `out_root`, by Debian's genpy."""
    if not GENERATOR.exists():
        raise GenerationError(f"{GENERATOR} is missing: install Debian's python3-genpy (make setup does)")
    for pkg in PACKAGES:
        msgs = sorted(str(p) for p in (MSG_ROOT / pkg / "msg").glob("*.msg"))
        out = out_root / pkg / "msg"
        base = [*SYSTEM_PYTHON, str(GENERATOR), "-p", pkg, "-o", str(out), *include_args()]
        for extra in (msgs, ["--initpy"]):
            run = subprocess.run([*base, *extra], capture_output=True, text=True)
            if run.returncode != 0:
                raise GenerationError(f"genmsg_py failed for {pkg}:\n{run.stdout}{run.stderr}")
        (out_root / pkg / "__init__.py").write_text("")


def verify(space: Path) -> None:
    """The generated classes, imported by the system interpreter as Debian's tools import them, carry the
    upstream md5sums."""
    code = (
        "import sys\n"
        "sys.path.insert(0, sys.argv.pop(1))\n"
        "import roslib.message as m\n"
        "for t in sys.argv[1:]:\n"
        "    print(t, m.get_message_class(t)._md5sum)\n"
    )
    python = str(space / PYTHON_DIR)
    run = subprocess.run([*SYSTEM_PYTHON, "-c", code, python, *EXPECTED_MD5], capture_output=True, text=True)
    if run.returncode != 0:
        raise GenerationError(f"the generated messages do not import:\n{run.stderr}")
    actual = dict(line.split() for line in run.stdout.splitlines())
    for name, expected in EXPECTED_MD5.items():
        if actual.get(name) != expected:
            raise GenerationError(f"{name} md5sum {actual.get(name)} differs from upstream {expected}")


def build_space(space: Path) -> None:
    """A fresh message space at `space` (see the module docstring), verified."""
    if space.exists():
        shutil.rmtree(space)
    for pkg in PACKAGES:
        share = space / "share" / pkg
        shutil.copytree(MSG_ROOT / pkg, share)
        if not (share / "package.xml").is_file():
            raise GenerationError(f"{MSG_ROOT / pkg / 'package.xml'} is missing")
    generate_python(space / PYTHON_DIR)
    (space / SETUP_FILE).write_text(SETUP_BASH % {"python": PYTHON_DIR.as_posix()})
    verify(space)


def setup_checkout(space: Path = CHECKOUT_SPACE) -> str:
    """`make setup`'s step: the checkout's space (rebuilt only when its sources changed) and a .pth file
    that puts its Python on the running interpreter's (the venv's) path. Returns what was done."""
    want = definitions_digest()
    stamp = space / STAMP_NAME
    site = Path(sysconfig.get_paths()["purelib"])
    _remove_in_venv_copies(site)
    pth = site / PTH_NAME
    pth_line = f"{space / PYTHON_DIR}\n"
    if stamp.is_file() and stamp.read_text() == want and (space / SETUP_FILE).is_file():
        verify(space)
        done = f"radar_msgs/uuid_msgs: up to date in {space}"
    else:
        build_space(space)
        stamp.write_text(want)
        done = f"generated radar_msgs and uuid_msgs into {space} (md5sums match upstream)"
    if not pth.is_file() or pth.read_text() != pth_line:
        pth.write_text(pth_line)
    return done


def _remove_in_venv_copies(site: Path) -> None:
    """Earlier setups generated the packages straight into the venv; the space replaces them."""
    old_stamp = site / STAMP_NAME
    if old_stamp.is_file():
        for pkg in PACKAGES:
            shutil.rmtree(site / pkg, ignore_errors=True)
        old_stamp.unlink()


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--space", type=Path, help="only build a message space at this directory")
    args = parser.parse_args(argv)
    try:
        if args.space is not None:
            build_space(args.space.resolve())
            print(f"setup: built the message space {args.space}")
        else:
            print(f"setup: {setup_checkout()}")
    except GenerationError as exc:
        print(f"setup: error: {exc}", file=sys.stderr)
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
