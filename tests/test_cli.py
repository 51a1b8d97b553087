"""The ``empathy-zoo`` command line end to end, on tiny runs: train, precedence of defaults <
config file < command line, bad input, reproduce + leaderboard, resume after a deleted result or
a kill, corrupted files."""

from __future__ import annotations

import json
import textwrap
from pathlib import Path

import pytest
from helpers_cli_method import TINY
from helpers_sweeps import TWO_ENV_SWEEP as TINY_SWEEP

import empathy_zoo.training.ensemble as ensemble
from empathy_zoo.cli import main, parse_args
from empathy_zoo.cli.train import train_values
from empathy_zoo.training.resume import CHECKPOINT_DIR

DOCS = Path(__file__).resolve().parents[1] / "docs"
QUICK = DOCS / "results" / "quick"


def run_files(out):
    return sorted((out / "runs").glob("*.json"))


def train(out, *extra):
    return main(["train", "--out", str(out), *TINY, *extra])


# ---------------------------------------------------------------------------- train
def test_train_writes_a_result_file_with_the_schema(tmp_path, capsys):
    out = tmp_path / "runs"
    assert train(out, "--env", "sharing_v0", "--selfishness", "0.5", "--seed", "3") == 0
    [path] = run_files(out)
    result = json.loads(path.read_text())
    for key in (
        "schema",
        "run_id",
        "env",
        "variant",
        "method",
        "method_label",
        "seed",
        "config",
        "steps",
        "train",
        "eval",
        "memory_bytes",
        "wall_time_s",
        "version",
        "commit",
        "created",
    ):
        assert key in result
    assert (result["env"], result["method"], result["seed"], result["steps"]) == ("sharing_v0", "empathic_dqn", 3, 300)
    assert result["method_label"] == "Empathic DQN (β=0.5)"
    assert result["config"]["settings"]["selfishness"] == 0.5
    assert result["config"]["settings"]["hidden_size"] == 16
    assert result["config"]["env_kwargs"] == {"max_cycles": 50}
    assert [e["step"] for e in result["eval"]] == [150, 300]
    assert len(result["eval"][0]["survival"]) == 2
    assert len(result["train"]["survival"]) == len(result["train"]["episode_end_step"]) > 0
    printed = capsys.readouterr().out
    assert str(out / "runs") in printed
    assert f"{result['run_id']} [Empathic DQN (β=0.5)]: final 10% of training: batteries" in printed and "harms" not in printed
    assert "last eval (step 300)" in printed


def parsed_values(*argv):
    return train_values(parse_args(["train", *argv]))


def test_precedence_defaults_then_config_then_command_line(tmp_path):
    config = tmp_path / "run.toml"
    config.write_text(
        textwrap.dedent("""
        env = "sharing_v0"
        steps = 5000
        seeds = [4, 5]
        fixed = { human_0 = "stay" }

        [settings]
        selfishness = 0.25
        learning_rate = 0.002
        hidden_size = 64
    """)
    )
    run, settings = parsed_values("--config", str(config))
    assert (run["env"], run["steps"], run["seeds"], run["method"]) == ("sharing_v0", 5000, [4, 5], "empathic_dqn")
    assert run["fixed"] == {"human_0": "stay"} and run["eval_interval"] == 50_000
    assert settings == {"selfishness": 0.25, "learning_rate": 0.002, "hidden_size": 64}
    run, settings = parsed_values(
        "--config", str(config), "--steps", "700", "--seed", "1", "--selfishness", "0.75", "--gamma", "0.5"
    )
    assert (run["env"], run["steps"], run["seeds"]) == ("sharing_v0", 700, [1])
    assert settings == {"selfishness": 0.75, "learning_rate": 0.002, "hidden_size": 64, "gamma": 0.5}
    run, settings = parsed_values()
    assert (run["env"], run["method"], run["seeds"], run["steps"], settings) == (
        "coexistence_v0",
        "empathic_dqn",
        [0],
        1_000_000,
        {},
    )


def test_config_file_is_applied_end_to_end(tmp_path):
    config = tmp_path / "run.toml"
    config.write_text('env = "sharing_v0"\nseed = 2\n[settings]\nselfishness = 0.25\nlearning_rate = 0.002\n')
    out = tmp_path / "out"
    assert train(out, "--config", str(config), "--selfishness", "0.75") == 0
    [path] = run_files(out)
    result = json.loads(path.read_text())
    assert (result["env"], result["seed"]) == ("sharing_v0", 2)
    assert result["config"]["settings"]["selfishness"] == 0.75
    assert result["config"]["settings"]["learning_rate"] == 0.002


