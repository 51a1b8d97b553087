"""The ruff version is the same wherever it is named: the lint extra, CI, and the pre-commit hook."""

from __future__ import annotations

import re
import tomllib
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def test_one_ruff_version_everywhere() -> None:
    project = tomllib.loads((ROOT / "pyproject.toml").read_text())
    (pin,) = project["project"]["optional-dependencies"]["lint"]
    version = pin.removeprefix("ruff==")
    assert re.fullmatch(r"\d+\.\d+\.\d+", version), pin
    assert f'pip install "ruff=={version}"' in (ROOT / ".ci" / "run").read_text()
    assert f"rev: v{version}" in (ROOT / ".pre-commit-config.yaml").read_text()


def test_every_package_ships_its_type_marker() -> None:
    project = tomllib.loads((ROOT / "pyproject.toml").read_text())
    data = project["tool"]["setuptools"]["package-data"]
    for package in ("empathy_zoo", "agents", "baselines", "leaderboard"):
        assert (ROOT / package / "py.typed").is_file() and "py.typed" in data[package]
