"""Probe 16: separation tables and their readers (``analyse separation-reading``, ``analyse
discrimination``) match a β by the number itself, never by rounded text; a table that lists a pair
or an outcome twice, pairs a row with itself, says two rows marked identical differ, pairs at an ε
no outcome has, names an unregistered environment or holds non-plain data in a field no check
reads is refused in one line naming the file and the field; the commands refuse an ε outside
[0, 1] and an empty path in one line naming the option."""

from __future__ import annotations

import json
import math
import shutil
from collections.abc import Callable
from pathlib import Path
from typing import Any

import pytest
from helpers_results import synthetic_document, synthetic_result

from baselines.discrimination import method_rows
from baselines.separation_file import SeparationTableError, read_separation_table
from empathy_zoo.cli import main as cli
from leaderboard.separation_reading import final_harms
from leaderboard.trained_separation import predictions

SHIPPED = Path(__file__).resolve().parents[1] / "docs" / "results" / "separation"
NEAR = 0.5000001
"""A β that ``:g`` prints as 0.5 but is not 0.5."""


def _tables(tmp_path: Path) -> Path:
    """The shipped separation tables, copied into ``tmp_path / "tables"``."""
    folder = tmp_path / "tables"
    folder.mkdir()
    for path in SHIPPED.glob("*.json"):
        shutil.copy(path, folder / path.name)
    return folder


def _load(folder: Path, task: str = "coexistence_v0") -> dict[str, Any]:
    return json.loads((folder / f"{task}.json").read_text())


def _save(folder: Path, table: dict[str, Any], task: str = "coexistence_v0") -> Path:
    path = folder / f"{task}.json"
    path.write_text(json.dumps(table))  # (NaN written as NaN, as a hostile file may hold it)
    return path


def _near_beta(table: dict[str, Any], method: str) -> None:
    """``method``'s β = 0.5 row moved to β = :data:`NEAR`."""
    (row,) = [row for row in table["rows"] if row["method"] == method and row["selfishness"] == 0.5]
    row["selfishness"] = NEAR


# --- 1. β matched by the number ---------------------------------------------------------------


def test_a_run_near_beta_is_not_read_as_one_at_beta() -> None:
    at = synthetic_result("charger_v0", "empathic_dqn", 0.5, 0, harms=1.0)
    near = synthetic_result("charger_v0", "empathic_dqn", NEAR, 1, harms=1.0)
    assert final_harms([at, near], {"empathic_dqn": True}) == {("charger_v0", "empathic_dqn"): [1.0]}


def test_a_table_row_near_beta_makes_no_prediction(tmp_path: Path) -> None:
    folder = _tables(tmp_path)
    table = _load(folder, "charger_v0")
    assert "empathic_dqn" in {p.method for p in predictions({"charger_v0": table})}
    _near_beta(table, "empathic_dqn")
    read = read_separation_table(_save(folder, table, "charger_v0"))
    assert "empathic_dqn" not in {p.method for p in predictions({"charger_v0": read})}


def test_a_table_row_near_beta_is_not_the_matrix_row(tmp_path: Path) -> None:
    folder = _tables(tmp_path)
    table = _load(folder)
    assert method_rows(table)["empathic_dqn"] == "empathic_dqn β=0.5"
    _near_beta(table, "empathic_dqn")
    assert "empathic_dqn" not in method_rows(read_separation_table(_save(folder, table)))


def test_the_reading_command_leaves_out_runs_near_beta(tmp_path: Path, capsys) -> None:
    folder = _tables(tmp_path)
    runs = tmp_path / "results" / "runs"
    runs.mkdir(parents=True)
    for seed in range(10):
        for method, beta, harms in (("dqn", 1.0, 1.0), ("empathic_dqn", NEAR, 0.0)):
            document = synthetic_document("charger_v0", method, beta, seed, harms=harms)
            (runs / f"{document['run_id']}.json").write_text(json.dumps(document))
    assert cli(["analyse", "separation-reading", str(tmp_path / "results"), "--tables", str(folder)]) == 0
    line = next(line for line in capsys.readouterr().out.splitlines() if line.startswith("| `empathic_dqn` |"))
    assert "| 0 (10) | — | no runs | not judged |" in line


# --- 2. separation tables: each new rule refused naming the field -------------------------------


def _append_pair(change: dict[str, Any]) -> Callable[[dict[str, Any]], None]:
    return lambda t: t["pairs"].append({**t["pairs"][1], **change})


def _swap(t: dict[str, Any]) -> None:
    pair = t["pairs"][3]
    swapped = {**pair, "first": pair["second"], "second": pair["first"], "harms_difference": -pair["harms_difference"]}
    t["pairs"].append(swapped)


def _identical_differ(t: dict[str, Any]) -> None:
    t["pairs"][0].update(differ=True, differing_states=3)  # (dqn / dqn_silver_literal: identical by construction)


def _identical_through_one(t: dict[str, Any]) -> None:
    """dqn_silver_literal and dqn_equality are both identical to dqn: so to each other."""
    (pair,) = [
        p for p in t["pairs"] if {p["first"], p["second"]} == {"dqn_silver_literal", "dqn_equality"} and p["epsilon"] == 0.0
    ]
    pair.update(differ=True, differing_states=2)


def _last_pair(t: dict[str, Any]) -> str:
    return f"pairs[{len(t['pairs']) - 1}]"  # (the one appended)


