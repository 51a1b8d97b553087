"""Tuning's effect on a verdict: a tuned row is read against the tuned DQN, the untuned against
the untuned DQN, and a verdict that differs is said (synthetic runs whose verdicts are known)."""

from __future__ import annotations

import dataclasses

import pytest
from helpers_results import synthetic_result

from empathy_zoo.experiment.records import RunResult
from leaderboard.tuning_effect import tuning_effect, tuning_effect_table


def _rows(method: str, beta: float, label: str, seeds: range = range(5), **means: float) -> list[RunResult]:
    return [dataclasses.replace(synthetic_result("coexistence_v0", method, beta, s, **means), method_label=label) for s in seeds]


def test_a_tuned_row_is_compared_with_the_tuned_dqn_and_a_changed_verdict_is_said() -> None:
    untuned = _rows("dqn", 1.0, "DQN", harms=0.9, survival=400.0) + _rows("empathic_dqn", 0.5, "E", harms=0.1, survival=400.0)
    # tuning made DQN harm-free too: the tuned method no longer harms less than (the tuned) DQN
    tuned = _rows("dqn", 1.0, "DQN, tuned", harms=0.1, survival=400.0) + _rows(
        "empathic_dqn", 0.5, "E, tuned", harms=0.1, survival=400.0
    )
    effect = tuning_effect(untuned, tuned, {"coexistence_v0": ("harms",)})
    assert effect.unmatched == ()
    harms = {(p.label, p.phase): p for p in effect.pairs}
    assert harms[("E", "eval")].untuned_verdict == "better" and harms[("E", "eval")].tuned_verdict == "no clear difference"
    assert harms[("E", "eval")].changed and harms[("E", "train_final10")].changed
    assert harms[("DQN", "eval")].untuned_verdict is None and not harms[("DQN", "eval")].changed
    assert harms[("DQN", "eval")].untuned_mean > 0.8 and harms[("DQN", "eval")].tuned_mean < 0.2
    text = tuning_effect_table(effect)
    assert "**changed by tuning**" in text and "(the reference)" in text
    assert "Verdicts changed by tuning: 2 of 2." in text


def test_an_unchanged_verdict_is_same_and_a_tuned_row_without_its_untuned_row_is_named() -> None:
    untuned = _rows("dqn", 1.0, "DQN", harms=0.9) + _rows("empathic_dqn", 0.5, "E", harms=0.1)
    tuned = (
        _rows("dqn", 1.0, "DQN, tuned", harms=0.9)
        + _rows("empathic_dqn", 0.5, "E, tuned", harms=0.1)
        + _rows("empathic_dqn", 0.25, "F, tuned", harms=0.1)
    )
    effect = tuning_effect(untuned, tuned, {"coexistence_v0": ("harms",)})
    assert all(not p.changed for p in effect.pairs)
    assert effect.unmatched == (("coexistence_v0", "F, tuned"),)
    text = tuning_effect_table(effect, changed_only=True)
    assert "Verdicts changed by tuning: 0 of 2." in text and "'F, tuned' (coexistence_v0)" in text
    assert "| E |" not in text  # (only the changed are listed)


def test_a_directory_with_two_dqn_rows_in_a_variant_is_refused() -> None:
    untuned = _rows("dqn", 1.0, "DQN", harms=0.9) + _rows("empathic_dqn", 1.0, "Empathic DQN (β=1)", harms=0.9)
    tuned = _rows("dqn", 1.0, "DQN, tuned", harms=0.9)
    with pytest.raises(ValueError, match="coexistence_v0 has 2 DQN reference rows"):
        tuning_effect(untuned, tuned, {"coexistence_v0": ("harms",)})


@pytest.mark.parametrize("which", ["tuned", "untuned"])
def test_a_row_with_no_dqn_beside_it_is_refused_never_read_as_the_reference(which: str) -> None:
    """Without a DQN row there is no verdict: before, the row read "changed by tuning" (6 of 6) or "(the reference)"."""
    untuned = _rows("empathic_dqn", 0.5, "E", harms=0.1)
    tuned = _rows("empathic_dqn", 0.5, "E, tuned", harms=0.1)
    if which == "tuned":
        untuned += _rows("dqn", 1.0, "DQN", harms=0.9)
    else:
        tuned += _rows("dqn", 1.0, "DQN, tuned", harms=0.9)
    row = "E, tuned" if which == "tuned" else "E"
    with pytest.raises(ValueError, match=f"the {which} row '{row}' has no DQN row of its variant, world and budget"):
        tuning_effect(untuned, tuned, {"coexistence_v0": ("harms",)})
