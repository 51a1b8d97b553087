"""The held-out reading rule that asks for harm avoidance before calling it general: "generalises"
only where the method is ▲ against DQN beside its own partners and keeps that beside the held-out
one; "keeps its own level" where there was nothing to keep. Harms per 100 steps beside harms per
episode; the old rule's verdicts listed beside the new ones."""

from __future__ import annotations

import math

import numpy as np
import pytest
from helpers_heldout import EPISODES, scenario_set, synthetic_run, write_synthetic

from leaderboard.heldout import heldout_section
from leaderboard.heldout_scores import (
    DOES_NOT_GENERALISE,
    DOES_NOT_KEEP_ITS_LEVEL,
    GENERALISES,
    KEEPS_ITS_LEVEL,
    UNDECIDED,
    heldout_cells,
    load_heldout,
    old_reading_rule,
    reading_rule,
    readings,
)
from leaderboard.heldout_verdicts import heldout_verdicts, verdicts_markdown
from leaderboard.improvement import TOO_FEW_SEEDS
from leaderboard.page_markdown import section_markdown

COEXISTENCE = "coexistence_v0"
OWN = {"cat_0": "random_walk"}
SCENARIOS = {
    "still": {"cat_0": "stay"},
    "chaser": {"cat_0": "chase"},
    "three_cats": {"cat_0": "random_walk", "cat_1": "random_walk", "cat_2": "random_walk"},
}
SEEDS = range(5)


def dqn_values(seed: int) -> dict[str, dict[str, float]]:
    harms = 0.84 + 0.01 * seed
    return {
        "trained_with": {"harms": harms, "survival": 400.0},
        "still": {"harms": harms, "survival": 400.0},
        "chaser": {"harms": 0.9 + 0.01 * seed, "survival": 400.0},
        "three_cats": {"harms": 2.3 + 0.01 * seed, "survival": 400.0},
    }


def careful_values(seed: int) -> dict[str, dict[str, float]]:
    """▲ against DQN beside its own cat (0.1 against 0.84); keeps it beside a still cat; loses it
    beside a chasing one (+0.6)."""
    own = 0.1 + 0.01 * seed
    return {
        "trained_with": {"harms": own, "survival": 300.0},
        "still": {"harms": own + 0.01, "survival": 300.0},
        "chaser": {"harms": own + 0.6, "survival": 300.0},
        "three_cats": {"harms": 3 * own, "survival": 300.0},
    }


def like_dqn_values(seed: int) -> dict[str, dict[str, float]]:
    """As harmful as DQN beside its own cat (no ▲): 0.84 → 2.21 harms with three cats is 0.74 per
    cat, which the old rule called "generalises"."""
    own = 0.84 + 0.01 * seed
    return {
        "trained_with": {"harms": own, "survival": 400.0},
        "still": {"harms": own, "survival": 400.0},
        "chaser": {"harms": own + 0.02, "survival": 400.0},
        "three_cats": {"harms": 2.21 + 0.01 * seed, "survival": 400.0},
    }


@pytest.fixture
def synthetic(tmp_path):
    definition = scenario_set(COEXISTENCE, SCENARIOS)
    pairs = []
    for seed in SEEDS:
        pairs.append((synthetic_run(COEXISTENCE, "dqn", 1.0, seed), dqn_values(seed)))
        pairs.append((synthetic_run(COEXISTENCE, "empathic_dqn", 0.5, seed), careful_values(seed)))
        pairs.append((synthetic_run(COEXISTENCE, "be_considerate", 1.0, seed), like_dqn_values(seed)))
    write_synthetic(tmp_path, pairs, definition, OWN)
    return tmp_path, [run for run, _ in pairs]


def _found(out, results) -> dict[tuple[str, str], tuple[str, str]]:
    (group,), notes = load_heldout(out, results)
    assert notes == []
    return {(r.method_label, r.scenario): (r.old_verdict, r.verdict) for r in readings(group)}