def test_a_config_file_builds_a_fixed_agent_with_arguments(tmp_path, capsys):
    config = tmp_path / "run.toml"
    config.write_text('env = "sharing_v0"\nfixed = { human_0 = { policy = "patrol", period = 3 } }\n')
    out = tmp_path / "out"
    assert train(out, "--config", str(config)) == 0
    [path] = run_files(out)
    assert json.loads(path.read_text())["config"]["fixed"] == {"human_0": "patrol(period=3)"}
    config.write_text('env = "sharing_v0"\nfixed = { human_0 = { policy = "patrol", pace = 3 } }\n')
    assert train(tmp_path / "bad", "--config", str(config)) == 2
    assert "takes no argument 'pace'" in capsys.readouterr().err


@pytest.mark.parametrize(
    ("content", "expected"),
    [
        ("steps = 100\nfoo = 1\n", "top level: unknown key 'foo'; allowed keys: env, method"),
        ("steps = 'many'\n", "steps: expected int, got str 'many'"),
        ("[settings]\nselfishness = 'high'\n", "[settings] selfishness: expected float, got str 'high'"),
        ("[settings]\nlearning_rat = 0.1\n", "[settings]: unknown key 'learning_rat'"),
        ("seed = 1\nseeds = [2]\n", "give 'seed' or 'seeds', not both"),
        ("steps = = 1\n", "not valid TOML"),
    ],
)
def test_bad_config_file_exits_2_naming_file_and_key(tmp_path, capsys, content, expected):
    config = tmp_path / "bad.toml"
    config.write_text(content)
    assert main(["train", "--config", str(config), "--out", str(tmp_path / "out")]) == 2
    err = capsys.readouterr().err
    assert err.startswith("empathy-zoo: error: ") and str(config) in err and expected in err, err
    assert "Traceback" not in err
    assert not (tmp_path / "out").exists()


@pytest.mark.parametrize(
    ("argv", "expected"),
    [
        (["train", "--method", "no_such_method"], "unknown method 'no_such_method'"),
        (["train", "--env", "chess_v0"], "unknown environment 'chess_v0'"),
        (["train", "--method", "dqn", "--selfishness", "0.5"], "fixes selfishness=1.0"),
        (["train", "--selfishness", "1.5"], "selfishness must be in [0, 1]"),
        (["train", "--steps", "0"], "steps must be a positive int"),
        (["train", "--fixed", "dog_0=stay"], "unknown agent(s) ['dog_0']"),
        (["train", "--fixed", "cat_0=nosuch"], "fixed.cat_0: unknown fixed policy 'nosuch'"),
        (["train", "--size", "4"], "size must be at least 5"),
        (["train", "--view", "4"], "view must be odd"),
        (["train", "--num-cats", "0"], "num_cats must be at least 1"),
        (["train", "--env", "sharing_v0", "--start", "corner"], "start must be one of 'random', 'centre'"),
        (["train", "--device", "tpu"], "--device 'tpu'"),
        (["reproduce", "--profile", "no_such_profile"], "unknown profile 'no_such_profile'"),
        (["reproduce", "--profile", str(DOCS)], "docs is a directory, not a sweep file"),
        (["reproduction", str(QUICK), "--note", "no_such_note.md", "--out", "-"], "--note no_such_note.md does not exist"),
        (["reproduction", str(QUICK), "--note", str(DOCS), "--out", "-"], "docs is a directory, not a file"),
        (["leaderboard", "/nonexistent/results"], "does not exist"),
        (["play", "--env", "chess_v0"], "unknown environment 'chess_v0'"),
    ],
)
def test_bad_input_exits_2_with_a_message(tmp_path, capsys, argv, expected):
    argv = [*argv, "--out", str(tmp_path / "out")] if argv[0] in ("train", "reproduce") else argv
    argv = [str(tmp_path / "out.md") if a == "-" else a for a in argv]
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert err.startswith("empathy-zoo: error: ") and expected in err, err
    assert "Traceback" not in err
    assert not (tmp_path / "out").exists(), "a refused run writes nothing (docs/limits.md)"


def test_cuda_unavailable_is_a_clear_error(tmp_path, capsys):
    torch = pytest.importorskip("torch")
    if torch.cuda.is_available():
        pytest.skip("CUDA is available here")
    assert main(["train", "--device", "cuda", "--out", str(tmp_path)]) == 2
    assert "CUDA is not available" in capsys.readouterr().err


@pytest.mark.parametrize(
    ("argv", "said"),
    [
        (
            ["train", "--seed", "1", "--seeds", "2"],
            "empathy-zoo train: error: argument --seeds: not allowed with argument --seed",
        ),
        (
            ["train", "--no-such-option", "1"],
            "empathy-zoo: error: unrecognized arguments: --no-such-option 1 (the settings of method",
        ),
        (["train", "--steps", "many"], "empathy-zoo train: error: argument --steps: invalid int value: 'many'"),
        (["train", "--fixed", "cat_0=stay", "--fixed", "cat_0=chase"], "cat_0 is given twice"),
        (["tune", "--objective", "nope"], "empathy-zoo tune: error: argument --objective: invalid choice: 'nope'"),
        ([], "empathy-zoo: error: the following arguments are required: COMMAND (see empathy-zoo --help)"),
    ],
)
def test_a_usage_error_is_one_line_and_exits_2(capsys, argv, said):
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and said in err and "usage:" not in err, err


