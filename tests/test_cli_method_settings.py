"""``empathy-zoo train`` takes the settings of the method it trains: one option per field of that
method's settings class, and the same keys in ``[settings]`` of a ``--config`` file, whether the
method is named by ``--method`` or by the config file; another method's settings are refused,
naming the ones it takes."""

from __future__ import annotations

import json
import subprocess
import sys
from dataclasses import fields
from importlib.metadata import entry_points

import pytest
from helpers_cli_method import TINY, AverseSettings

from baselines.registry import METHODS
from empathy_zoo.cli import main, parse_args
from empathy_zoo.cli.settings_options import option_reading
from empathy_zoo.cli.train import train_values
from empathy_zoo.experiment.values import field_types

AVERSE = "helpers_cli_method:AVERSE_DQN"
ODD = "helpers_cli_method:ODD"


def values(*argv):
    return train_values(parse_args(["train", *argv]))


def help_of(capsys, *argv):
    assert main(["train", *argv, "--help"]) == 0
    return " ".join(capsys.readouterr().out.split())  # argparse wraps lines: compare words


def trained_settings(out):
    [path] = (out / "runs").glob("*.json")
    return json.loads(path.read_text())["config"]["settings"]


def test_a_plugin_methods_own_setting_is_an_option(tmp_path):
    out = tmp_path / "out"
    assert (
        main(["train", "--method", AVERSE, "--aversion", "2", "--cautious", "--widths", "8", "4", "--out", str(out), *TINY]) == 0
    )
    settings = trained_settings(out)
    assert (settings["aversion"], settings["cautious"], settings["widths"]) == (2, True, [8, 4])


def test_a_plugin_methods_own_setting_is_a_config_key_with_the_method_named_in_the_file(tmp_path):
    config = tmp_path / "run.toml"
    config.write_text(f'method = "{AVERSE}"\n[settings]\naversion = 2\n')
    out = tmp_path / "out"
    assert main(["train", "--config", str(config), "--out", str(out), *TINY]) == 0
    assert trained_settings(out)["aversion"] == 2


def test_the_method_named_in_the_config_file_gives_the_options(tmp_path):
    config = tmp_path / "run.toml"
    config.write_text(f'method = "{AVERSE}"\n[settings]\naversion = 2\ncautious = true\n')
    run, settings = values("--config", str(config), "--aversion", "3", "--no-cautious", "--widths", "5")
    assert run["method"] == AVERSE
    assert settings == {"aversion": 3.0, "cautious": False, "widths": (5,)}
    # --method on the command line wins over the file's, and brings its own options
    config.write_text(f'method = "{AVERSE}"\n')
    assert values("--config", str(config), "--method", "empathic_dqn", "--gamma", "0.5")[1] == {"gamma": 0.5}


def test_help_shows_the_chosen_methods_settings_with_their_docs(capsys):
    text = help_of(capsys, "--method", AVERSE)
    assert "settings of averse_dqn" in text
    assert "--aversion FLOAT How strongly the robot shies away from harm (this method's own setting). (default: 1.0)" in text
    assert "--cautious, --no-cautious" in text and "--widths INT [INT ...]" in text
    assert "settings averse_dqn fixes" in text and "(fixed at 1.0)" in text
    assert "--aversion" not in help_of(capsys)  # the default method has no such setting


@pytest.mark.parametrize("name", sorted(METHODS))
def test_help_of_every_registered_method_offers_each_of_its_settings(capsys, name):
    method = METHODS[name]
    text = help_of(capsys, "--method", name)
    kinds = field_types(method.settings)
    for field in fields(method.settings):
        if option_reading(kinds[field.name]) is None:
            assert field.name in text.split("in [settings] only: ")[1], field.name
        else:
            assert "--" + field.name.replace("_", "-") in text, field.name
    for other in {f.name for m in METHODS.values() for f in fields(m.settings)} - set(kinds):
        assert "--" + other.replace("_", "-") + " " not in text, other


