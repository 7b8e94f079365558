"""Regenerate what the converter catalogue and the mapping model are the source of: the mapping schema's
`converter` and `for_each` enums (`airsim_mapper/schemas/mapping.schema.json`) and the converter table in
`docs/converters.md`. Run `python -m tools.catalogue` after adding a converter (or a for_each domain);
`--check` only says what is out of date (exit status 1). Tests check the same equalities.
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

from airsim_mapper.common.resources import SCHEMA_PATH
from airsim_mapper.convert.catalog import CONVERTERS, converters_markdown
from airsim_mapper.mapping.model import DOMAIN_VARIABLES

ROOT = Path(__file__).resolve().parent.parent
DOC = ROOT / "docs" / "converters.md"
BEGIN, END = "<!-- converters:begin -->", "<!-- converters:end -->"
ENUMS = {"converter": lambda: list(CONVERTERS), "for_each": lambda: list(DOMAIN_VARIABLES)}


def schema_text(text: str) -> str:
    """The schema text with its generated enums set from the code (the rest as it was)."""
    schema = json.loads(text)
    for name, values in ENUMS.items():
        schema["$defs"][name]["enum"] = values()
    return json.dumps(schema, indent=2, ensure_ascii=False) + "\n"


def doc_text(text: str) -> str:
    """docs/converters.md with the table between its markers made from the catalogue."""
    head, rest = text.split(BEGIN, 1)
    _old, tail = rest.split(END, 1)
    return f"{head}{BEGIN}\n{converters_markdown()}{END}{tail}"


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--check", action="store_true", help="write nothing; exit 1 if a file is out of date")
    args = parser.parse_args(argv)
    stale = []
    for path, make in ((Path(SCHEMA_PATH), schema_text), (DOC, doc_text)):
        old = path.read_text(encoding="utf-8")
        new = make(old)
        if new != old:
            stale.append(path)
            if not args.check:
                path.write_text(new, encoding="utf-8")
    for path in stale:
        print(f"{path.relative_to(ROOT)}: {'out of date' if args.check else 'regenerated'}")
    return 1 if stale and args.check else 0


if __name__ == "__main__":
    sys.exit(main())