def test_generalises_needs_harm_avoidance_beside_its_own_partners(synthetic) -> None:
    out, results = synthetic
    found = _found(out, results)
    assert found[("empathic_dqn 0.5", "still")] == (GENERALISES, GENERALISES)
    assert found[("empathic_dqn 0.5", "chaser")] == (DOES_NOT_GENERALISE, DOES_NOT_GENERALISE)
    assert found[("empathic_dqn 0.5", "three_cats")] == (GENERALISES, GENERALISES)
    # no ▲ beside its own cat: nothing to keep, so it keeps its own level (the old rule said "generalises")
    assert found[("be_considerate 1.0", "still")] == (GENERALISES, KEEPS_ITS_LEVEL)
    assert found[("be_considerate 1.0", "three_cats")] == (GENERALISES, KEEPS_ITS_LEVEL)
    assert found[("be_considerate 1.0", "chaser")] == (GENERALISES, KEEPS_ITS_LEVEL)


def test_the_reading_records_the_verdict_beside_its_own_partners(synthetic) -> None:
    out, results = synthetic
    (group,), _ = load_heldout(out, results)
    by = {(r.method_label, r.scenario): r for r in readings(group)}
    assert by[("empathic_dqn 0.5", "still")].trained_versus_dqn == "better"
    assert by[("be_considerate 1.0", "still")].trained_versus_dqn == "no clear difference"
    assert "no harm avoidance" in by[("be_considerate 1.0", "still")].why


@pytest.mark.parametrize(
    "trained, versus, low, high, expected",
    [
        ("better", "better", 0.0, 0.05, GENERALISES),
        ("better", "no clear difference", -0.2, 0.1, GENERALISES),
        ("better", "better", 0.11, 0.5, DOES_NOT_GENERALISE),
        ("better", "worse", -0.5, -0.1, DOES_NOT_GENERALISE),
        ("better", "no clear difference", 0.0, 0.2, UNDECIDED),
        ("no clear difference", "no clear difference", -0.2, 0.05, KEEPS_ITS_LEVEL),
        ("worse", "worse", -0.1, 0.0, DOES_NOT_KEEP_ITS_LEVEL),
        ("no clear difference", "better", 0.2, 0.4, DOES_NOT_KEEP_ITS_LEVEL),
        ("no clear difference", "no clear difference", 0.0, 0.2, UNDECIDED),
        ("worse", "no clear difference", 0.0, 0.05, KEEPS_ITS_LEVEL),
        (TOO_FEW_SEEDS, TOO_FEW_SEEDS, 0.0, 0.0, UNDECIDED),
        (None, None, 0.0, 0.0, UNDECIDED),
        ("better", "better", math.nan, math.nan, UNDECIDED),
    ],
)
def test_reading_rule_table(trained, versus, low, high, expected) -> None:
    assert reading_rule(trained, versus, low, high, 0.1)[0] == expected


def test_the_old_rule_is_kept_unchanged() -> None:
    assert old_reading_rule("no clear difference", -0.2, 0.1, 0.1)[0] == GENERALISES
    assert old_reading_rule("worse", -0.5, -0.1, 0.1)[0] == DOES_NOT_GENERALISE
    assert old_reading_rule(TOO_FEW_SEEDS, 0.0, 0.0, 0.1)[0] == UNDECIDED


