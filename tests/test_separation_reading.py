"""Trained runs read against separation tables (``leaderboard.separation_reading``): runs matched to
predictions by task, method and β; each prediction judged by the leaderboard's rule; a task whose
robot cannot harm, or a method without runs, said and never judged."""

from __future__ import annotations

import json
from pathlib import Path

import pytest
from helpers_results import synthetic_document, synthetic_result

from empathy_zoo.cli import main
from empathy_zoo.markdown_escape import markdown_text
from leaderboard.separation_reading import final_harms, markdown, read_runs


def _row(name: str, method: str, beta: float | None = None) -> dict:
    return {"name": name, "method": method, "selfishness": beta, "identical_to": "", "reason": ""}


TABLE = {
    "rows": [
        _row("dqn", "dqn"),
        _row("dqn_harm_penalty", "dqn_harm_penalty"),
        _row("dqn_lagrangian", "dqn_lagrangian"),
        _row("dqn_considerate", "dqn_considerate"),
        _row("empathic_dqn β=0.5", "empathic_dqn", 0.5),
        _row("empathic_dqn β=0.25", "empathic_dqn", 0.25),
    ],
    "outcomes": [
        {"row": "dqn", "epsilon": 0.0, "harms": 1.0, "robot_harmed": 0.0},
        {"row": "dqn_harm_penalty", "epsilon": 0.0, "harms": 0.0, "robot_harmed": 0.0},  # ▲ predicted
        {"row": "dqn_lagrangian", "epsilon": 0.0, "harms": 1.0, "robot_harmed": 0.0},  # no mark predicted
        {"row": "dqn_considerate", "epsilon": 0.0, "harms": 2.0, "robot_harmed": 0.0},  # ▼ predicted
        {"row": "empathic_dqn β=0.5", "epsilon": 0.0, "harms": 0.0, "robot_harmed": 0.0},  # ▲ predicted
        {"row": "empathic_dqn β=0.25", "epsilon": 0.0, "harms": 3.0, "robot_harmed": 0.0},  # (a β the reading does not read)
    ],
    "pairs": [],
}
SEEDS = range(10)


def _runs(**harms_by_method: float):
    """Ten seeds of each method on Charger, final greedy harms as given (an empathic method at β = 0.5
    unless the key says ``__b0_25``; the others at 1, as they fix it)."""
    runs = []
    for key, harms in harms_by_method.items():
        method, _, beta = key.partition("__b")
        selfishness = float(beta.replace("_", ".")) if beta else (0.5 if method.startswith("empathic") else 1.0)
        for seed in SEEDS:
            runs.append(synthetic_result("charger_v0", method, selfishness, seed, harms=harms))
    return runs


def test_each_prediction_is_judged_on_its_methods_final_greedy_harms() -> None:
    runs = _runs(dqn=1.0, dqn_harm_penalty=0.0, dqn_lagrangian=1.0, empathic_dqn=1.0, empathic_dqn__b0_25=0.0)
    readings = {reading.prediction.method: reading for reading in read_runs({"charger_v0": TABLE}, runs)}
    assert set(readings) == {"dqn_harm_penalty", "dqn_lagrangian", "dqn_considerate", "empathic_dqn"}
    assert readings["dqn_harm_penalty"].judgement.outcome == "holds"
    assert readings["dqn_lagrangian"].judgement.outcome == "holds"  # (no mark, none given)
    assert readings["empathic_dqn"].judgement.observed == "no mark"  # (β = 0.25's fewer harms are not read)
    assert readings["empathic_dqn"].judgement.outcome == "not confirmed"
    assert readings["dqn_considerate"].judgement is None and readings["dqn_considerate"].seeds == 0
    assert readings["dqn_harm_penalty"].seeds == readings["dqn_harm_penalty"].dqn_seeds == 10
    page = markdown(list(readings.values()), {"charger_v0": TABLE})
    assert "| `dqn_considerate` | 1.000 | 2.000 | ▼ more | 0 (10) | — | no runs | not judged |" in page
    assert "Separates in trained runs: **yes**" in page


def test_an_opposite_mark_fails_and_a_task_without_a_holding_mark_does_not_separate() -> None:
    runs = _runs(dqn=0.0, dqn_harm_penalty=1.0)  # (Charger: one cat, harmed at most once)
    (reading,) = [r for r in read_runs({"charger_v0": TABLE}, runs) if r.prediction.method == "dqn_harm_penalty"]
    assert reading.judgement.observed == "more" and reading.judgement.outcome == "fails"
    assert "Separates in trained runs: **no**" in markdown(read_runs({"charger_v0": TABLE}, runs), {"charger_v0": TABLE})


def test_a_variant_and_an_unread_beta_are_left_out_and_a_repeated_seed_refused() -> None:
    own = synthetic_result("charger_v0", "empathic_dqn", 0.5, 0, harms=1.0)
    other_beta = synthetic_result("charger_v0", "empathic_dqn", 0.25, 1, harms=1.0)
    document = synthetic_document("charger_v0", "empathic_dqn", 0.5, 2, harms=1.0)
    from empathy_zoo.experiment.records import RunResult

    variant = RunResult.from_checked({**document, "variant": "charger_big", "run_id": "charger_big__e-0.5__s2"})
    assert final_harms([own, other_beta, variant], {"empathic_dqn": True}) == {("charger_v0", "empathic_dqn"): [1.0]}
    with pytest.raises(ValueError, match="are both empathic_dqn on charger_v0 but of two experiments"):
        final_harms([own, other_beta], {"empathic_dqn": False})  # (two β of a method read at any β: never pooled)
    with pytest.raises(ValueError, match="two runs of empathic_dqn on charger_v0 with seed 0"):
        final_harms([own, own], {"empathic_dqn": True})


