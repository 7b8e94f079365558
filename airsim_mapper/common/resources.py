"""The package's own data: the shipped mappings and the mapping schema, found the same way in a checkout,
an editable install and a wheel.

A checkout has `mappings/` and `schemas/` at its top (links into the package), so the paths the README uses
work there; an installed package has the same two folders inside it. `mapping_path` accepts what a user
types: a file that exists, a shipped mapping's name (`enu`), or a checkout-relative path such as
`mappings/default.yaml` from any directory.
"""

from __future__ import annotations

from pathlib import Path

PACKAGE_DIR = Path(__file__).resolve().parent.parent  # airsim_mapper/, this module being in common/
MAPPINGS_DIR = PACKAGE_DIR / "mappings"
SCHEMA_PATH = PACKAGE_DIR / "schemas" / "mapping.schema.json"
DEFAULT_MAPPING = MAPPINGS_DIR / "default.yaml"
MAPPING_SUFFIX = ".yaml"
DEFAULT_SIM_CONFIG = "sim_config/"


def shipped_mappings() -> list[str]:
    """The names of the mappings that ship with the package (`default`, `enu`, ...)."""
    return sorted(path.stem for path in MAPPINGS_DIR.glob(f"*{MAPPING_SUFFIX}"))


def mapping_path(spec: str | Path) -> Path:
    """The mapping file `spec` stands for: the file itself if it exists; else the shipped mapping of that
    name (with or without `.yaml`); else a relative path resolved inside the package (`mappings/enu.yaml`).
    Anything else comes back unchanged, so that reading it reports the path the user gave."""
    path = Path(spec)
    if path.exists():
        return path
    if path.parent == Path(".") and path.stem in shipped_mappings() and path.suffix in ("", MAPPING_SUFFIX):
        return MAPPINGS_DIR / f"{path.stem}{MAPPING_SUFFIX}"
    if not path.is_absolute() and (PACKAGE_DIR / path).is_file():
        return PACKAGE_DIR / path
    return path


def package_sim_config() -> Path | None:
    """The sample scenes that ship with the package (inside a wheel's package, or a checkout's or catkin
    package's `sim_config/`)."""
    for candidate in (PACKAGE_DIR / "sim_config", PACKAGE_DIR.parent / "sim_config"):
        if candidate.is_dir():
            return candidate
    return None


def sim_config_dir(given: str | Path | None) -> Path:
    """The scene directory a command uses: the one given; else `./sim_config/` where it exists; else the
    package's sample scenes (so `--scene scene_basic_drone.jsonc` works from any directory)."""
    if given is not None:
        return Path(given)
    here = Path(DEFAULT_SIM_CONFIG)
    return here if here.is_dir() else (package_sim_config() or here)


def ros_setup_file() -> Path:
    """The setup file that lets ROS's own tools find the generated radar_msgs/uuid_msgs: the message space
    inside an installed wheel, else the checkout's devel/ (built by `make setup`)."""
    inside = PACKAGE_DIR / "ros" / "setup.bash"
    return inside if inside.is_file() else PACKAGE_DIR.parent / "devel" / "setup.bash"
