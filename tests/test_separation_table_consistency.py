"""A separation table consistent with itself, as ``analyse separation`` writes it
(:func:`baselines.separation_file.check_separation_table`): every row's outcome at every ε of the
table, outcomes within what an episode of its environment holds, and each pair's differences its
rows' outcomes'. Each forgery below was accepted before, and a reader then read it silently (the
scenarios reading dropped a row with no outcome at ε = 0 and the task's verdict changed)."""

from __future__ import annotations

import json
import math
import re
import shutil
from collections.abc import Callable
from pathlib import Path
from typing import Any

import pytest

from baselines.separation_file import SeparationTableError, read_separation_table
from empathy_zoo.cli import main as cli
from leaderboard.trained_separation import predictions

ROOT = Path(__file__).resolve().parents[1]
SHIPPED = ROOT / "docs" / "results" / "separation"
SCENARIOS = ROOT / "docs" / "results" / "scenarios"
DROPPED = ("empathic_dqn β=0.5", "empathic_dqn_silver β=0.5")
"""The rows the probe dropped at ε = 0 from the Charger table: both predicted, so the verdict moved."""


def _shipped(name: str = "charger_v0") -> dict[str, Any]:
    return json.loads((SHIPPED / f"{name}.json").read_text(encoding="utf-8"))


def _written(folder: Path, document: dict[str, Any], name: str = "charger_v0") -> Path:
    folder.mkdir(parents=True, exist_ok=True)
    path = folder / f"{name}.json"
    path.write_text(json.dumps(document, ensure_ascii=False), encoding="utf-8")
    return path


def _refused(path: Path, field: str, expected: str = "") -> str:
    """The one-line message refusing ``path``, which names it and ``field`` (and ``expected``)."""
    with pytest.raises(SeparationTableError) as caught:
        read_separation_table(path)
    message = str(caught.value)
    assert "\n" not in message and str(path) in message, message
    assert f"field {field}:" in message, message
    assert expected in message, message
    return message


def _pair_index(table: dict[str, Any], first: str, second: str, epsilon: float) -> int:
    return next(
        i
        for i, pair in enumerate(table["pairs"])
        if (pair["first"], pair["second"]) == (first, second) and pair["epsilon"] == epsilon
    )


def _outcome_index(table: dict[str, Any], row: str, epsilon: float) -> int:
    return next(i for i, o in enumerate(table["outcomes"]) if o["row"] == row and o["epsilon"] == epsilon)


def _drop_outcomes(table: dict[str, Any], rows: tuple[str, ...], epsilon: float = 0.0) -> None:
    table["outcomes"] = [o for o in table["outcomes"] if not (o["epsilon"] == epsilon and o["row"] in rows)]


def _drop_pairs(table: dict[str, Any], rows: tuple[str, ...], epsilon: float = 0.0) -> None:
    table["pairs"] = [p for p in table["pairs"] if not (p["epsilon"] == epsilon and {p["first"], p["second"]} & set(rows))]


# ---------------------------------------------------------------------------- what still passes
@pytest.mark.parametrize("path", sorted(SHIPPED.glob("*.json")), ids=lambda p: p.name)
def test_every_shipped_table_passes_the_checker(path: Path) -> None:
    table = read_separation_table(path)
    epsilons = {o["epsilon"] for o in table["outcomes"]}
    assert len(table["outcomes"]) == len(table["rows"]) * len(epsilons)


def test_a_difference_off_by_a_floats_rounding_and_harms_a_rounding_past_the_bound_pass(tmp_path: Path) -> None:
    table = _shipped()
    pair = table["pairs"][_pair_index(table, "dqn", "dqn_harm_penalty", 0.0)]
    pair["harms_difference"] = math.nextafter(pair["harms_difference"], math.inf)
    table["outcomes"][_outcome_index(table, "dqn", 0.01)]["harms"] = 1.0000000000000002  # (the shipped helping table's)
    for key in ("harms_difference", "survival_difference"):  # (kept what dqn's new harms give)
        for pair in table["pairs"]:
            if pair["epsilon"] == 0.01 and "dqn" in (pair["first"], pair["second"]):
                first, second = (table["outcomes"][_outcome_index(table, pair[k], 0.01)] for k in ("first", "second"))
                figure = key.removesuffix("_difference")
                pair[key] = first[figure] - second[figure]
    read_separation_table(_written(tmp_path, table))