def _last_outcome(t: dict[str, Any]) -> str:
    return f"outcomes[{len(t['outcomes']) - 1}]"  # (the one appended)


def _pair_index(t: dict[str, Any], first: str, second: str) -> int:
    return next(i for i, p in enumerate(t["pairs"]) if {p["first"], p["second"]} == {first, second} and p["epsilon"] == 0.0)


BROKEN: dict[str, tuple[Callable[[dict[str, Any]], Any], Callable[[dict[str, Any]], str]]] = {
    "a pair listed twice": (_append_pair({}), lambda t: _last_pair(t) + ".second"),
    "a pair listed twice, its rows swapped": (_swap, lambda t: _last_pair(t) + ".second"),
    "a pair of a row with itself": (
        lambda t: t["pairs"].append({**t["pairs"][5], "second": t["pairs"][5]["first"]}),
        lambda t: _last_pair(t) + ".second",
    ),
    "identical rows said to differ": (_identical_differ, lambda t: "pairs[0].differ"),
    "rows identical to one row said to differ": (
        _identical_through_one,
        lambda t: f"pairs[{_pair_index(t, 'dqn_silver_literal', 'dqn_equality')}].differ",
    ),
    "an outcome listed twice": (lambda t: t["outcomes"].append({**t["outcomes"][0]}), lambda t: _last_outcome(t) + ".epsilon"),
    "a pair at an ε no outcome has": (lambda t: t["pairs"][0].update(epsilon=0.123), lambda t: "pairs[0].epsilon"),
    "an unregistered environment": (lambda t: t.update(env="not_an_env"), lambda t: "env"),
    "NaN in a field no check reads": (lambda t: t.update(zzz=math.nan), lambda t: "zzz"),
    "an escape in gamma": (lambda t: t.update(gamma="x\x1b"), lambda t: "gamma"),
    "an escape in an outcome's note": (lambda t: t["outcomes"][0].update(note="\x1b[31mred"), lambda t: "outcomes[0].note"),
    "infinity in a pair's extra": (
        lambda t: t["pairs"][2].update(survival_difference=math.inf),
        lambda t: "pairs[2].survival_difference",
    ),
    "NaN nested in a row's extra": (lambda t: t["rows"][3].update(extra={"a": [math.nan]}), lambda t: "rows[3].extra.a[0]"),
    "an escape in an omission's extra": (
        lambda t: t["omitted"].append({"method": "m", "reason": "r", "why": "\x07"}),
        lambda t: "omitted[0].why",
    ),
}


@pytest.mark.parametrize("name", list(BROKEN))
def test_a_broken_table_is_refused_naming_the_field(tmp_path: Path, name: str) -> None:
    folder = _tables(tmp_path)
    table = _load(folder)
    change, field = BROKEN[name]
    change(table)
    path = _save(folder, table)
    with pytest.raises(SeparationTableError) as caught:
        read_separation_table(path)
    message = str(caught.value)
    assert "\n" not in message and str(path) in message
    assert f"field {field(table)}:" in message


def test_the_matrix_command_refuses_a_broken_table_in_one_line(tmp_path: Path, capsys) -> None:
    folder = _tables(tmp_path)
    table = _load(folder)
    _identical_differ(table)
    _save(folder, table)
    assert cli(["analyse", "discrimination", str(folder), "--out", str(tmp_path / "page.md")]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "coexistence_v0.json: field pairs[0].differ" in err and "Traceback" not in err
    assert not (tmp_path / "page.md").exists()


def test_every_shipped_table_still_reads(tmp_path: Path) -> None:
    folder = _tables(tmp_path)
    assert len(list(folder.glob("*.json"))) >= 6
    for path in sorted(folder.glob("*.json")):
        assert read_separation_table(path)["rows"]


# --- 3. --epsilon in [0, 1] ----------------------------------------------------------------------


@pytest.mark.parametrize("epsilon", ["nan", "-1", "2", "inf", "-inf"])
def test_an_epsilon_outside_its_range_is_refused_as_the_argument(tmp_path: Path, capsys, epsilon: str) -> None:
    folder = _tables(tmp_path)
    out = tmp_path / "page.md"
    assert cli(["analyse", "discrimination", str(folder), f"--epsilon={epsilon}", "--out", str(out)]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "--epsilon" in err and "[0, 1]" in err and "no pair" not in err
    assert not out.exists()


# --- 4. empty paths ------------------------------------------------------------------------------


def test_an_empty_path_is_refused_naming_the_option(tmp_path: Path, capsys, monkeypatch) -> None:
    folder = _tables(tmp_path)
    work = tmp_path / "work"
    work.mkdir()
    monkeypatch.chdir(work)
    cases = [
        (["analyse", "discrimination", str(folder), "--out", ""], "--out"),
        (["analyse", "discrimination", str(folder), "--results", ""], "--results"),
        (["analyse", "discrimination", ""], "directory"),
        (["analyse", "separation-reading", ""], "results"),
        (["analyse", "separation-reading", str(tmp_path), "--tables", ""], "--tables"),
    ]
    for argv, option in cases:
        assert cli(argv) == 2, argv
        err = capsys.readouterr().err
        assert err.count("\n") == 1 and option in err and "empty" in err, (argv, err)
    assert list(work.iterdir()) == []
