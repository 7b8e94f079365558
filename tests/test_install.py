"""A non-editable install is the product alone, and finds its shipped mappings and schema from anywhere."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest
from harness import ROOT

pytestmark = pytest.mark.live  # builds and installs the package in a subprocess


@pytest.fixture(scope="module")
def installed(tmp_path_factory: pytest.TempPathFactory) -> Path:
    target = tmp_path_factory.mktemp("site")
    run = subprocess.run(
        [
            sys.executable,
            "-m",
            "pip",
            "install",
            "--no-deps",
            "--no-build-isolation",
            "-q",
            ".",
            "--target",
            target,
        ],
        cwd=ROOT,
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert run.returncode == 0, run.stdout + run.stderr
    return target


def from_root(installed: Path, *argv: str) -> subprocess.CompletedProcess:
    """The installed `validate-mapping` run from `/`, importing only the installed package."""
    env = {**os.environ, "PYTHONPATH": str(installed)}
    return subprocess.run(
        [str(installed / "bin" / "validate-mapping"), *argv], cwd="/", env=env, capture_output=True, text=True
    )


def test_the_installed_package_holds_the_product_and_its_data_but_no_tools(installed: Path) -> None:
    package = installed / "airsim_mapper"
    assert (package / "mappings" / "default.yaml").is_file() and (package / "mappings" / "enu.yaml").is_file()
    assert (package / "schemas" / "mapping.schema.json").is_file()
    assert not (installed / "tools").exists()
    assert not any(name in {"bench", "soak.py", "demo.py", "screenshot.py"} for name in os.listdir(package))


@pytest.mark.parametrize("mapping", ["mappings/default.yaml", "default", "enu", "enu.yaml"])
def test_validate_mapping_finds_a_shipped_mapping_by_path_or_name_from_the_root(installed, mapping) -> None:
    run = from_root(installed, mapping)
    assert run.returncode == 0, run.stderr
    assert (
        run.stdout.rstrip().endswith("rules") and str(installed / "airsim_mapper" / "mappings") in run.stdout
    )


def test_an_unknown_mapping_name_is_reported_as_the_path_the_user_gave(installed) -> None:
    run = from_root(installed, "nope")
    assert run.returncode == 2
    assert run.stderr.startswith("nope: cannot read the mapping file")