def test_the_command_reads_a_directory_and_says_what_it_cannot_read(tmp_path: Path, capsys) -> None:
    runs = tmp_path / "runs"
    runs.mkdir()
    for seed in SEEDS:
        for env, method, harms in (
            ("charger_v0", "dqn", 1.0),
            ("charger_v0", "dqn_harm_penalty", 0.0),
            ("sharing_v0", "dqn", 0.0),
        ):
            document = synthetic_document(env, method, 1.0, seed, harms=harms)
            (runs / f"{document['run_id']}.json").write_text(json.dumps(document))
    tables = tmp_path / "tables"
    tables.mkdir()
    (tables / "charger_v0.json").write_text(json.dumps(TABLE))
    (tables / "sharing_v0.json").write_text(json.dumps({"rows": [_row("dqn", "dqn")], "outcomes": [], "pairs": []}))
    assert main(["analyse", "separation-reading", str(tmp_path), "--tables", str(tables)]) == 0
    out = capsys.readouterr().out
    assert "| `dqn_harm_penalty` | 1.000 | 0.000 | ▲ fewer | 10 (10) |" in out and "| holds |" in out
    assert "## `sharing_v0`\n\nNot read: its robot cannot harm" in out
    assert main(["analyse", "separation-reading", str(tmp_path), "--tables", str(tmp_path / "none")]) == 2
    assert f"separation tables' folder {tmp_path / 'none'} does not exist" in capsys.readouterr().err
    (tmp_path / "empty").mkdir()
    assert main(["analyse", "separation-reading", str(tmp_path), "--tables", str(tmp_path / "empty")]) == 2
    assert "no separation table" in capsys.readouterr().err


def test_every_run_left_out_is_counted_with_its_reason() -> None:
    """No run is left out without a word: each reason says how many runs it kept out."""
    import dataclasses

    from empathy_zoo.experiment.records import RunResult
    from leaderboard.separation_reading import not_read_notes, why_not_read

    read = synthetic_result("charger_v0", "empathic_dqn", 0.5, 0, harms=1.0)
    other_beta = [synthetic_result("charger_v0", "empathic_dqn", 0.25, s, harms=1.0) for s in (1, 2)]
    document = synthetic_document("charger_v0", "dqn", 1.0, 3, harms=1.0)
    variant = RunResult.from_checked({**document, "variant": "charger_big", "run_id": "charger_big__d-1.0__s3"})
    world = synthetic_result("charger_v0", "dqn", 1.0, 4, fixed={"cat_0": "stay"}, harms=1.0)
    unevaluated = dataclasses.replace(synthetic_result("charger_v0", "dqn", 1.0, 5, harms=1.0), eval=())
    unknown = synthetic_result("charger_v0", "dqn_social_value", 1.0, 6, harms=1.0)
    elsewhere = synthetic_result("coexistence_v0", "dqn", 1.0, 7, harms=1.0)
    runs = [read, *other_beta, variant, world, unevaluated, unknown, elsewhere]
    selfish = {"empathic_dqn": True}
    assert [why_not_read(run, selfish) for run in (read, other_beta[0], variant, world, unevaluated)] == [
        None,
        "beta",
        "variant",
        "world",
        "evaluation",
    ]
    notes = not_read_notes(runs, selfish, ["charger_v0"], ["dqn", "empathic_dqn"])
    assert notes == [
        "2 runs of a method with β at another β than 0.5: not read",
        "1 run of a variant, not the task's own world: not read",
        "1 run trained outside the default world the tables model (another environment argument or partner): not read",
        "1 run without a greedy evaluation: not read",
        "1 run of a method no table has a row of (dqn_social_value): not read",
        "1 run of an environment no table models (coexistence_v0): not read",
    ]
    page = markdown(read_runs({"charger_v0": TABLE}, runs), {"charger_v0": TABLE}, notes)
    assert page.endswith("".join(f"* {markdown_text(note)}\n" for note in notes))
    assert "## Runs not read\n\n* 2 runs of a method with β at another β than 0.5: not read\n" in page
    assert "## Runs not read" not in markdown(read_runs({"charger_v0": TABLE}, [read]), {"charger_v0": TABLE})


def test_a_task_of_no_judged_row_is_not_judged_and_names_the_runs_without_dqn() -> None:
    runs = _runs(dqn_harm_penalty=0.0, empathic_dqn=1.0)  # (no DQN runs: nothing can be judged)
    readings = read_runs({"charger_v0": TABLE}, runs)
    assert all(reading.judgement is None for reading in readings)
    page = markdown(readings, {"charger_v0": TABLE})
    assert "Separates in trained runs: **not judged**" in page and "**no**" not in page
    assert (
        "Not judged for want of DQN runs of charger_v0 beside them: dqn_harm_penalty (10 runs), empathic_dqn (10 runs)." in page
    )
