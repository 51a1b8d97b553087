"""Sharing's exact separation table (docs/results/separation/sharing_v0.json, size 5): the committed
rows are the solvers' own and render as shipped; nobody is harmed, and the harm rows are DQN by
construction; Be Considerate is DQN at every ε, computed; every β of either empathic rule has its
own optimum, the golden rule at β ≤ 0.5 leaves every battery to the human, and equality scaling
shares more than DQN; AUP is left out, with its reason."""

from __future__ import annotations

from pathlib import Path

import pytest

from baselines.separation_batteries import battery_figures, layer_figures
from baselines.separation_render import from_json, to_markdown
from empathy_zoo.exact_solver import alone_policy, optimal_values, outcome, tabular_model
from empathy_zoo.reference import greedy_policy

RESULTS = Path(__file__).resolve().parents[1] / "docs" / "results" / "separation"
ARGUMENTS = {"size": 5, "view": 3}
"""The table's Sharing: the 5×5 torus (view 3: the window must be smaller than the grid)."""


@pytest.fixture(scope="module")
def model():
    return tabular_model("sharing_v0", **ARGUMENTS)


@pytest.fixture(scope="module")
def committed():
    return from_json((RESULTS / "sharing_v0.json").read_text(encoding="utf-8"))


def test_the_committed_table_is_the_model_s_and_renders_as_shipped(model, committed) -> None:
    assert dict(committed.arguments) == ARGUMENTS
    dqn = committed.outcome("dqn", 0.0)
    result = outcome(model, greedy_policy(optimal_values(model)), committed.max_cycles, alone_policy(model, 0.0))
    assert dqn.survival == pytest.approx(result.survival, abs=1e-9)
    assert dqn.batteries == pytest.approx(battery_figures(result, layer_figures(model))["batteries"], abs=1e-9)
    assert to_markdown(committed) == (RESULTS / "sharing_v0.md").read_text(encoding="utf-8")


def test_nobody_is_harmed_and_the_harm_rows_are_dqn_by_construction(committed) -> None:
    assert all(o.harms == 0.0 and o.robot_harmed == 0.0 for o in committed.outcomes)
    rows = {row.name: row for row in committed.rows}
    for name in ("dqn_harm_penalty", "dqn_lagrangian", "dqn_silver_literal"):
        assert rows[name].identical_to == "dqn", name
    for epsilon in committed.epsilons:
        pair = committed.pair("dqn", "dqn_harm_penalty", epsilon)
        assert pair is not None and pair.by_construction and not pair.differ


def test_be_considerate_is_dqn_at_every_epsilon_computed_not_by_construction(committed) -> None:
    row = next(row for row in committed.rows if row.name == "dqn_considerate")
    assert not row.identical_to
    for epsilon in committed.epsilons:
        pair = committed.pair("dqn", "dqn_considerate", epsilon)
        assert pair is not None and not pair.by_construction and not pair.differ and pair.differing_states == 0


def test_every_beta_of_either_rule_has_its_own_optimum_and_the_golden_rule_gives_way(committed) -> None:
    for method in ("empathic_dqn", "empathic_dqn_silver"):
        names = [row.name for row in committed.rows if row.method == method]
        for epsilon in committed.epsilons:
            for i, first in enumerate(names):
                for second in names[i + 1 :]:
                    assert committed.differ(first, second, epsilon), (first, second, epsilon)
    dqn = committed.outcome("dqn", 0.0)
    for beta in ("0.5", "0.25", "0"):
        golden = committed.outcome(f"empathic_dqn β={beta}", 0.0)
        assert golden.batteries == pytest.approx(0.0, abs=1e-9)
        assert golden.other_batteries == pytest.approx(4.0, abs=1e-3)  # (the random human, in 500 steps)
    assert dqn.batteries is not None and dqn.batteries > 3.5  # DQN takes nearly all
    assert committed.differ("dqn", "dqn_equality", 0.0)
    equality = committed.outcome("dqn_equality", 0.0).equality
    assert dqn.equality is not None and equality is not None and equality > dqn.equality + 0.3


def test_aup_is_left_out_with_its_reason(committed) -> None:
    assert [o.method for o in committed.omitted] == ["dqn_aup"]
    assert "30,000 joint states" in committed.omitted[0].reason
