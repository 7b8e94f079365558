"""What the offline commands (airsim-mapper, validate-mapping) share: their exit statuses, the arguments
that name a mapping's scene and the names its templates take, and the parsing of their command line."""

from __future__ import annotations

import argparse
from collections.abc import Sequence

from airsim_mapper.common.resources import sim_config_dir

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


def parse(parser: argparse.ArgumentParser, argv: Sequence[str] | None) -> argparse.Namespace | int:
    """`argv` parsed, --simconfigpath (where the command has one) resolved to the directory it means; or
    the exit status when argparse has printed its usage or help message instead."""
    try:
        args = parser.parse_args(argv)
    except SystemExit as stop:
        return EXIT_OK if stop.code == 0 else EXIT_USAGE
    if hasattr(args, "simconfigpath"):
        args.simconfigpath = sim_config_dir(args.simconfigpath)
    return args
