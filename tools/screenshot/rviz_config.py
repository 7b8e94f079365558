"""What RViz's config (`rviz/airsim_mapper.rviz`) shows: its topics, its tf frames, its background."""

from __future__ import annotations

from collections.abc import Iterable
from pathlib import Path
from typing import Any

from tools.rig import ROOT

CONFIG = ROOT / "rviz" / "airsim_mapper.rviz"


def config_topics(path: Path = CONFIG) -> dict[str, str]:
    """Every topic the config's displays subscribe to, with the display class: {topic: class}."""
    import yaml

    config = yaml.safe_load(Path(path).read_text())
    found: dict[str, str] = {}

    def walk(displays: Iterable[Any]) -> None:
        for display in displays or ():
            for key, value in display.items():
                if key.endswith("Topic") and isinstance(value, str) and value:
                    found[value] = display["Class"]
            walk(display.get("Displays", ()))

    walk(config["Visualization Manager"]["Displays"])
    return found


def config_background(path: Path = CONFIG) -> tuple[int, int, int]:
    """The 3D view's background colour in the config (RViz writes it as "R; G; B")."""
    import yaml

    options = yaml.safe_load(Path(path).read_text())["Visualization Manager"]["Global Options"]
    red, green, blue = (int(v) for v in options["Background Color"].split(";"))
    return red, green, blue


def config_frames(path: Path = CONFIG) -> set[str]:
    """The tf frames the config's TF displays enable by name, plus the fixed frame."""
    import yaml

    config = yaml.safe_load(Path(path).read_text())
    manager = config["Visualization Manager"]
    frames = {manager["Global Options"]["Fixed Frame"]}
    for display in manager["Displays"]:
        if display["Class"] == "rviz/TF":
            frames |= {
                k for k, v in display.get("Frames", {}).items() if isinstance(v, dict) and v.get("Value")
            }
    return frames