def test_a_row_of_an_omitted_method_may_lack_an_outcome_and_its_pairs_at_an_epsilon(tmp_path: Path) -> None:
    """The producer's own case: no joint fixed point at some ε, the method listed in ``omitted``,
    and no prediction read from it (what the scenarios reading's page says of an omitted method)."""
    table = _shipped()
    _drop_outcomes(table, ("dqn_considerate",))
    _drop_pairs(table, ("dqn_considerate",))
    reason = "at some ε its optimum and the cat's value find no joint fixed point"
    table["omitted"].append({"method": "dqn_considerate", "reason": reason})
    read = read_separation_table(_written(tmp_path, table))
    assert "dqn_considerate" not in {p.method for p in predictions({"charger_v0": read})}


# ---------------------------------------------------------------------------- 1. a missing outcome
def test_a_row_with_no_outcome_at_an_epsilon_is_refused_naming_row_epsilon_and_file(tmp_path: Path) -> None:
    table = _shipped()
    _drop_outcomes(table, DROPPED)  # (the probe's forgery: its pairs at ε = 0 kept)
    _refused(_written(tmp_path, table), "outcomes", f"missing the outcome of row {DROPPED[0]!r} at ε = 0.0")


def test_a_row_with_neither_outcome_nor_pairs_at_an_epsilon_is_refused(tmp_path: Path) -> None:
    table = _shipped()
    _drop_outcomes(table, DROPPED[1:], 0.05)
    _drop_pairs(table, DROPPED[1:], 0.05)
    _refused(_written(tmp_path, table), "outcomes", f"missing the outcome of row {DROPPED[1]!r} at ε = 0.05")


def test_a_pair_naming_a_row_of_an_omitted_method_where_it_has_no_outcome_is_refused(tmp_path: Path) -> None:
    table = _shipped()
    _drop_outcomes(table, ("dqn_considerate",))
    table["omitted"].append({"method": "dqn_considerate", "reason": "no joint fixed point at ε = 0"})
    index = _pair_index(table, "dqn", "dqn_considerate", 0.0)
    _refused(_written(tmp_path, table), f"pairs[{index}].second", "a row with an outcome at ε = 0.0")


