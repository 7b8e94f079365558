"""validate-mapping: check a mapping offline and, with --scene, show the bridges it makes; with --ros 2,
its ROS names must also be ones ROS 2 takes.

Exit status: 0 valid, 1 the mapping or scene is invalid (every problem on stderr as FILE:LINE:COL: message;
with --format json, on stdout as {"problems": [{file, line, column, message, key}, ...]}), 2 usage errors
or unreadable files.
"""

from __future__ import annotations

import argparse
import json
import sys
from collections.abc import Sequence
from pathlib import Path

from airsim_mapper.cli.arguments import (
    EXIT_INVALID,
    EXIT_OK,
    EXIT_USAGE,
    MAPPING_HELP,
    add_scene_arguments,
    parse,
)
from airsim_mapper.common.errors import ConfigError
from airsim_mapper.common.resources import mapping_path
from airsim_mapper.mapping.expand import selected
from airsim_mapper.mapping.match import describe
from airsim_mapper.mapping.model import BridgeSpec, MappingDoc
from airsim_mapper.mapping.pipeline import load_and_expand
from airsim_mapper.mapping.report import bridge_row, format_rows, format_table, rule_row
from airsim_mapper.mapping.scene import Scene

__all__ = ["format_table", "load_and_expand", "main"]


def _parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="validate-mapping",
        description="Validate an airsim-mapper mapping YAML (and expand it over a scene).",
    )
    parser.add_argument("mapping", help=MAPPING_HELP)
    parser.add_argument(
        "new",
        nargs="?",
        help="an edited mapping: with --scene, print the bridges it adds, removes and changes (what a "
        "running node's live reload would do)",
    )
    parser.add_argument("--scene", help="a scene config file name inside --simconfigpath: print its bridges")
    add_scene_arguments(parser)
    parser.add_argument(
        "--format",
        choices=("text", "json"),
        default="text",
        help='output format; json also reports problems on stdout, as {"problems": [...]}',
    )
    parser.add_argument(
        "--ros",
        type=int,
        choices=(1, 2),
        default=1,
        help="the ROS whose name rules the mapping's names must also keep (2: ROS 2's, as the node checks "
        "at start-up on ROS 2; default 1)",
    )
    parser.add_argument(
        "--resolved",
        action="store_true",
        help="print the mapping with its extends chain merged in, as YAML (after validating it)",
    )
    return parser


def _print_bridges(bridges: Sequence[BridgeSpec], fmt: str, scene_path: Path) -> None:
    """The bridges as a table (with their count and the scene file they were expanded over) or JSON."""
    if fmt == "json":
        print(json.dumps([bridge_row(b) for b in bridges], indent=2))
    else:
        print(format_table(bridges))
        print(f"\n{len(bridges)} bridges in {scene_path}")


def described(spec: str) -> str:
    """The mapping as the user named it, with the file it resolved to when that is another path."""
    path = mapping_path(spec)
    return spec if path == Path(spec) else f"{spec} ({path})"


def difference(args: argparse.Namespace) -> str:
    """What replacing args.mapping by args.new changes in the bridges of args.scene."""
    from airsim_mapper.mapping.diff import bridge_diff, format_diff

    where = (args.scene, args.simconfigpath, args.nodename, args.namespace)
    _, _, old = load_and_expand(args.mapping, *where)
    _, _, new = load_and_expand(args.new, *where)
    return format_diff(bridge_diff(old, new), old, new)


def resolved_yaml(spec: str) -> str:
    """The valid mapping `spec` with its extends chain merged in, as a standalone YAML mapping."""
    import yaml

    from airsim_mapper.common.files import read_config_text
    from airsim_mapper.mapping.extends import resolved_document
    from airsim_mapper.mapping.loader import load_mapping

    mapping = load_mapping(spec)  # every problem first
    path = mapping_path(spec)
    document = resolved_document(read_config_text(path), str(path))
    header = f"# {described(spec)} with its extends chain merged in ({len(mapping.rules)} rules)\n"
    return header + yaml.safe_dump(document, sort_keys=False, width=110, allow_unicode=True)


def main(argv: Sequence[str] | None = None) -> int:
    """Run validate-mapping with `argv` (default: sys.argv[1:]); return the exit status."""
    args = parse(_parser(), argv)
    if isinstance(args, int):  # usage or help printed
        return args
    try:
        if args.new is not None:
            if args.scene is None:
                print("validate-mapping: comparing two mappings needs --scene", file=sys.stderr)
                return EXIT_USAGE
            print(difference(args))
            return EXIT_OK
        if args.resolved:
            print(resolved_yaml(args.mapping), end="")
            return EXIT_OK
        if args.scene is None:
            from airsim_mapper.mapping.errors import MappingError
            from airsim_mapper.mapping.loader import load_mapping
            from airsim_mapper.mapping.ros2_names import rule_problems

            mapping = load_mapping(args.mapping)
            if args.ros == 2 and rule_problems(mapping):
                raise MappingError(rule_problems(mapping))
            rows = [rule_row(rule) for rule in mapping.rules]
            if args.format == "json":
                print(json.dumps(rows, indent=2))
            else:
                print(format_rows(rows))
                print(f"\n{described(args.mapping)}: valid, {len(rows)} rules")
            return EXIT_OK
        mapping, scene, bridges = load_and_expand(
            args.mapping, args.scene, args.simconfigpath, args.nodename, args.namespace, ros=args.ros
        )
    except ConfigError as err:
        if args.format == "json":
            print(json.dumps({"problems": [problem.as_dict() for problem in err.problems]}, indent=2))
        else:
            print(str(err), file=sys.stderr)
        return EXIT_USAGE if err.unreadable else EXIT_INVALID
    _print_bridges(bridges, args.format, Path(args.simconfigpath) / args.scene)
    summary, warnings = match_report(mapping, scene, args.nodename, args.namespace)
    if summary and args.format == "text":
        print("\n" + "\n".join(summary))
    for warning in warnings:
        print(warning, file=sys.stderr)
    return EXIT_OK


def match_report(
    mapping: MappingDoc, scene: Scene, node_name: str, namespace: str
) -> tuple[list[str], list[str]]:
    """What each rule's `match` selected in `scene` (one line a rule), and a warning for each rule whose
    `match` selects nothing there (FILE:LINE: warning: ...)."""
    summary, warnings = [], []
    rules = {rule.name: rule for rule in mapping.rules}
    for name, (matched, total) in selected(mapping, scene, node_name, namespace).items():
        rule = rules[name]
        patterns = describe(rule.match)
        summary.append(f"match: rule '{name}' ({patterns}) selects {matched} of {total} elements")
        if not matched:
            where = f"{rule.file or mapping.source}:{rule.line}"
            warnings.append(f"{where}: warning: rule '{name}': match selects nothing in scene {scene.name}")
    return summary, warnings


if __name__ == "__main__":
    sys.exit(main())
