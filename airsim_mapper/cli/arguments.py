"""What the offline commands (airsim-mapper, validate-mapping) share: their exit statuses and the
arguments that name a mapping's scene and the names its templates take."""

from __future__ import annotations

import argparse

EXIT_OK, EXIT_INVALID, EXIT_USAGE = 0, 1, 2
MAPPING_HELP = "the mapping YAML file, or a shipped mapping's name (default, enu)"


def add_scene_arguments(parser: argparse.ArgumentParser) -> None:
    """--simconfigpath, --nodename and --namespace (a command adds its own --scene)."""
    parser.add_argument(
        "--simconfigpath",
        default=None,
        help="the scene config directory (default: ./sim_config/, else the package's sample scenes)",
    )
    parser.add_argument("--nodename", default="projectairsim", help="the node name for <node_name>")
    parser.add_argument("--namespace", default="", help="the value of <namespace> (default: empty)")