def test_the_separation_reading_refuses_the_probes_table_instead_of_dropping_its_rows(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    folder = tmp_path / "tables"
    for path in sorted(SHIPPED.glob("*.json")):
        _written(folder, json.loads(path.read_text(encoding="utf-8")), path.stem)
    table = _shipped()
    _drop_outcomes(table, DROPPED)
    _written(folder, table)
    assert cli(["analyse", "separation-reading", str(SCENARIOS), "--tables", str(folder)]) == 2
    error = capsys.readouterr().err
    assert f"charger_v0.json: field outcomes: missing the outcome of row {DROPPED[0]!r} at ε = 0.0" in error


def test_predictions_refuse_an_unchecked_table_missing_a_rows_greedy_outcome() -> None:
    table = _shipped()
    _drop_outcomes(table, DROPPED)
    with pytest.raises(ValueError, match=re.escape(f"no outcome of row {DROPPED[0]!r} at ε = 0")):
        predictions({"charger_v0": table})


# ---------------------------------------------------------------------------- 2. an episode's bounds
Change = Callable[[dict[str, Any]], None]


def _set_outcome(row: str, epsilon: float, **figures: Any) -> Change:
    return lambda t: t["outcomes"][_outcome_index(t, row, epsilon)].update(figures)


BEYOND_AN_EPISODE: dict[str, tuple[str, Change, Callable[[dict[str, Any]], str], str]] = {
    "charger harms of 40 (one cat, harmed at most once)": (
        "charger_v0",
        _set_outcome("dqn", 0.0, harms=40.0),
        lambda t: f"outcomes[{_outcome_index(t, 'dqn', 0.0)}].harms",
        "at most 1 (",
    ),
    "sharing harms of 0.5 (no one can be harmed)": (
        "sharing_v0",
        _set_outcome("dqn", 0.01, harms=0.5),
        lambda t: f"outcomes[{_outcome_index(t, 'dqn', 0.01)}].harms",
        "at most 0 (",
    ),
    "vase harms of 3 (the cat and the vase)": (
        "vase_v0",
        _set_outcome("dqn", 0.0, harms=3.0),
        lambda t: f"outcomes[{_outcome_index(t, 'dqn', 0.0)}].harms",
        "at most 2 (",
    ),
    "survival of 501 steps in 500": (
        "charger_v0",
        _set_outcome("dqn", 0.05, survival=501.0),
        lambda t: f"outcomes[{_outcome_index(t, 'dqn', 0.05)}].survival",
        "at most 500 (",
    ),
    "survival past the table's own max_cycles": (
        "coexistence_v0_authors",
        _set_outcome("dqn", 0.0, survival=502.0),
        lambda t: f"outcomes[{_outcome_index(t, 'dqn', 0.0)}].survival",
        "at most 501 (",
    ),
    "max_cycles other than its arguments give": (
        "charger_v0",
        lambda t: t.update(max_cycles=5000),
        lambda t: "max_cycles",
        "(500)",
    ),
    "an argument its environment does not take": (
        "charger_v0",
        lambda t: t["arguments"].append(["num_cats", 40]),
        lambda t: "arguments.num_cats",
        "an argument of charger_v0",
    ),
    "an argument given twice": (
        "coexistence_v0_authors",
        lambda t: t["arguments"].append(["max_cycles", 500]),
        lambda t: "arguments[2][0]",
        "an argument not given before",
    ),
}


@pytest.mark.parametrize("name", list(BEYOND_AN_EPISODE))
def test_an_outcome_beyond_what_an_episode_of_its_environment_holds_is_refused(tmp_path: Path, name: str) -> None:
    task, change, field, expected = BEYOND_AN_EPISODE[name]
    table = _shipped(task)
    change(table)
    _refused(_written(tmp_path, table, task), field(table), expected)


# ---------------------------------------------------------------------------- 3. a pair's differences
def _set_pair(task: str, first: str, second: str, epsilon: float, key: str, value: Callable[[float], float]) -> Change:
    def change(table: dict[str, Any]) -> None:
        pair = table["pairs"][_pair_index(table, first, second, epsilon)]
        pair[key] = value(pair[key])

    return change


DISAGREEING: dict[str, tuple[str, tuple[str, str, float], str, Callable[[float], float]]] = {
    "a harms difference of 123": ("charger_v0", ("dqn", "dqn_harm_penalty", 0.0), "harms_difference", lambda _: 123.0),
    "a harms difference of the wrong sign": ("charger_v0", ("dqn", "dqn_harm_penalty", 0.0), "harms_difference", lambda v: -v),
    "a harms difference off by 1e-6": ("vase_v0", ("dqn", "dqn_harm_penalty", 0.01), "harms_difference", lambda v: v + 1e-6),
    "a survival difference of the wrong sign": ("sharing_v0", ("dqn", "dqn_equality", 0.0), "survival_difference", lambda v: -v),
    "an equality difference of the wrong sign": ("sharing_v0", ("dqn", "dqn_equality", 0.0), "equality_difference", lambda v: -v),
}


@pytest.mark.parametrize("name", list(DISAGREEING))
def test_a_pairs_difference_its_rows_outcomes_do_not_give_is_refused(tmp_path: Path, name: str) -> None:
    task, (first, second, epsilon), key, value = DISAGREEING[name]
    table = _shipped(task)
    index = _pair_index(table, first, second, epsilon)
    before = table["pairs"][index][key]
    assert before != 0.0 and value(before) != before  # (a change the checker must see)
    _set_pair(task, first, second, epsilon, key, value)(table)
    a, b = (table["outcomes"][_outcome_index(table, row, epsilon)] for row in (first, second))
    figure = key.removesuffix("_difference")
    assert before == a[figure] - b[figure]  # (the producer's sign: the first row's minus the second's)
    _refused(_written(tmp_path, table, task), f"pairs[{index}].{key}", f"expected {before!r}, the first row's {figure} (")


def test_a_table_saved_under_another_tasks_name_is_refused(tmp_path: Path, capsys) -> None:
    """Readers key a table by its file's name: Vase's table saved as coexistence_v0.json would be
    read as Coexistence's predictions."""
    from baselines.separation_file import read_separation_table

    shipped = Path(__file__).resolve().parents[1] / "docs" / "results" / "separation"
    (tmp_path / "tables").mkdir()
    shutil.copyfile(shipped / "vase_v0.json", tmp_path / "tables" / "coexistence_v0.json")
    with pytest.raises(ValueError, match=r"holds the table of vase_v0 .*not of coexistence_v0: name it vase_v0\.json"):
        read_separation_table(tmp_path / "tables" / "coexistence_v0.json")
    from empathy_zoo.cli import main

    assert main(["analyse", "discrimination", str(tmp_path / "tables"), "--out", str(tmp_path / "d.md")]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "vase_v0" in err, err
    assert not (tmp_path / "d.md").exists()
