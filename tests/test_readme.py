"""The README is a user's guide: at most 25 KB, and every file it points to exists."""

from __future__ import annotations

import re

from harness import ROOT

README = ROOT / "README.md"
LIMIT_BYTES = 25_000


def test_the_readme_stays_a_guide_of_at_most_25_kb():
    size = len(README.read_bytes())
    assert size <= LIMIT_BYTES, f"README.md is {size} bytes; move details to docs/ (limit {LIMIT_BYTES})"


def test_every_file_the_readme_names_exists():
    names = set(
        re.findall(
            r"`((?:docs|tools|scripts|launch|rviz|mappings|schemas|sim_config)/[\w./-]+)`", README.read_text()
        )
    )
    missing = sorted(name for name in names if "*" not in name and not (ROOT / name).exists())
    assert not missing, missing