def test_train_bounds_its_command_line_seeds_before_writing(tmp_path, capsys):
    out = tmp_path / "out"
    assert main(["train", "--out", str(out), "--seeds", *map(str, range(10_001))]) == 2
    assert "--seeds: an experiment has at most 10,000 seeds" in capsys.readouterr().err
    assert main(["train", "--out", str(out), "--seeds", "3", "3"]) == 2
    assert "--seeds" in capsys.readouterr().err
    assert not out.exists()


def test_methods_policies_and_play(capsys):
    assert main(["methods"]) == 0
    listed = capsys.readouterr().out
    assert all(name in listed for name in ("empathic_dqn", "dqn", "dqn_harm_penalty", "dqn_equality"))
    assert main(["policies"]) == 0
    listed = capsys.readouterr().out
    assert "random_walk" in listed and "patrol" in listed and "cat_0 in coexistence_v0" in listed
    assert main(["play", "--env", "sharing_v0", "--episodes", "2", "--seed", "5"]) == 0
    lines = capsys.readouterr().out.splitlines()
    assert lines[0].startswith("episode 0 (seed 5): survival") and "equality" in lines[1]
    assert main(["play", "--episodes", "1", "--render", "ansi", "--fixed", "cat_0=stay"]) == 0
    assert "R" in capsys.readouterr().out


# ---------------------------------------------------------------------------- reproduce and resume
def test_reproduce_tiny_sweep_writes_leaderboard_and_resumes(tmp_path, capsys):
    sweep = tmp_path / "tiny.toml"
    sweep.write_text(TINY_SWEEP)
    out = tmp_path / "results"
    argv = ["reproduce", "--profile", str(sweep), "--out", str(out), "--no-progress", "--workers", "1"]
    assert main(argv) == 0
    files = run_files(out)
    assert len(files) == 2 * 2 * 2
    for name in ("LEADERBOARD.md", "leaderboard.csv", "leaderboard.html"):
        assert (out / name).is_file()
    board = (out / "LEADERBOARD.md").read_text()
    assert f"empathy-zoo reproduce --profile {sweep}" in board
    assert "Empathic DQN (β=0.5)" in board and "DQN" in board
    printed = capsys.readouterr().out
    assert "8 runs" in printed
    # a sweep without the paper's experiments gets no paper verdicts, and says why
    assert not (out / "REPRODUCTION.md").exists()
    assert "no REPRODUCTION.md" in printed and "missing" in printed
    assert main(["reproduction", str(out)]) == 2
    assert "do not contain the paper's experiments" in capsys.readouterr().err

    removed = files[3]
    removed.unlink()
    before = {p: p.stat().st_mtime_ns for p in files if p != removed}
    assert main(argv) == 0
    after = run_files(out)
    assert after == files  # the removed run is back, nothing else is new
    assert {p: p.stat().st_mtime_ns for p in after if p != removed} == before
    assert "7 already finished" in capsys.readouterr().out


class Killed(Exception):
    """Stands in for the process being killed right after a checkpoint."""


def test_killed_run_resumes_from_its_checkpoint_and_matches_an_uninterrupted_run(tmp_path, monkeypatch, capsys):
    args = ["--seeds", "0", "1", "--checkpoint-interval", "100", "--selfishness", "0.5"]
    reference = tmp_path / "reference"
    assert train(reference, *args) == 0

    real_save = ensemble.save_checkpoint
    saved_steps = []

    def save_then_die(path, payload):
        real_save(path, payload)
        saved_steps.append(payload["step"])
        if payload["step"] == 200:
            raise Killed

    out = tmp_path / "killed"
    monkeypatch.setattr(ensemble, "save_checkpoint", save_then_die)
    with pytest.raises(Killed):
        train(out, *args)
    assert saved_steps == [100, 200]
    assert run_files(out) == []
    [checkpoint] = (out / CHECKPOINT_DIR).glob("*.pt")

    monkeypatch.setattr(ensemble, "save_checkpoint", real_save)
    real_load = ensemble.load_checkpoint
    loaded = []
    monkeypatch.setattr(ensemble, "load_checkpoint", lambda path: loaded.append(path) or real_load(path))
    assert train(out, *args) == 0
    assert loaded == [checkpoint] and not checkpoint.exists()
    resumed, uninterrupted = run_files(out), run_files(reference)
    assert [p.name for p in resumed] == [p.name for p in uninterrupted]
    for mine, theirs in zip(resumed, uninterrupted, strict=True):
        a, b = json.loads(mine.read_text()), json.loads(theirs.read_text())
        assert a["train"] == b["train"] and a["eval"] == b["eval"]


