"""Imports flow one way (CONTRIBUTING.md, "Where things go"): the command line and the leaderboard
→ training and the configuration files (sweep files, run specs, scenario sets, result reading) →
``baselines/`` → ``agents/`` → the environments (the rest of ``empathy_zoo``). No module imports a
module of a higher layer, at its top or inside a function."""

from __future__ import annotations

import ast
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
PACKAGES = ("empathy_zoo", "agents", "baselines", "leaderboard")

LAYERS: tuple[tuple[int, tuple[str, ...]], ...] = (
    (5, ("empathy_zoo.cli", "leaderboard")),
    (4, ("empathy_zoo.training", "empathy_zoo.experiment", "empathy_zoo.scenarios")),
    (3, ("baselines",)),
    (2, ("agents",)),
    (1, ("empathy_zoo",)),
)
"""The layers, highest first; a module belongs to the first whose prefix it starts with."""


def layer(module: str) -> int | None:
    """The layer of ``module`` (``None``: not a module of the suite)."""
    for level, prefixes in LAYERS:
        if any(module == p or module.startswith(p + ".") for p in prefixes):
            return level
    return None


def module_name(path: Path) -> str:
    parts = path.relative_to(ROOT).with_suffix("").parts
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


def imported(tree: ast.AST) -> list[tuple[str, int]]:
    """Every absolute import of ``tree`` and its line, top-level or not."""
    found: list[tuple[str, int]] = []
    for node in ast.walk(tree):
        if isinstance(node, ast.ImportFrom) and node.module and node.level == 0:
            found.append((node.module, node.lineno))
        elif isinstance(node, ast.Import):
            found.extend((alias.name, node.lineno) for alias in node.names)
    return found


def upward_imports() -> list[str]:
    """``path:line: importer (layer) -> imported (layer)`` for every import that runs back up."""
    found = []
    for package in PACKAGES:
        for path in sorted((ROOT / package).rglob("*.py")):
            me = layer(module_name(path))
            for name, line in imported(ast.parse(path.read_text(encoding="utf-8"))):
                theirs = layer(name)
                if me is not None and theirs is not None and theirs > me:
                    found.append(f"{path.relative_to(ROOT)}:{line}: layer {me} -> {name} (layer {theirs})")
    return found


def test_no_import_runs_back_up() -> None:
    assert upward_imports() == []


@pytest.mark.parametrize(
    ("module", "expected"),
    [
        ("empathy_zoo.cli.tune", 5),
        ("leaderboard.report", 5),
        ("empathy_zoo.training.ensemble", 4),
        ("empathy_zoo.experiment.result_reader", 4),
        ("empathy_zoo.scenarios", 4),
        ("baselines.registry", 3),
        ("agents.rewards", 2),
        ("empathy_zoo.engine.base", 1),
        ("empathy_zoo.result_file", 1),
        ("empathy_zoo", 1),
        ("numpy", None),
    ],
)
def test_each_module_has_its_layer(module: str, expected: int | None) -> None:
    assert layer(module) == expected


def test_an_upward_import_is_found() -> None:
    tree = ast.parse("def f():\n    from baselines.registry import METHODS\n")
    names = [name for name, _ in imported(tree)]
    assert names == ["baselines.registry"] and layer(names[0]) > layer("empathy_zoo.result_file")  # type: ignore[operator]
