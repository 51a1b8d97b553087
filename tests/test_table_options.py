"""A setting that is a table (SB3's ``algorithm_kwargs``) is a ``train`` option too:
``--algorithm-kwargs KEY=VALUE ...``, each value a TOML value, merged over the ``--config`` file's
table; and a warm-up refusal of an SB3 method names that option."""

from __future__ import annotations

import importlib.util
import json

import pytest

from empathy_zoo.cli import main

needs_sb3 = pytest.mark.skipif(importlib.util.find_spec("stable_baselines3") is None, reason="stable-baselines3 not installed")

SMALL = ["--steps", "600", "--max-cycles", "50", "--eval-interval", "600", "--eval-episodes", "1", "--no-progress"]


def trained_settings(out):
    [run_file] = (out / "runs").glob("*.json")
    return json.loads(run_file.read_text())["config"]["settings"]


@needs_sb3
def test_algorithm_kwargs_reads_toml_values_and_merges_over_the_config_file(tmp_path):
    config = tmp_path / "run.toml"
    config.write_text('method = "sb3_dqn"\n[settings.algorithm_kwargs]\nlearning_starts = 20000\ntarget_update_interval = 50\n')
    argv = ["train", "--config", str(config), "--out", str(tmp_path / "out"), *SMALL]
    assert main([*argv, "--algorithm-kwargs", "learning_starts=300", "exploration_fraction=0.5"]) == 0
    kwargs = trained_settings(tmp_path / "out")["algorithm_kwargs"]
    assert kwargs == {"learning_starts": 300, "target_update_interval": 50, "exploration_fraction": 0.5}


@pytest.mark.parametrize(
    ("given", "said"),
    [
        (["policy=MlpPolicy"], "policy=MlpPolicy: the value is no TOML value (a string needs quotes"),
        (["learning_starts"], "'learning_starts' is no KEY=VALUE"),
        (["learning_starts=1", "learning_starts=2"], "learning_starts given twice"),
    ],
)
def test_a_bad_table_option_is_refused_naming_it(tmp_path, capsys, given, said):
    assert main(["train", "--method", "sb3_dqn", "--out", str(tmp_path), *SMALL, "--algorithm-kwargs", *given]) == 2
    err = capsys.readouterr().err
    assert "argument --algorithm-kwargs: " + said in err, err
    assert not (tmp_path / "runs").exists()


@needs_sb3
def test_an_sb3_warmup_refusal_names_the_option_that_lowers_it(tmp_path, capsys):
    assert main(["train", "--method", "sb3_dqn", "--out", str(tmp_path), *SMALL]) == 2
    err = capsys.readouterr().err
    assert (
        "lower algorithm_kwargs.learning_starts to 60 (a tenth of the budget, train's --algorithm-kwargs learning_starts=60)"
        in err
    )