def test_a_setting_the_method_fixes_is_refused_naming_the_method(tmp_path, capsys):
    assert main(["train", "--method", AVERSE, "--selfishness", "0.5", "--out", str(tmp_path / "out")]) == 2
    assert "method 'averse_dqn' fixes selfishness=1.0" in capsys.readouterr().err
    assert not (tmp_path / "out").exists()


def test_another_methods_setting_is_refused_with_the_allowed_ones(tmp_path, capsys):
    assert main(["train", "--aversion", "2", "--out", str(tmp_path / "out")]) == 2
    err = capsys.readouterr().err
    assert "unrecognized arguments: --aversion 2" in err
    names = ", ".join(f.name for f in fields(METHODS["empathic_dqn"].settings))
    assert f"the settings of method 'empathic_dqn' are {names};" in err
    config = tmp_path / "run.toml"
    config.write_text("[settings]\naversion = 2\n")
    assert main(["train", "--config", str(config), "--out", str(tmp_path / "out")]) == 2
    err = capsys.readouterr().err
    assert err.startswith("empathy-zoo: error: ") and f"[settings]: unknown key 'aversion'; allowed keys: {names}" in err
    config.write_text(f'method = "{AVERSE}"\n[settings]\nrate = 2\n')
    assert main(["train", "--config", str(config), "--out", str(tmp_path / "out")]) == 2
    assert ", ".join(f.name for f in fields(AverseSettings)) in capsys.readouterr().err
    assert not (tmp_path / "out").exists()


@pytest.mark.parametrize(
    "argv", [["--method", "no_such_method"], ["--method", "no_such_method", "--help"], ["--config", "METHOD_FILE"]]
)
def test_an_unknown_method_is_a_clean_error(tmp_path, capsys, argv):
    config = tmp_path / "run.toml"
    config.write_text('method = "no_such_method"\n')
    assert main(["train", *[str(config) if a == "METHOD_FILE" else a for a in argv]]) == 2
    captured = capsys.readouterr()
    assert captured.err.startswith("empathy-zoo: error: unknown method 'no_such_method'"), captured.err
    assert captured.out == ""


def test_a_method_named_by_a_non_string_in_the_config_file_is_a_clean_error(tmp_path, capsys):
    config = tmp_path / "run.toml"
    config.write_text("method = 3\n")
    assert main(["train", "--config", str(config)]) == 2
    assert f"{config}: method: expected str, got int 3" in capsys.readouterr().err


def test_fields_no_option_can_read_are_config_keys(tmp_path, capsys):
    text = help_of(capsys, "--method", ODD)
    assert "in [settings] only: seed " in text and "--rate FLOAT" in text
    assert "--extras KEY=VALUE [KEY=VALUE ...]" in text  # (a table reads KEY=VALUE pairs)
    config = tmp_path / "run.toml"
    config.write_text("[settings]\nseed = 4\nextras = { depth = 2 }\n")
    run, settings = values("--method", ODD, "--config", str(config), "--seed", "7", "--rate", "0.5")
    assert run["seeds"] == [7]  # --seed is the run's
    assert settings == {"seed": 4, "extras": {"depth": 2}, "rate": 0.5}
    _, settings = values("--method", ODD, "--config", str(config), "--extras", "width=3", "depth=5")
    assert settings == {"seed": 4, "extras": {"depth": 5, "width": 3}}


def test_the_console_script_and_python_dash_m_run_the_command_line():
    [script] = entry_points(group="console_scripts", name="empathy-zoo")
    assert script.load() is main
    done = subprocess.run(
        [sys.executable, "-m", "empathy_zoo.cli", "train", "--method", "dqn", "--help"],
        capture_output=True,
        text=True,
        check=False,
    )
    assert done.returncode == 0, done.stderr
    assert "settings dqn fixes" in done.stdout and "--selfishness" in done.stdout
