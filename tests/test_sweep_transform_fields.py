"""Every method parameter can be swept: the fields of a method's reward transform are keys of a
sweep file's ``[[methods]]`` entry (a list is a grid), ``train`` options and ``[reward]`` keys of a
``--config`` file, checked as the settings are (an unknown key or a value of the wrong type is
refused naming what is allowed); they reach ``config.reward`` (so run ids differ per value) and
the default label. Runs that set none keep their ids and labels. The leaderboard orders labels
by their numbers' values."""

from __future__ import annotations

import dataclasses
import json
import textwrap
from pathlib import Path

import pytest
from helpers_cli_method import TINY
from helpers_results import synthetic_result

from agents.rewards import TrainRewards, same_transform
from baselines.registry import get_method
from baselines.shaping import HarmPenalty, InequityAversion
from empathy_zoo.cli import main, parse_args
from empathy_zoo.cli.train import train_values
from empathy_zoo.experiment.model import RunSpec
from empathy_zoo.experiment.records import RunResult
from empathy_zoo.experiment.result_reader import read_result
from empathy_zoo.experiment.sweep_file import load_sweep
from empathy_zoo.experiment.values import SweepConfigError
from leaderboard.aggregate import group_runs
from leaderboard.ordering import label_order

HEAD = """
[sweep]
seeds = 2
steps = 1000
eval_interval = 500
eval_episodes = 2

[envs.sharing_v0]

[[methods]]
method = "{method}"
"""
SHIPPED = Path(__file__).resolve().parents[1] / "docs" / "results" / "methods" / "runs"


def sweep(tmp_path, method: str, entry: str):
    path = tmp_path / "sweep.toml"
    path.write_text(textwrap.dedent(HEAD.format(method=method)) + textwrap.dedent(entry), encoding="utf-8")
    return path


def error_of(tmp_path, method: str, entry: str) -> str:
    path = sweep(tmp_path, method, entry)
    with pytest.raises(SweepConfigError) as caught:
        load_sweep(path)
    message = str(caught.value)
    assert str(path) in message, message
    return message


# ---------------------------------------------------------------------------- sweep files
def test_a_grid_of_a_transform_field_gives_one_experiment_per_value(tmp_path):
    specs = load_sweep(sweep(tmp_path, "dqn_inequity_aversion", "disadvantageous = [0.1, 0.3, 1.0]\n"))
    assert len(specs) == 3 * 2  # three values × two seeds
    experiments = {s.experiment_id for s in specs}
    assert len(experiments) == 3
    rewards = {json.dumps(s.config()["reward"], sort_keys=True) for s in specs}
    assert [json.loads(r)["disadvantageous"] for r in sorted(rewards)] == [0.1, 0.3, 1.0]
    assert all(json.loads(r)["advantageous"] == 0.05 and json.loads(r)["name"] == "inequity_aversion" for r in rewards)
    assert {s.display_label() for s in specs} == {f"DQN + inequity aversion (disadvantageous={v})" for v in ("0.1", "0.3", "1")}
    assert all(
        s.entry.changed_settings() == {}
        and s.reward_transform() == InequityAversion(disadvantageous=s.entry.changed_reward()["disadvantageous"])
        for s in specs
    )


def test_a_grid_shows_its_default_value_in_the_label_too(tmp_path):
    specs = load_sweep(sweep(tmp_path, "dqn_considerate", "caring = [0.3, 1.0]\nbonus_starts = 5000\n"))
    assert {s.display_label() for s in specs} == {
        "DQN + Be Considerate (caring=0.3, bonus_starts=5000)",
        "DQN + Be Considerate (caring=1, bonus_starts=5000)",
    }
    assert sorted({s.config()["reward"]["caring"] for s in specs}) == [0.3, 1.0]


def test_a_field_is_also_a_reward_dot_key_which_a_field_named_like_a_setting_needs(tmp_path):
    specs = load_sweep(sweep(tmp_path, "dqn_inequity_aversion", "reward.smoothing = [0.5, 0.9]\n"))
    assert sorted({s.config()["reward"]["smoothing"] for s in specs}) == [0.5, 0.9]
    # dqn_aup: learning_rate alone is the DQN learner's; reward.learning_rate is the auxiliary learner's
    [spec, _] = load_sweep(sweep(tmp_path, "dqn_aup", "learning_rate = 0.01\nreward.learning_rate = 0.0001\n"))
    assert spec.config()["settings"]["learning_rate"] == 0.01 and spec.config()["reward"]["learning_rate"] == 0.0001
    assert spec.display_label() == "DQN + AUP (reward.learning_rate=0.0001)"


def test_label_templates_may_name_the_transforms_fields(tmp_path):
    specs = load_sweep(
        sweep(
            tmp_path,
            "dqn_inequity_aversion",
            """\
        label = "IA (α={disadvantageous:g}, γλ={reward.smoothing:.2f}, γ={gamma})"
        disadvantageous = [0.3, 1.0]
        """,
        )
    )
    assert {s.display_label() for s in specs} == {"IA (α=0.3, γλ=0.94, γ=0.99)", "IA (α=1, γλ=0.94, γ=0.99)"}
    message = error_of(tmp_path, "dqn_inequity_aversion", 'label = "{alpha}"\n')
    assert "bad placeholder" in message and "reward transform's fields" in message


