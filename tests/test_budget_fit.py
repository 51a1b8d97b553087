"""A budget that ends inside the warm-up is refused before anything trains (``train``, sweep files,
the Python API), naming the setting to lower and a value; an ε decay that outlasts the budget is
warned about once per sweep, naming the methods; settings that declare nothing are not checked."""

from __future__ import annotations

import textwrap

import pytest

from agents.phases import TrainingPhases, training_phases
from agents.settings import EmpathicDQNSettings
from empathy_zoo.cli import main
from empathy_zoo.experiment import RunSpec, load_sweep, profile_path, profiles
from empathy_zoo.experiment.budget_fit import check_budgets, exploration_shortfall, warmup_refusal
from empathy_zoo.training.options import RunnerOptions
from empathy_zoo.training.runner import train_runs

SMALL = {"replay_capacity": 300, "hidden_size": 8, "target_update_interval": 50}
"""Settings of a run that takes a second."""


def test_empathic_dqn_settings_declare_their_warmup_and_the_end_of_the_decay():
    phases = training_phases(EmpathicDQNSettings(learning_starts=500, epsilon_decay_steps=2_000, batch_size=16))
    assert isinstance(phases, TrainingPhases)
    assert (phases.learning_starts, phases.learning_starts_setting, phases.learning_starts_least) == (500, "learning_starts", 16)
    assert phases.exploration_ends == 2_500
    assert phases.exploration_fix is not None and phases.exploration_fix(2_000) == "epsilon_decay_steps = 1,500"


def test_the_default_warmup_refuses_a_train_of_3000_steps_and_says_what_to_lower(tmp_path, capsys):
    out = tmp_path / "runs"
    assert main(["train", "--out", str(out), "--steps", "3000", "--eval-interval", "3000", "--no-progress"]) == 2
    err = capsys.readouterr().err
    assert "3,000 env steps ends inside the warm-up" in err and "learning_starts = 20,000" in err, err
    assert "lower learning_starts to 300" in err and "raise steps above 20,000" in err, err
    assert not list(out.glob("runs/*.json"))


def test_a_budget_equal_to_the_warmup_is_refused_one_step_more_is_not():
    at = RunSpec.of(steps=2_000, eval_interval=1_000, settings={"learning_starts": 2_000, "epsilon_decay_steps": 1})
    assert warmup_refusal(at) is not None
    with pytest.raises(ValueError, match=at.run_id):
        check_budgets([at])
    after = RunSpec.of(steps=2_001, eval_interval=1_000, settings={"learning_starts": 2_000, "epsilon_decay_steps": 1})
    assert warmup_refusal(after) is None and check_budgets([after]) == []


def test_a_refusal_suggests_no_value_below_the_batch_size():
    spec = RunSpec.of(steps=40, eval_interval=40, settings={"learning_starts": 100, "batch_size": 32})
    refusal = warmup_refusal(spec)
    assert refusal is not None and refusal.endswith("lower learning_starts to 32 (the least it may be) or raise steps above 100")
    spec = RunSpec.of(steps=30, eval_interval=30, settings={"learning_starts": 100, "batch_size": 32})
    refusal = warmup_refusal(spec)
    assert refusal is not None and "lower" not in refusal and refusal.endswith("raise steps above 100")


def test_a_sweep_file_whose_budget_ends_inside_the_warmup_is_refused_before_anything_is_written(tmp_path, capsys):
    sweep = tmp_path / "short.toml"
    sweep.write_text(
        textwrap.dedent(
            """
            [sweep]
            seeds = 1
            steps = 1_000
            eval_interval = 1_000
            eval_episodes = 1

            [settings]
            learning_starts = 5_000

            [envs.coexistence_v0]
            max_cycles = 50

            [[methods]]
            method = "dqn"
            """
        )
    )
    out = tmp_path / "results"
    assert main(["reproduce", "--profile", str(sweep), "--out", str(out), "--no-progress", "--workers", "1"]) == 2
    err = capsys.readouterr().err
    assert "DQN" in err and "ends inside the warm-up" in err and "lower learning_starts to 100" in err, err
    assert not list(out.glob("runs/*.json"))


def test_an_epsilon_decay_past_the_budget_is_warned_about_once_naming_every_method(tmp_path):
    settings = {**SMALL, "learning_starts": 32, "epsilon_decay_steps": 1_000}
    budget = {"steps": 200, "eval_interval": 200, "eval_episodes": 1, "env_kwargs": {"max_cycles": 50}}
    specs = [
        RunSpec.of(method=method, seed=seed, settings=settings, **budget)
        for method in ("dqn", "dqn_harm_penalty")
        for seed in (0, 1)
    ]
    notes: list[str] = []
    train_runs(specs, tmp_path, RunnerOptions(progress=False, checkpoint_interval=0), on_note=notes.append)
    warnings = [note for note in notes if note.startswith("WARNING")]
    assert len(warnings) == 1, notes
    [warning] = warnings
    assert "for 2 method(s)" in warning and "DQN:" in warning and "DQN + harm penalty" in warning, warning
    assert "env step 1,032 (learning_starts + epsilon_decay_steps), after its 200 steps" in warning
    assert "set epsilon_decay_steps = 168" in warning
    assert len(list((tmp_path / "runs").glob("*.json"))) == 4  # a warning, not a refusal


def test_a_decay_that_ends_on_the_last_step_is_not_warned_about():
    spec = RunSpec.of(steps=1_000_000, settings={"learning_starts": 20_000, "epsilon_decay_steps": 980_000})
    assert exploration_shortfall(spec) is None


@pytest.mark.parametrize("profile", profiles())
def test_every_shipped_profile_loads_without_refusal_or_warning(profile):
    assert check_budgets(load_sweep(profile_path(profile))) == []


def test_a_plugin_whose_settings_declare_nothing_is_not_checked():
    spec = RunSpec.of(method="helpers_described_method:KIND_DQN", steps=10, eval_interval=10)
    assert training_phases(spec.method_settings()) is None
    assert check_budgets([spec]) == []


def test_sb3_dqn_declares_its_own_names_and_ppo_declares_nothing():
    pytest.importorskip("stable_baselines3")
    from baselines.sb3 import SB3Settings

    kwargs = {"learning_starts": 1_000, "exploration_fraction": 0.5}
    phases = training_phases(SB3Settings(schedule_steps=10_000, algorithm_kwargs=kwargs))
    assert phases is not None
    assert (phases.learning_starts, phases.learning_starts_setting, phases.exploration_ends) == (
        1_000,
        "algorithm_kwargs.learning_starts",
        5_000,
    )
    assert phases.exploration_fix is not None and phases.exploration_fix(4_000) == "schedule_steps = 8,000"
    assert training_phases(SB3Settings(algorithm="ppo")) is None
