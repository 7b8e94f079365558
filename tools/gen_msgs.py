"""Generate Python for the radar_msgs and uuid_msgs definitions in msg/ into the venv's site-packages.

Debian ships ROS1 but not these two packages. Debian's own genpy generator turns the .msg files into
Python; the result is checked against the upstream ROS1 md5sums so a wrong definition fails loudly.
Nothing is regenerated when the definitions have not changed.
"""

from __future__ import annotations

import hashlib
import importlib
import subprocess
import sys
import sysconfig
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
MSG_ROOT = ROOT / "msg"
GENERATOR = Path("/usr/lib/genpy/genmsg_py.py")
SYSTEM_PYTHON = "/usr/bin/python3"
PACKAGES = ("uuid_msgs", "radar_msgs")  # in dependency order
INCLUDES = {
    "std_msgs": Path("/usr/share/std_msgs/msg"),
    "geometry_msgs": Path("/usr/share/geometry_msgs/msg"),
}
# Upstream ROS1 md5sums: a definition that differs from upstream on the wire fails here.
EXPECTED_MD5 = {
    "radar_msgs.msg.RadarScan": "6dfacef1e665538dbd8e159d5ce7a97a",
    "radar_msgs.msg.RadarTrack": "3344659e36aff40bd4f09e82be663ec5",
    "radar_msgs.msg.RadarTracks": "d068321616577632690aba69b8985e75",
}
STAMP_NAME = ".airsim-mapper-msgs"


class GenerationError(RuntimeError):
    """The messages could not be generated or do not match upstream."""


def definitions_digest() -> str:
    digest = hashlib.sha256()
    for path in sorted(MSG_ROOT.rglob("*.msg")):
        digest.update(path.relative_to(MSG_ROOT).as_posix().encode())
        digest.update(path.read_bytes())
    digest.update(GENERATOR.read_bytes() if GENERATOR.exists() else b"")
    return digest.hexdigest()


def include_args() -> list[str]:
    args = [f"-I{name}:{path}" for name, path in INCLUDES.items()]
    args += [f"-I{pkg}:{MSG_ROOT / pkg / 'msg'}" for pkg in PACKAGES]
    return args


def generate(out_root: Path) -> None:
    if not GENERATOR.exists():
        raise GenerationError(f"{GENERATOR} is missing: install Debian's python3-genpy (make setup does)")
    for pkg in PACKAGES:
        msgs = sorted(str(p) for p in (MSG_ROOT / pkg / "msg").glob("*.msg"))
        out = out_root / pkg / "msg"
        base = [SYSTEM_PYTHON, str(GENERATOR), "-p", pkg, "-o", str(out), *include_args()]
        for extra in (msgs, ["--initpy"]):
            run = subprocess.run([*base, *extra], capture_output=True, text=True)
            if run.returncode != 0:
                raise GenerationError(f"genmsg_py failed for {pkg}:\n{run.stdout}{run.stderr}")
        (out_root / pkg / "__init__.py").write_text("")


def verify() -> None:
    importlib.invalidate_caches()
    for dotted, expected in EXPECTED_MD5.items():
        module_name, cls_name = dotted.rsplit(".", 1)
        module = importlib.import_module(module_name)
        actual = getattr(module, cls_name)._md5sum
        if actual != expected:
            raise GenerationError(f"{dotted} md5sum {actual} differs from upstream {expected}")


def main() -> int:
    site = Path(sysconfig.get_paths()["purelib"])
    stamp = site / STAMP_NAME
    want = definitions_digest()
    try:
        if stamp.exists() and stamp.read_text() == want:
            verify()
            print("setup: radar_msgs/uuid_msgs: up to date")
            return 0
        generate(site)
        verify()
    except (GenerationError, ImportError) as exc:
        print(f"setup: error: {exc}", file=sys.stderr)
        return 1
    stamp.write_text(want)
    print(f"setup: generated radar_msgs and uuid_msgs into {site} (md5sums match upstream)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