def test_an_unknown_key_is_refused_naming_the_settings_and_the_transforms_fields(tmp_path):
    message = error_of(tmp_path, "dqn_inequity_aversion", "alpha = [0.1, 0.3, 1.0]\n")
    assert "[[methods]] #1 (dqn_inequity_aversion): unknown key 'alpha'" in message
    assert "the settings of dqn_inequity_aversion: selfishness, gamma" in message
    assert "the fields of its reward transform 'inequity_aversion': disadvantageous, advantageous, smoothing" in message
    message = error_of(tmp_path, "dqn_inequity_aversion", "reward.alpha = 0.1\n")
    assert "reward.alpha: unknown field 'alpha'" in message and "disadvantageous, advantageous, smoothing" in message
    message = error_of(tmp_path, "dqn_aup", "reward = 3\n")
    assert "expected a table of the reward transform's fields" in message
    assert "it has no reward transform" in error_of(tmp_path, "dqn", "reward.penalty = 1.0\n")
    assert "its reward transform has no fields" in error_of(tmp_path, "dqn_equality", "penalty = 1.0\n")


@pytest.mark.parametrize(
    ("entry", "expected"),
    [
        ('disadvantageous = "high"\n', "disadvantageous: expected float, got str 'high'"),
        ("disadvantageous = [0.1, true]\n", "disadvantageous: expected float, got bool True"),
        ('reward.smoothing = "x"\n', "reward.smoothing: expected float, got str 'x'"),
        ("disadvantageous = []\n", "disadvantageous: empty grid"),
        ("disadvantageous = [1.0, 1]\n", "disadvantageous: value listed twice"),
        ("disadvantageous = 1.0\nreward.disadvantageous = 2.0\n", "disadvantageous is given twice"),
        ("reward.penalty_weight = -1.0\n", "penalty_weight must be a finite number >= 0"),
    ],
)
def test_a_bad_value_is_refused_naming_the_key(tmp_path, entry, expected):
    method = "dqn_aup" if "penalty_weight" in entry else "dqn_inequity_aversion"
    assert expected in error_of(tmp_path, method, entry)


def test_an_int_is_taken_for_a_float_field_and_a_default_value_changes_nothing(tmp_path):
    [given, _] = load_sweep(sweep(tmp_path, "dqn_inequity_aversion", "disadvantageous = 5\n"))
    [plain, _] = load_sweep(sweep(tmp_path, "dqn_inequity_aversion", ""))
    assert given.config()["reward"]["disadvantageous"] == 5.0
    assert (
        (given.run_id, given.display_label())
        == (plain.run_id, plain.display_label())
        == (plain.run_id, "DQN + inequity aversion")
    )


# ---------------------------------------------------------------------------- train
def values(*argv):
    return train_values(parse_args(["train", *argv]))


def test_the_harm_penalty_is_a_train_option(tmp_path):
    run, settings = values("--method", "dqn_harm_penalty", "--penalty", "-10")
    assert run["reward"] == {"penalty": -10.0} and settings == {}
    assert values("--method", "dqn_harm_penalty")[0]["reward"] == {}
    out = tmp_path / "out"
    assert main(["train", "--method", "dqn_harm_penalty", "--penalty", "-10", "--out", str(out), *TINY]) == 0
    [path] = (out / "runs").glob("*.json")
    result = read_result(path)
    assert result.config.reward == {"name": "harm_penalty", "penalty": -10.0}
    assert result.method_label == "DQN + harm penalty (−10)"


def test_a_field_named_like_a_setting_is_a_reward_option_and_a_config_table_sets_fields(tmp_path):
    run, settings = values(
        "--method", "dqn_aup", "--learning-rate", "0.01", "--reward-learning-rate", "0.0001", "--num-rewards", "4"
    )
    assert settings == {"learning_rate": 0.01} and run["reward"] == {"learning_rate": 0.0001, "num_rewards": 4}
    config = tmp_path / "run.toml"
    config.write_text('method = "dqn_inequity_aversion"\n[reward]\ndisadvantageous = 2\nsmoothing = 0.5\n')
    run, _ = values("--config", str(config), "--smoothing", "0.25")
    assert run["reward"] == {"disadvantageous": 2.0, "smoothing": 0.25}  # the command line wins


