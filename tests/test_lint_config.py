"""The lint tools' versions are the same wherever they are named: the lint extra, CI, and the pre-commit hook."""

from __future__ import annotations

import re
import tomllib
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def test_one_ruff_version_everywhere() -> None:
    project = tomllib.loads((ROOT / "pyproject.toml").read_text())
    pins = dict(pin.split("==") for pin in project["project"]["optional-dependencies"]["lint"])
    assert set(pins) == {"ruff", "mypy"} and all(re.fullmatch(r"\d+\.\d+\.\d+", v) for v in pins.values()), pins
    ci = (ROOT / ".ci" / "run").read_text()
    assert f'pip install "ruff=={pins["ruff"]}" "mypy=={pins["mypy"]}"' in ci
    assert f"rev: v{pins['ruff']}" in (ROOT / ".pre-commit-config.yaml").read_text()


def test_every_package_ships_its_type_marker() -> None:
    project = tomllib.loads((ROOT / "pyproject.toml").read_text())
    data = project["tool"]["setuptools"]["package-data"]
    for package in ("empathy_zoo", "agents", "baselines", "leaderboard"):
        assert (ROOT / package / "py.typed").is_file() and "py.typed" in data[package]