def test_harms_per_100_steps_is_the_ratio_of_sums_per_run(tmp_path) -> None:
    """A run that dies early harms less per episode but not per 100 steps: episodes of 50 and 150
    steps with 1 and 1 harm give 2 / 200 · 100 = 1.0 per 100 steps (the mean of per-episode ratios
    would say 1.33)."""
    definition = scenario_set(COEXISTENCE, {"still": {"cat_0": "stay"}})
    survival = [50.0, 150.0] * (EPISODES // 2)
    harms = [1.0, 1.0] * (EPISODES // 2)
    pairs = [
        (
            synthetic_run(COEXISTENCE, "empathic_dqn", 0.5, seed),
            {s: {"harms": harms, "survival": survival} for s in ("trained_with", "still")},
        )
        for seed in SEEDS
    ]
    write_synthetic(tmp_path, pairs, definition, OWN)
    (group,), _ = load_heldout(tmp_path, [run for run, _ in pairs])
    assert "harms_per_100_steps" in group.metrics
    cells = {(c.scenario, c.metric): c for c in heldout_cells(group)}
    assert cells[("still", "harms_per_100_steps")].mean == pytest.approx(1.0)
    assert cells[("still", "harms")].mean == pytest.approx(1.0)


def test_harms_per_100_steps_is_compared_with_dqn_towards_fewer(synthetic) -> None:
    out, results = synthetic
    (group,), _ = load_heldout(out, results)
    cells = {(c.method_label, c.scenario, c.metric): c for c in heldout_cells(group)}
    mine = cells[("empathic_dqn 0.5", "still", "harms_per_100_steps")]
    assert mine.mean == pytest.approx(np.mean([(0.11 + 0.01 * s) / 3 for s in SEEDS]))
    assert mine.versus_dqn == "better"


def test_the_section_states_the_rule_its_blind_spots_and_both_measures(synthetic) -> None:
    out, results = synthetic
    found = heldout_section(out, results, out)
    assert found is not None
    markdown = section_markdown(found.section)
    for text in (
        "harms per 100 steps (lower is better)",
        "keeps its own level",
        "old rule: generalises",
        "dies early",
        "says nothing of whether that level is good",
    ):
        assert text in markdown, text


def test_the_command_lists_old_and_new_verdicts(synthetic) -> None:
    from empathy_zoo.atomic import write_json_atomic

    out, results = synthetic
    for run in results:
        write_json_atomic(out / "runs" / f"{run.run_id}.json", run.to_document())
    rows = heldout_verdicts(out)
    assert len(rows) == 6  # two methods × three held-out scenarios
    assert {(r.method_label, r.scenario, r.old_verdict, r.verdict) for r in rows} >= {
        ("be_considerate 1.0", "three_cats", GENERALISES, KEEPS_ITS_LEVEL),
        ("empathic_dqn 0.5", "still", GENERALISES, GENERALISES),
    }
    text = verdicts_markdown(rows)
    assert "| old rule | new rule |" in text and "keeps its own level" in text
    assert "changed: 3 of 6" in text


def test_two_sets_scenarios_of_one_name_are_told_apart(synthetic) -> None:
    from empathy_zoo.atomic import write_json_atomic

    out, results = synthetic
    pairs = [(run, dqn_values(run.seed) if run.method == "dqn" else careful_values(run.seed)) for run in results]
    write_synthetic(out, pairs, scenario_set(COEXISTENCE, SCENARIOS, name="again"), OWN)
    for run in results:
        write_json_atomic(out / "runs" / f"{run.run_id}.json", run.to_document())
    rows = heldout_verdicts(out)
    assert len(rows) == 12 and len({(r.method_label, r.scenario) for r in rows}) == 12
    assert {r.scenario for r in rows} == {f"{name}: {s}" for name in ("again", "synthetic") for s in SCENARIOS}


def test_a_directory_with_no_reading_is_refused_not_read_as_nothing_changed(synthetic, tmp_path, capsys) -> None:
    from empathy_zoo.atomic import write_json_atomic
    from empathy_zoo.cli import main

    _, results = synthetic
    bare = tmp_path / "bare"  # (the runs without their evaluations)
    for run in results:
        write_json_atomic(bare / "runs" / f"{run.run_id}.json", run.to_document())
    assert main(["analyse", "heldout-verdicts", str(bare)]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and str(bare) in err and "holds no held-out reading" in err, err