def test_bad_transform_options_are_clean_errors(tmp_path, capsys):
    assert main(["train", "--method", "dqn_harm_penalty", "--penalty", "high"]) == 2
    assert "argument --penalty: invalid float value: 'high'" in capsys.readouterr().err
    assert main(["train", "--method", "dqn_inequity_aversion", "--alpha", "0.3"]) == 2
    err = capsys.readouterr().err
    assert "unrecognized arguments: --alpha 0.3" in err
    assert "the fields of its reward transform are disadvantageous, advantageous, smoothing" in err
    config = tmp_path / "run.toml"
    for text, expected in [
        (
            'method = "dqn_inequity_aversion"\n[reward]\nalpha = 1.0\n',
            "[reward]: unknown key 'alpha'; allowed keys: disadvantageous, advantageous, smoothing",
        ),
        (
            'method = "dqn_inequity_aversion"\n[reward]\ndisadvantageous = "x"\n',
            "[reward] disadvantageous: expected float, got str 'x'",
        ),
        ('method = "dqn"\n[reward]\npenalty = 1.0\n', "[reward]: method 'dqn' has no reward transform"),
    ]:
        config.write_text(text)
        assert main(["train", "--config", str(config), "--out", str(tmp_path / "out")]) == 2
        assert expected in capsys.readouterr().err
    assert not (tmp_path / "out").exists()


def test_help_lists_the_transforms_fields(capsys):
    assert main(["train", "--method", "dqn_aup", "--help"]) == 0
    text = " ".join(capsys.readouterr().out.split())
    assert "reward transform of dqn_aup" in text and "--penalty-weight FLOAT" in text
    assert "--reward-learning-rate FLOAT" in text and "--reward-batch-size INT" in text


# ---------------------------------------------------------------------------- Python and result files
def test_a_runspec_checks_its_reward_fields():
    with pytest.raises(ValueError, match=r"unknown field\(s\) \['alpha'\].*its fields: disadvantageous, advantageous"):
        RunSpec.of(method="dqn_inequity_aversion", reward={"alpha": 1.0})
    with pytest.raises(ValueError, match="disadvantageous must be a number, got str 'x'"):
        RunSpec.of(method="dqn_inequity_aversion", reward={"disadvantageous": "x"})
    with pytest.raises(ValueError, match="must be a finite number, got float nan"):
        RunSpec.of(method="dqn_harm_penalty", reward={"penalty": float("nan")})
    with pytest.raises(ValueError, match="method 'dqn' has no reward transform"):
        RunSpec.of(method="dqn", reward={"penalty": 1.0})


def test_runs_with_equal_transforms_share_one_state_and_call():
    a, b = get_method("dqn_aup").make_reward({"num_rewards": 4}), get_method("dqn_aup").make_reward({"num_rewards": 4})
    assert a is not b and same_transform(a, b) and not same_transform(a, get_method("dqn_aup").reward)
    rewards = TrainRewards([a, None, b, HarmPenalty()], seeds=[0, 1, 2, 3])
    assert len(rewards.distinct) == 2 and rewards.rows[0].tolist() == [0, 2] and rewards.rows[1].tolist() == [3]


@pytest.mark.parametrize("method", ["dqn_harm_penalty", "dqn_inequity_aversion"])
def test_shipped_result_files_still_load_and_record_the_defaults_a_run_records_now(method):
    paths = sorted(SHIPPED.glob(f"*__{method}-*.json"))
    assert paths
    spec = RunSpec.of(method=method)
    for path in paths:
        assert read_result(path).config.reward == spec.config()["reward"]


# ---------------------------------------------------------------------------- the leaderboard's order
def test_labels_sort_by_their_numbers_values():
    labels = [
        "DQN + IA (disadvantageous=1)",
        "DQN + IA (disadvantageous=0.3)",
        "DQN + IA (disadvantageous=10)",
        "DQN + IA",
        "DQN + IA (disadvantageous=0.1)",
        "DQN + harm penalty (−20)",
        "DQN + harm penalty (−100)",
        "lr 1e-05",
        "lr 0.001",
        "coexistence_v10",
        "coexistence_v9",
    ]
    assert sorted(labels, key=label_order) == [
        "DQN + IA",
        "DQN + IA (disadvantageous=0.1)",
        "DQN + IA (disadvantageous=0.3)",
        "DQN + IA (disadvantageous=1)",
        "DQN + IA (disadvantageous=10)",
        "DQN + harm penalty (−100)",
        "DQN + harm penalty (−20)",
        "coexistence_v10",
        "coexistence_v9",
        "lr 1e-05",
        "lr 0.001",
    ]


def test_the_leaderboard_puts_alpha_one_after_alpha_point_three():
    def run(label: str, method: str = "dqn_inequity_aversion") -> RunResult:
        return dataclasses.replace(synthetic_result("sharing_v0", method, 1.0, 0), method_label=label)

    runs = [
        run("DQN + IA (disadvantageous=1)"),
        run("DQN + IA (disadvantageous=0.3)"),
        run("DQN", "dqn"),
        run("DQN + IA (disadvantageous=0.1)"),
    ]
    assert [label for _, label in group_runs(runs)] == [
        "DQN",
        "DQN + IA (disadvantageous=0.1)",
        "DQN + IA (disadvantageous=0.3)",
        "DQN + IA (disadvantageous=1)",
    ]
