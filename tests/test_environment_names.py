"""What the suite knows about an environment is in its entry of the environment table, and what it
knows about a metric is in ``empathy_zoo/metrics.py``: no other module of ``leaderboard/``,
``empathy_zoo/``, ``agents/`` or ``baselines/`` names an environment in a string of its code, or
holds a table of metrics (a literal of several metric names), except the modules of
:data:`ALLOWED`, each with its reason. Docstrings and comments may name environments: they are
documentation."""

from __future__ import annotations

import ast
import importlib
import re
from collections.abc import Iterator
from pathlib import Path

import pytest

from empathy_zoo.environments import ENVIRONMENT_TABLE
from empathy_zoo.metrics import DERIVED_METRICS, METRIC_NAMES

ROOT = Path(__file__).resolve().parents[1]
SCANNED = ("leaderboard", "empathy_zoo", "agents", "baselines")
TABLES = ("empathy_zoo/environments.py", "empathy_zoo/metrics.py")
"""The environment table and the metrics' facts."""
ALLOWED: dict[str, str] = {
    "empathy_zoo/__init__.py": "the package exports each face module by name (from empathy_zoo import coexistence_v0)",
    "leaderboard/reproduction.py": "the paper's claims (C1–C5) are about its two environments, by name",
    "leaderboard/sensitivity.py": "the study of Sharing under its own fidelity options and partner (claim C5)",
    "baselines/methods.py": "a method records the environments where it reduces to DQN (its penalty is always 0 there)",
    "baselines/reachability.py": "relative reachability keeps Coexistence's own one-cat table; other tasks use their exact model",
}
"""Modules that may name an environment or list metrics, and why."""
METRICS = frozenset(METRIC_NAMES) | frozenset(DERIVED_METRICS)
NAMES = re.compile(r"\b(" + "|".join(map(re.escape, ENVIRONMENT_TABLE)) + r")\b")


def _module_path(module: str) -> str:
    return Path(importlib.import_module(module).__file__ or "").resolve().relative_to(ROOT).as_posix()


def own_modules() -> set[str]:
    """Every registered environment's engine module and face module."""
    return {_module_path(entry.module) for entry in ENVIRONMENT_TABLE.values()} | {
        _module_path(entry.engine.__module__) for entry in ENVIRONMENT_TABLE.values()
    }


def scanned() -> list[str]:
    """The source files the rule applies to."""
    skipped = own_modules() | set(TABLES)
    files = (path.relative_to(ROOT).as_posix() for top in SCANNED for path in sorted((ROOT / top).rglob("*.py")))
    return [path for path in files if path not in skipped]


def _docstrings(tree: ast.AST) -> set[int]:
    """The ids of every string that stands alone as a statement (docstrings and attribute docstrings)."""
    return {
        id(node.value)
        for node in ast.walk(tree)
        if isinstance(node, ast.Expr) and isinstance(node.value, ast.Constant) and isinstance(node.value.value, str)
    }


def named_environments(source: str) -> Iterator[tuple[int, str]]:
    """``(line, text)`` of every string of code in ``source`` that names a registered environment."""
    tree = ast.parse(source)
    documentation = _docstrings(tree)
    for node in ast.walk(tree):
        if (
            isinstance(node, ast.Constant)
            and isinstance(node.value, str)
            and id(node) not in documentation
            and NAMES.search(node.value)
        ):
            yield node.lineno, node.value


def metric_tables(source: str) -> Iterator[tuple[int, list[str]]]:
    """``(line, names)`` of every dict, tuple, list or set literal in ``source`` whose keys or items
    are two or more metric names and nothing else."""
    for node in ast.walk(ast.parse(source)):
        if isinstance(node, ast.Dict):
            items: list[ast.expr | None] = list(node.keys)
        elif isinstance(node, (ast.Tuple, ast.List, ast.Set)):
            items = list(node.elts)
        else:
            continue
        names = [item.value for item in items if isinstance(item, ast.Constant) and isinstance(item.value, str)]
        if len(items) >= 2 and len(names) == len(items) and set(names) <= METRICS:
            yield node.lineno, names


def test_no_module_outside_the_table_names_an_environment_or_lists_metrics() -> None:
    found = []
    for path in scanned():
        if path in ALLOWED:
            continue
        source = (ROOT / path).read_text(encoding="utf-8")
        found += [f"{path}:{line}: names an environment: {text!r}" for line, text in named_environments(source)]
        found += [f"{path}:{line}: a table of metrics: {names}" for line, names in metric_tables(source)]
    assert not found, "\n".join(found)


@pytest.mark.parametrize("path", sorted(ALLOWED))
def test_every_allowed_module_still_needs_its_place(path: str) -> None:
    source = (ROOT / path).read_text(encoding="utf-8")
    assert path in scanned()
    assert list(named_environments(source)) or list(metric_tables(source)), f"{path} no longer names one: drop it"


def test_the_rule_sees_a_name_and_a_table_in_code_but_not_in_documentation() -> None:
    source = '"""Scores coexistence_v0."""\nSHOWN = {"coexistence_v0": ("survival", "harms")}\nDOC = 1\n"""of sharing_v0"""\n'
    assert list(named_environments(source)) == [(2, "coexistence_v0")]
    assert list(metric_tables(source)) == [(2, ["survival", "harms"])]
