"""Relative reachability and AUP in every separation table small enough: computed from the model's
own states on a model of the cells only (Charger, Coexistence's rules of the authors), AUP beside
the paper's displacement-table reachability on Coexistence; each row tested against DQN's."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from empathy_zoo.exact_solver import tabular_model

TABLES = Path(__file__).resolve().parents[1] / "docs" / "results" / "separation"


def _table(name: str) -> dict:
    return json.loads((TABLES / f"{name}.json").read_text())


def test_aup_penalises_a_model_of_the_cells_only() -> None:
    """On Charger's 5×5 variant (no layer to set): AUP's reward is the model's less a penalty that
    is never negative, finite everywhere, and positive somewhere."""
    from baselines.separation_world import attainable_utility_reward

    model = tabular_model("charger_v0", size=5, view=3)
    assert model.layers == 1
    shaped = attainable_utility_reward(model, 0.99)
    assert shaped.shape == model.reward.shape and np.isfinite(shaped).all()
    penalty = model.reward - shaped
    assert penalty.min() >= -1e-12 and penalty.max() > 0


@pytest.mark.parametrize(
    "name, rows",
    [
        ("charger_v0", ("dqn_relative_reachability", "dqn_aup")),
        ("coexistence_v0", ("dqn_relative_reachability", "dqn_aup")),
        ("coexistence_v0_authors", ("dqn_relative_reachability", "dqn_aup")),
        ("vase_v0", ("dqn_relative_reachability", "dqn_aup")),
        ("helping_v0", ("dqn_relative_reachability", "dqn_aup")),
        ("sharing_v0", ("dqn_relative_reachability",)),
    ],
)
def test_every_shipped_table_holds_the_rows_its_model_is_small_enough_for(name: str, rows: tuple[str, ...]) -> None:
    table = _table(name)
    names = {row["name"] for row in table["rows"]}
    omitted = {entry["method"]: entry["reason"] for entry in table["omitted"]}
    for row in rows:
        assert row in names and row not in omitted, (name, row)
        assert {o["epsilon"] for o in table["outcomes"] if o["row"] == row} == {0.0, 0.01, 0.05}
    if "dqn_aup" not in rows:
        assert "would take too long on the model's" in omitted["dqn_aup"]


@pytest.mark.parametrize("name", ["charger_v0", "coexistence_v0", "coexistence_v0_authors"])
def test_the_new_rows_act_unlike_dqn_and_each_other(name: str) -> None:
    """Computed, not assumed: each new row's greedy policy differs from DQN's and from the other's
    in states the ε-greedy policies reach."""
    pairs = {(p["first"], p["second"]): p for p in _table(name)["pairs"] if p["epsilon"] == 0.01}
    for pair in (("dqn", "dqn_relative_reachability"), ("dqn", "dqn_aup"), ("dqn_relative_reachability", "dqn_aup")):
        assert pairs[pair]["differ"] and pairs[pair]["differing_states"] > 0 and not pairs[pair]["by_construction"], pair
