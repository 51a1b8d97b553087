"""The equivalence rule of two sets of runs (leaderboard/equivalence.py) on hand-made and synthetic
data: Holm's step-down, a set drawn from the same distribution shows no difference, a moved metric is
found and named, constant cells are not tested, the leaderboard's verdict flips are listed, and the
simulated power behaves as a power must."""

from __future__ import annotations

import numpy as np
import pytest

from empathy_zoo.experiment.records import RunResult
from leaderboard.equivalence import FAMILY_LEVEL, equivalence, holm_rejections, simulated_power, split_flips, verdict_flips
from tests.helpers_results import edited, synthetic_result

SEEDS = range(10)


def runs(draw_seed: int, harm_shift: float = 0.0, beta: float = 0.5, method: str = "empathic_dqn") -> list[RunResult]:
    """Ten seeds of one Coexistence experiment, each run's metric means drawn from ``draw_seed``'s
    generator (harms ~ N(0.5 + shift·0.1, 0.08), within the one cat's [0, 1]; survival ~ N(400, 30),
    the cat's return ~ N(450, 20))."""
    rng = np.random.default_rng(draw_seed)
    return [
        synthetic_result(
            "coexistence_v0",
            method,
            beta,
            seed,
            harms=float(rng.normal(0.5 + harm_shift * 0.1, 0.08)),
            survival=float(rng.normal(400, 30)),
            other_return=float(rng.normal(450, 20)),
            **{"return": 0.0},
        )
        for seed in SEEDS
    ]


def test_holm_on_hand_made_p_values() -> None:
    # m = 4: thresholds 0.0125, 0.01667, 0.025, 0.05 in ascending order of p
    assert holm_rejections([0.01, 0.04, 0.012, 0.3]) == [True, False, True, False]
    assert holm_rejections([0.02, 0.5]) == [True, False]
    assert holm_rejections([0.026, 0.03]) == [False, False]  # the smallest fails 0.025: nothing is rejected
    assert holm_rejections([]) == []


def test_a_set_from_the_same_distribution_shows_no_difference() -> None:
    result = equivalence(runs(1), runs(2))
    assert result.verdict == "no difference detected"
    assert not result.differing
    # one experiment, 3 metrics, 2 phases; `return` is not a Coexistence table metric
    assert {(c.phase, c.metric) for c in result.cells} == {
        (phase, metric) for phase in ("eval", "train_final10") for metric in ("survival", "harms", "other_return")
    }
    assert all(len(c.old) == len(c.new) == 10 for c in result.cells)


def test_a_moved_metric_is_found_and_named() -> None:
    result = equivalence(runs(1), runs(2, harm_shift=4.0))
    assert result.verdict == "different"
    assert {(c.phase, c.metric) for c in result.differing} == {("eval", "harms"), ("train_final10", "harms")}
    assert all(c.p_value <= FAMILY_LEVEL for c in result.differing)


def test_constant_cells_are_not_tested_and_unmatched_experiments_are_listed() -> None:
    old = [synthetic_result("coexistence_v0", "empathic_dqn", 0.5, s, harms=0.0, survival=500.0) for s in SEEDS]
    new = [synthetic_result("coexistence_v0", "empathic_dqn", 0.5, s, harms=0.0, survival=500.0) for s in SEEDS]
    only_new = [synthetic_result("coexistence_v0", "empathic_dqn", 0.25, s, harms=1.0) for s in SEEDS]

    def harm_free(document: dict) -> None:  # every greedy episode
        document["eval"][0]["harms"] = [0.0] * len(document["eval"][0]["harms"])

    old, new = [edited(run, harm_free) for run in old], [edited(run, harm_free) for run in new]
    result = equivalence(old, new + only_new)
    eval_harms = next(c for c in result.cells if (c.phase, c.metric) == ("eval", "harms"))
    assert eval_harms.constant and not eval_harms.differs
    assert len(result.only_new) == 1 and result.only_new[0][2] == 0.25 and not result.only_old
    assert result.verdict in ("no difference detected", "nothing compared")


def test_verdict_flips_are_listed_with_their_p_values() -> None:
    dqn = runs(3, beta=1.0)
    old = dqn + runs(4)  # β = 0.5 drawn like DQN: no clear difference
    new = dqn + runs(5, harm_shift=-4.0)  # β = 0.5 harms far less: better
    flips = verdict_flips(old, new)
    harms = [flip for flip in flips if flip[0][3] == "harms"]
    assert {flip[0][2] for flip in harms} == {"eval", "train_final10"}
    for _key, before, after, p_before, p_after in harms:
        assert (before, after) == ("no clear difference", "better")
        assert p_after < 0.05 <= p_before
    assert verdict_flips(old, old) == []


def test_the_simulated_power_is_the_level_under_the_null_and_grows_with_the_shift() -> None:
    null = simulated_power(0.0, seeds=10, cells=1, trials=400, seed=0)
    assert null <= 0.08  # one cell alone: the test's size, at most 5 % (plus draw noise)
    powers = [simulated_power(shift, seeds=10, cells=20, trials=200, seed=1) for shift in (0.5, 2.0, 4.0)]
    assert powers[0] < powers[1] < powers[2]
    assert powers[2] >= 0.95


@pytest.mark.parametrize("level", [0.01, 0.05])
def test_holm_keeps_the_family_wise_level_under_the_null(level: float) -> None:
    """Where nothing differs, any rejection among 20 cells happens in at most ``level`` of draws."""
    rng = np.random.default_rng(7)
    draws = 300
    any_rejected = 0
    for _ in range(draws):
        from leaderboard.improvement import permutation_test

        p_values = [permutation_test(rng.normal(size=10), rng.normal(size=10))[1] for _ in range(20)]
        any_rejected += any(holm_rejections(p_values, level))
    assert any_rejected / draws <= level + 0.03


def test_split_flips_counts_flips_between_halves_of_the_pooled_runs() -> None:
    dqn_a, dqn_b = runs(3, beta=1.0), runs(6, beta=1.0)
    far = runs(4, harm_shift=-6.0) + runs(5, harm_shift=-6.0)  # β = 0.5 harms far less in both sets: never flips
    counts = split_flips(dqn_a + far[:10], dqn_b + far[10:], trials=5, seed=0)
    assert len(counts) == 5 and all(isinstance(c, int) for c in counts)
    flips_of_harms = split_flips(dqn_a + far[:10], dqn_b + far[10:], trials=5, seed=0)
    assert flips_of_harms == counts  # seeded
    assert max(counts) <= 4  # only survival and the cat's return can flip; both harms cells stay "better"


def test_runs_of_another_budget_are_another_experiment() -> None:
    longer = [edited(run, lambda document: document.update(steps=40000)) for run in runs(2)]
    result = equivalence(runs(1), longer)
    assert result.verdict == "nothing compared" and len(result.only_old) == len(result.only_new) == 1
