"""What the trainer gives a plug-in learner is declared on :class:`agents.base.Learner`: the
keyword ``num_others`` for every learner, and the optional ``replay_bytes_per_run()`` and
``check_observation_range(low, high)``, used where a learner has them; the integer metrics are
the ones :data:`empathy_zoo.metrics.INTEGER_METRICS` names."""

from __future__ import annotations

import pytest
from helpers_learners import REPLAY_BYTES_PER_OTHER

from empathy_zoo.experiment.model import RunSpec
from empathy_zoo.metrics import INTEGER_METRICS, METRIC_NAMES
from empathy_zoo.training import RunnerOptions, train_ensemble


def _train(tmp_path, method: str, num_cats: int = 1, **settings) -> dict:
    spec = RunSpec.of(
        env="coexistence_v0",
        method=f"helpers_learners:{method}",
        settings=settings,
        steps=30,
        eval_interval=30,
        eval_episodes=1,
        env_kwargs={"num_cats": num_cats, "max_cycles": 10},
        fixed={f"cat_{i}": "stay" for i in range(num_cats)},
    )
    (result,) = train_ensemble([spec], tmp_path, RunnerOptions(progress=False, checkpoint_interval=0), write_results=False)
    return result


@pytest.mark.parametrize("num_cats", [1, 3])
def test_a_learner_is_told_how_many_others_there_are_and_reports_its_replay(tmp_path, num_cats: int) -> None:
    result = _train(tmp_path, "RECORDING", num_cats)
    assert result["memory_bytes"] == {"replay_per_run": REPLAY_BYTES_PER_OTHER * num_cats, "learner_per_run": 7}


def test_a_learner_without_the_optional_methods_trains_and_reports_no_replay(tmp_path) -> None:
    result = _train(tmp_path, "PLAIN", 2)
    assert result["memory_bytes"] == {"replay_per_run": 0, "learner_per_run": 7}


def test_an_observation_range_the_learner_refuses_stops_training_before_it_starts(tmp_path) -> None:
    with pytest.raises(ValueError, match=r"observations range over \[-1, 1\], this learner takes values up to 0.5"):
        _train(tmp_path, "RECORDING", highest=0.5)


def test_the_integer_metrics_are_counts_recorded_as_integers(tmp_path) -> None:
    # the constant under test stands on the left
    assert INTEGER_METRICS <= set(METRIC_NAMES)  # noqa: SIM300
    assert INTEGER_METRICS == {"survival", "harms", "batteries", "other_batteries"}  # noqa: SIM300
    train = _train(tmp_path, "PLAIN")["train"]
    assert train["survival"], "the run should end episodes"
    for name in METRIC_NAMES:
        assert all(type(value) is (int if name in INTEGER_METRICS else float) for value in train[name]), name