def test_corrupted_checkpoint_is_a_clear_error_and_left_alone(tmp_path, monkeypatch, capsys):
    args = ["--checkpoint-interval", "100"]
    real_save = ensemble.save_checkpoint

    def save_then_die(path, payload):
        real_save(path, payload)
        raise Killed

    out = tmp_path / "out"
    monkeypatch.setattr(ensemble, "save_checkpoint", save_then_die)
    with pytest.raises(Killed):
        train(out, *args)
    monkeypatch.setattr(ensemble, "save_checkpoint", real_save)
    [checkpoint] = (out / CHECKPOINT_DIR).glob("*.pt")
    checkpoint.write_bytes(b"not a checkpoint")
    assert train(out, *args) == 2
    err = capsys.readouterr().err
    assert err.startswith("empathy-zoo: error: ") and str(checkpoint) in err and "corrupted" in err
    assert checkpoint.read_bytes() == b"not a checkpoint"
    assert run_files(out) == []


def test_corrupted_result_file_is_a_clear_error_and_left_alone(tmp_path, capsys):
    out = tmp_path / "out"
    assert train(out) == 0
    [path] = run_files(out)
    path.write_text("{ truncated")
    assert train(out) == 2
    err = capsys.readouterr().err
    assert err.startswith("empathy-zoo: error: ") and str(path) in err and "corrupted" in err
    assert path.read_text() == "{ truncated"
    assert main(["leaderboard", str(out)]) == 2
    assert str(path) in capsys.readouterr().err


def test_train_takes_sharings_fidelity_options(tmp_path, capsys):
    out = tmp_path / "runs"
    argv = [
        "train",
        "--env",
        "sharing_v0",
        "--start",
        "centre",
        "--inventory-encoding",
        "authors",
        "--selfishness",
        "0.5",
        "--out",
        str(out),
        *TINY,
    ]
    assert main(argv) == 0
    (result,) = [json.loads(p.read_text()) for p in (out / "runs").glob("*.json")]
    assert result["config"]["env_kwargs"] == {"max_cycles": 50, "start": "centre", "inventory_encoding": "authors"}
    capsys.readouterr()
    assert main(["train", "--env", "coexistence_v0", "--start", "centre", "--out", str(tmp_path / "x"), *TINY]) == 2
    assert "start" in capsys.readouterr().err
    assert main(["train", "--env", "sharing_v0", "--start", "middle", "--out", str(tmp_path / "y"), *TINY]) == 2
    assert "'middle'" in capsys.readouterr().err


def test_train_takes_several_others_and_their_aggregation(tmp_path, capsys):
    out = tmp_path / "runs"
    argv = [
        "train",
        "--env",
        "sharing_v0",
        "--num-humans",
        "2",
        "--others",
        "min",
        "--selfishness",
        "0.5",
        "--out",
        str(out),
        *TINY,
    ]
    assert main(argv) == 0
    (result,) = [json.loads(p.read_text()) for p in (out / "runs").glob("*.json")]
    assert result["config"]["env_kwargs"]["num_humans"] == 2 and result["config"]["settings"]["others"] == "min"
    assert set(result["config"]["fixed"]) == {"human_0", "human_1"}
    capsys.readouterr()
    assert main(["train", "--env", "sharing_v0", "--num-cats", "2", "--out", str(tmp_path / "x"), *TINY]) == 2
    assert "num_cats" in capsys.readouterr().err


@pytest.mark.parametrize("command, report", [("reproduction", "REPRODUCTION.md"), ("sensitivity", "SENSITIVITY.md")])
def test_a_report_given_an_existing_directory_as_out_is_written_into_it(tmp_path, capsys, command, report):
    results = DOCS / "results" / ("paper" if command == "reproduction" else "sharing_sensitivity")
    assert main([command, str(results), "--out", str(tmp_path)]) == 0
    assert capsys.readouterr().out.strip() == f"empathy-zoo: wrote {tmp_path / report}"
    assert (tmp_path / report).read_text().startswith("#")
    assert [p.name for p in tmp_path.iterdir()] == [report]


def test_a_fifo_given_as_a_sweep_file_is_refused_as_what_it_is(tmp_path, capsys):
    import os

    fifo = tmp_path / "sweep.toml"
    os.mkfifo(fifo)
    assert main(["reproduce", "--profile", str(fifo), "--out", str(tmp_path / "out")]) == 2
    assert f"sweep file {fifo} is a FIFO (named pipe), not a regular file" in capsys.readouterr().err
    assert not (tmp_path / "out").exists()
