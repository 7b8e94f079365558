"""Every broken mapping under broken/ is rejected with its exact FILE:LINE:COL message and exit status 1."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest
from harness import ROOT

from airsim_mapper.cli.validate import main

BROKEN = Path(__file__).resolve().parent / "broken"
CORPUS = sorted(BROKEN.glob("*.yaml"))
RUN_AS_SUBPROCESS = (
    "unknown_key.yaml",
    "tabs.yaml",
    "python_tag.yaml",
    "empty.yaml",
    "alias_bomb.yaml",
    "non_utf8.yaml",
    "merge_bomb.yaml",
)


def expectations(path: Path) -> list[str]:
    """The `# expect: LINE:COL: message` lines of a corpus file, as full `FILE:LINE:COL: message` lines."""
    lines = path.read_bytes().decode("utf-8", "replace").splitlines()  # non_utf8.yaml is not UTF-8
    expected = [line.removeprefix("# expect: ") for line in lines if line.startswith("# expect: ")]
    return [f"{path}:{text}" for text in expected]


def test_the_corpus_covers_every_kind_of_mistake_and_states_its_expected_messages():
    names = {path.name for path in CORPUS}
    for kind in (
        "unknown_key",
        "wrong_type",
        "misspelt_converter",
        "duplicate_topic",
        "unknown_variable",
        "type_mismatch",
        "tabs",
        "invalid_yaml",
        "empty",
        "top_level_list",
        "python_tag",
        "alias_bomb",
        "extends_cycle",
        "extends_missing_base",
        "extends_unknown_rule",
        "extends_remove_unknown_rule",
        "unknown_mapping_variable",
        "variable_cycle",
        "match_unknown_variable",
        "match_bad_glob",
        "module_import_type",
        "non_utf8",
        "merge_key",
        "merge_bomb",
    ):
        assert f"{kind}.yaml" in names
    assert all(expectations(path) for path in CORPUS)


@pytest.mark.parametrize("path", CORPUS, ids=[p.stem for p in CORPUS])
def test_validate_mapping_rejects_the_broken_mapping_with_its_precise_error(path, capsys):
    status = main([str(path)])
    captured = capsys.readouterr()
    assert status == 1
    assert captured.out == ""
    assert "Traceback" not in captured.err
    reported = captured.err.splitlines()
    for line in expectations(path):
        assert any(got.startswith(line) for got in reported), f"{line!r} not in {reported!r}"


@pytest.mark.live
@pytest.mark.parametrize("name", RUN_AS_SUBPROCESS)
def test_the_installed_command_exits_1_with_the_error_on_stderr(name):
    path = BROKEN / name
    result = subprocess.run(
        [sys.executable, "-m", "airsim_mapper.cli.validate", str(path)],
        capture_output=True,
        text=True,
        cwd=ROOT,
        timeout=60,
    )
    assert result.returncode == 1
    assert "Traceback" not in result.stderr
    assert result.stderr.startswith(expectations(path)[0])
