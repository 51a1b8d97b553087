"""The held-out section's reading rule on hand-made evaluation files whose verdicts are known both
ways (generalises, does not: by its own partners and by DQN's), before any real run is judged; the
section and its figure rendered from them."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest
from helpers_heldout import scenario_set, synthetic_run, write_synthetic

from empathy_zoo.experiment.records import AgentRef
from empathy_zoo.metrics import HELDOUT_MARGINS
from leaderboard.heldout import heldout_section
from leaderboard.heldout_scores import (
    DOES_NOT_GENERALISE,
    GENERALISES,
    UNDECIDED,
    heldout_cells,
    load_heldout,
    old_reading_rule,
    readings,
)
from leaderboard.improvement import TOO_FEW_SEEDS
from leaderboard.page import Page
from leaderboard.page_html import to_html
from leaderboard.page_markdown import section_markdown

COEXISTENCE = "coexistence_v0"
OWN = {"cat_0": "random_walk"}
SCENARIOS = {
    "kept": {"cat_0": "stay"},
    "lost": {"cat_0": "chase"},
    "below_dqn": {"cat_0": "keep_away"},
    "noisy": {"cat_0": "slow_walk(move_probability=0.1)"},
    "two_cats": {"cat_0": "random_walk", "cat_1": "random_walk"},
}
SEEDS = range(5)
DQN_HARMS = 0.8


def method_harms(seed: int) -> dict[str, float]:
    """Harms per episode of the method's run ``seed`` in every scenario: kept (+0.02, ▲ against DQN),
    lost (+0.5: still ▲ against DQN, but far from its own partners), below_dqn (+0.05 where DQN
    harms nothing: ▼), noisy (+0.3 on two seeds of five: the seeds cannot tell), two_cats (twice the
    harms with twice the cats: the same harms per cat)."""
    own = 0.1 + 0.01 * seed
    return {
        "trained_with": own,
        "kept": own + 0.02,
        "lost": own + 0.5 + 0.01 * seed,
        "below_dqn": own + 0.05,
        "noisy": own + (0.3 if seed in (1, 3) else 0.0),
        "two_cats": 2 * own,
    }


def dqn_harms(seed: int) -> dict[str, float]:
    base = DQN_HARMS + 0.01 * seed
    return {**dict.fromkeys(("trained_with", *SCENARIOS), base), "below_dqn": 0.0}


@pytest.fixture
def synthetic(tmp_path):
    definition = scenario_set(COEXISTENCE, SCENARIOS)
    pairs = []
    for seed in SEEDS:
        dqn = synthetic_run(COEXISTENCE, "dqn", 1.0, seed)
        mine = synthetic_run(COEXISTENCE, "empathic_dqn", 0.5, seed)
        pairs.append((dqn, {s: {"harms": h, "survival": 400.0} for s, h in dqn_harms(seed).items()}))
        pairs.append((mine, {s: {"harms": h, "survival": 300.0} for s, h in method_harms(seed).items()}))
    write_synthetic(tmp_path, pairs, definition, OWN)
    return tmp_path, [run for run, _ in pairs]


def verdicts(out, results) -> dict[str, str]:
    (group,), notes = load_heldout(out, results)
    assert notes == []
    return {r.scenario: r.verdict for r in readings(group)}


def test_the_reading_rule_on_known_cases(synthetic) -> None:
    out, results = synthetic
    assert verdicts(out, results) == {
        "kept": GENERALISES,
        "lost": DOES_NOT_GENERALISE,
        "below_dqn": DOES_NOT_GENERALISE,
        "noisy": UNDECIDED,
        "two_cats": GENERALISES,
    }


def test_why_each_verdict_was_given(synthetic) -> None:
    out, results = synthetic
    (group,), _ = load_heldout(out, results)
    found = {r.scenario: r for r in readings(group)}
    assert found["lost"].versus_dqn == "better" and found["lost"].gap_low > HELDOUT_MARGINS["harms"]
    assert found["below_dqn"].versus_dqn == "worse" and "DQN" in found["below_dqn"].why
    assert found["kept"].versus_dqn == "better" and found["kept"].gap == pytest.approx(0.02)
    assert found["two_cats"].gap == pytest.approx(0.0)  # harms per cat: 2·h over 2 cats is h
    assert found["noisy"].gap_low <= HELDOUT_MARGINS["harms"] < found["noisy"].gap_high


def test_fewer_seeds_than_the_test_needs_leave_every_reading_undecided(synthetic) -> None:
    out, results = synthetic
    few = [run for run in results if run.seed < 3]  # 3 against 3: the exact test cannot reach 5 %
    (group,), notes = load_heldout(out, few)
    assert all(r.verdict == UNDECIDED and r.versus_dqn == TOO_FEW_SEEDS for r in readings(group))
    assert len(notes) == 4  # the evaluations of the seeds left out have no result file here


def test_without_dqn_nothing_is_judged(synthetic) -> None:
    out, results = synthetic
    (group,), _ = load_heldout(out, [run for run in results if run.method != "dqn"])
    assert {r.verdict for r in readings(group)} == {UNDECIDED}
    assert all("no DQN" in r.why for r in readings(group))


@pytest.mark.parametrize(
    "versus, low, high, expected",
    [
        ("better", 0.0, 0.05, GENERALISES),
        ("no clear difference", -0.2, 0.1, GENERALISES),
        ("no clear difference", 0.0, 0.2, UNDECIDED),
        ("better", 0.11, 0.5, DOES_NOT_GENERALISE),
        ("worse", -0.5, -0.1, DOES_NOT_GENERALISE),
        (TOO_FEW_SEEDS, 0.5, 0.9, UNDECIDED),
        (None, 0.0, 0.0, UNDECIDED),
        ("better", math.nan, math.nan, UNDECIDED),
    ],
)
def test_reading_rule_table(versus, low, high, expected) -> None:
    assert old_reading_rule(versus, low, high, 0.1)[0] == expected


def test_equality_in_sharing_is_judged_towards_lower(tmp_path) -> None:
    env, own = "sharing_v0", {"human_0": "patrol"}
    definition = scenario_set(env, {"fair": {"human_0": "stay"}, "unfair": {"human_0": "random_walk"}})
    pairs = []
    for seed in SEEDS:
        noise = 0.005 * seed
        pairs.append(
            (synthetic_run(env, "dqn", 1.0, seed), {s: {"equality": 0.3 + noise} for s in ("trained_with", "fair", "unfair")})
        )
        mine = {"trained_with": 0.9 + noise, "fair": 0.85 + noise, "unfair": 0.5 + 2 * noise}
        pairs.append((synthetic_run(env, "empathic_dqn", 0.5, seed), {s: {"equality": e} for s, e in mine.items()}))
    write_synthetic(tmp_path, pairs, definition, own)
    assert verdicts(tmp_path, [run for run, _ in pairs]) == {"fair": GENERALISES, "unfair": DOES_NOT_GENERALISE}


def test_cells_are_the_means_over_seeds_with_the_suites_marks(synthetic) -> None:
    out, results = synthetic
    (group,), _ = load_heldout(out, results)
    cells = {(c.method_label, c.scenario, c.metric): c for c in heldout_cells(group)}
    mine = cells[("empathic_dqn 0.5", "kept", "harms")]
    assert mine.mean == pytest.approx(np.mean([method_harms(s)["kept"] for s in SEEDS]))
    assert mine.versus_dqn == "better" and mine.probability == 1.0
    assert cells[("empathic_dqn 0.5", "below_dqn", "harms")].versus_dqn == "worse"
    assert cells[("dqn 1.0", "kept", "harms")].versus_dqn is None  # DQN is the reference


def test_the_section_renders_with_its_rule_and_figure(synthetic) -> None:
    out, results = synthetic
    found = heldout_section(out, results, out)
    assert found is not None and found.section.title == "Held-out partners"
    section, html_page, figures = section_markdown(found.section), to_html(Page("board", [found.section])), found.figures
    for text in (
        "Reading rule",
        "✓ generalises",
        "✗ does not generalise",
        "? undecided",
        "P(improves on DQN): harms",
        "Why kept.",
    ):
        assert text in section
    assert "<h2>Held-out partners</h2>" in html_page
    (path,) = figures.values()
    assert path.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert f"]({path.relative_to(out).as_posix()})" in section


def test_without_evaluation_files_there_is_no_section(tmp_path) -> None:
    run = synthetic_run(COEXISTENCE, "dqn", 1.0, 0)
    assert heldout_section(tmp_path, [run], tmp_path) is None


def test_an_evaluation_of_another_agent_is_left_out_with_a_note(synthetic) -> None:
    out, results = synthetic
    retrained = AgentRef(f"{results[0].run_id}.agent.pt", "0" * 64)
    changed = [dataclasses.replace(run, agent=retrained) if run.seed == 0 else run for run in results]
    (group,), notes = load_heldout(out, changed)
    assert len(notes) == 2 and all("another agent" in note for note in notes)
    assert all(len(pairs) == 4 for pairs in group.runs.values())


def test_a_run_without_an_evaluation_is_named_in_a_note_with_its_rows_count(synthetic) -> None:
    from empathy_zoo.evaluation_file import evaluation_path

    out, results = synthetic
    (missing,) = [run for run in results if run.method == "empathic_dqn" and run.seed == 2]
    evaluation_path(out, "synthetic", missing.run_id).unlink()
    (group,), notes = load_heldout(out, results)
    assert len(group.runs["empathic_dqn 0.5"]) == 4 and len(group.runs["dqn 1.0"]) == 5
    (note,) = notes
    assert missing.run_id in note and "seed 2" in note and "empathic_dqn 0.5" in note and "4 of its 5 runs" in note
    section = heldout_section(out, results, out)
    assert section is not None
    assert missing.run_id in section_markdown(section.section)
    unevaluated = [synthetic_run(COEXISTENCE, "empathic_dqn", 0.9, seed) for seed in SEEDS]  # (a row of no evaluation:
    (group,), notes = load_heldout(out, [*results, *unevaluated])  # absent from the section, named in a note)
    assert "empathic_dqn 0.9" not in group.runs and len(notes) == 2
    assert any("rows with no evaluation in it, so in none of its tables: empathic_dqn 0.9 (5 runs)" in note for note in notes)


def test_seeds_evaluated_with_different_episode_counts_are_named_in_a_note(synthetic) -> None:
    import json

    from empathy_zoo.evaluation_file import evaluation_path

    out, results = synthetic
    path = evaluation_path(out, "synthetic", results[1].run_id)
    document = json.loads(path.read_text())
    document["episodes"] = 10
    for entry in document["scenarios"]:
        entry["metrics"] = {metric: values[:10] for metric, values in entry["metrics"].items()}
    path.write_text(json.dumps(document))
    (group,), notes = load_heldout(out, results)
    (note,) = notes
    assert "10 to 100 episodes" in note and str(path) in note
    assert sum(len(pairs) for pairs in group.runs.values()) == len(results)


def test_several_results_directories_match_each_evaluation_in_its_own(synthetic, tmp_path) -> None:
    import shutil

    out, results = synthetic
    other = tmp_path / "other"
    shutil.copytree(out / "evaluations", other / "evaluations")
    prefixed = [dataclasses.replace(run, method_label=f"B {run.method_label}") for run in results]
    (group,), notes = load_heldout([out, other], results + prefixed, [str(out)] * len(results) + [str(other)] * len(results))
    assert notes == [] and set(group.runs) == {"dqn 1.0", "empathic_dqn 0.5", "B dqn 1.0", "B empathic_dqn 0.5"}
    with pytest.raises(ValueError, match="need each result's origin"):
        load_heldout([out, other], results + prefixed)


def test_the_figure_draws_no_interval_for_a_row_of_fewer_than_three_seeds(tmp_path, monkeypatch) -> None:
    """As the tables say "(n=2: no interval)", the figure draws no band and no bars for such a row,
    and its tick label says so; a row of enough seeds keeps both."""
    from matplotlib.axes import Axes

    from leaderboard.heldout_plot import render_heldout_png

    definition = scenario_set(COEXISTENCE, SCENARIOS)
    pairs = []
    for seed in SEEDS:
        dqn = synthetic_run(COEXISTENCE, "dqn", 1.0, seed)
        pairs.append((dqn, {s: {"harms": h, "survival": 400.0} for s, h in dqn_harms(seed).items()}))
    for seed in SEEDS[:2]:
        mine = synthetic_run(COEXISTENCE, "empathic_dqn", 0.5, seed)
        pairs.append((mine, {s: {"harms": h, "survival": 300.0} for s, h in method_harms(seed).items()}))
    write_synthetic(tmp_path, pairs, definition, OWN)
    (group,), _ = load_heldout(tmp_path, [run for run, _ in pairs])
    bars, bands, ticks = [], [], []
    real_errorbar, real_fill, real_ticks = Axes.errorbar, Axes.fill_between, Axes.set_xticklabels
    monkeypatch.setattr(Axes, "errorbar", lambda self, x, y, **kw: bars.append(kw.get("yerr")) or real_errorbar(self, x, y, **kw))
    monkeypatch.setattr(Axes, "fill_between", lambda self, *a, **kw: bands.append(a) or real_fill(self, *a, **kw))
    monkeypatch.setattr(
        Axes, "set_xticklabels", lambda self, labels, **kw: ticks.extend(labels) or real_ticks(self, labels, **kw)
    )
    assert render_heldout_png(group, heldout_cells(group))[:8] == b"\x89PNG\r\n\x1a\n"
    few = [t for t in ticks if "n=2: no interval" in t]
    assert few and all("n=2" not in t for t in ticks if t not in few)
    held_out = len(group.scenarios) - 1
    per_metric_row = held_out  # one marker per held-out scenario
    assert sum(b is None for b in bars) == per_metric_row * len(group.metrics)  # the 2-seed row: markers only
    assert sum(b is not None for b in bars) == per_metric_row * len(group.metrics)  # DQN's row keeps its bars
    assert len(bands) == len(group.metrics)  # DQN's band only


def test_the_rule_states_the_range_of_harms_in_each_environment() -> None:
    """Vase's vase is harmed too: its harms per other agent reach 2 beside one cat, and the rule says so."""
    from leaderboard.heldout import _range_text

    assert _range_text("harms", "coexistence_v0") == "harms per other agent lie in [0, 1]: a harmed cat leaves"
    vase = _range_text("harms", "vase_v0")
    assert vase.startswith("harms per other agent lie in [0, 1]: a harmed cat leaves; in vase_v0")
    assert "lie in [0, 2] beside one other agent" in vase and "a tenth of the other agents' part" in vase
    assert _range_text("equality", "sharing_v0") == "[0, 1]"
