"""Files are data: a policy a result or agent file names is never imported or called.

A result file's ``config.fixed`` and an agent file's ``header.fixed`` record the partners a run
trained beside. Read back, they resolve only to registered policies; a ``package.module:Name``
in them is refused (``evaluate``, ``watch``) or not replayed (the leaderboard's greedy episodes)
unless the user names it with ``--allow-import``. The forged value below ran a shell command in
0.5.0; here it must leave no trace. Also: a name a user gives is checked to be a policy class
before it is called; a scenario's reason is one line of printable text; a misspelt reset option
is refused; ``watch --gif`` replaces only a regular file and checks its directory first.
"""

from __future__ import annotations

import hashlib
import json
import os
from pathlib import Path

import numpy as np
import pytest
import torch
from helpers_heldout import dqn_and_empathic_runs
from helpers_results import derive_run_id, record

from empathy_zoo import coexistence_v0
from empathy_zoo.cli import main
from empathy_zoo.cli.watch import check_gif_path
from empathy_zoo.experiment.result_reader import read_result
from empathy_zoo.experiment.values import SweepConfigError
from empathy_zoo.greedy_episode import agent_policies
from empathy_zoo.policies import POLICIES, make_policy, recorded_entry
from empathy_zoo.run_ids import run_id
from empathy_zoo.scenarios import parse_scenario_set
from empathy_zoo.scenarios import trained_with as trained_with_scenario
from empathy_zoo.training import RunnerOptions, train_runs
from leaderboard.episodes import play_row_episodes, trained_world

PWNED = "PWNED"
"""The file the forged policy's shell command would create in the working directory."""
FORGED = f'subprocess:Popen(args="touch {PWNED}", shell=true)'
"""A policy label that, resolved as code, runs ``touch PWNED`` (what 0.5.0 did)."""


@pytest.fixture(scope="module")
def trained(tmp_path_factory) -> Path:
    """A results directory of one tiny DQN run that kept its agent file."""
    out = tmp_path_factory.mktemp("trained")
    train_runs(dqn_and_empathic_runs((0,), 40, 1)[:1], out, RunnerOptions(progress=False, checkpoint_interval=0, workers=1))
    return out


def exit_code(argv: list[str]) -> int:
    """The exit status of ``empathy-zoo ARGV`` (argparse's own refusals exit, the commands' return 2)."""
    try:
        return main(argv)
    except SystemExit as stop:
        return int(stop.code or 0)


def forged_copy(trained: Path, target: Path, label: str = FORGED) -> Path:
    """A copy of ``trained`` whose runs trained beside ``label`` as the cat's policy: each result
    file records it, and so does its agent file's header (one run's: the reader compares them),
    each under the run id its changed config gives (:func:`renamed`), the result file recording
    that agent file's SHA-256."""
    runs = target / "runs"
    runs.mkdir(parents=True)
    for path in (trained / "runs").iterdir():
        if path.is_file() and not path.name.endswith((".json", ".agent.pt")):
            (runs / path.name).write_bytes(path.read_bytes())
    for path in (trained / "runs").glob("*.json"):
        result = json.loads(path.read_text())
        kept = result.get("agent")
        result["config"]["fixed"] = {"cat_0": label}
        renamed(result)
        if kept:
            document = torch.load(trained / "runs" / kept["file"], weights_only=True)
            document["header"]["fixed"] = {"cat_0": label}
            document["header"]["run_id"] = result["run_id"]
            torch.save(document, runs / result["agent"]["file"])
            result["agent"]["sha256"] = hashlib.sha256((runs / result["agent"]["file"]).read_bytes()).hexdigest()
        (runs / f"{result['run_id']}.json").write_text(json.dumps(result))
    return target


def renamed(result: dict) -> dict:
    """``result`` (changed in place) under the run id its config gives, its agent file (if it
    kept one) named after that id."""
    derive_run_id(result)
    if result.get("agent"):
        result["agent"] = {**result["agent"], "file": f"{result['run_id']}.agent.pt"}
    return result


def forged_agent_file(trained: Path, target: Path, label: str = FORGED) -> Path:
    """The trained run's agent file with ``header.fixed`` naming ``label`` (a stand-alone agent file)."""
    source = next((trained / "runs").glob("*.agent.pt"))
    document = torch.load(source, weights_only=True)
    document["header"]["fixed"] = {"cat_0": label}
    header = document["header"]  # (under the run id its changed fields give, as the trainer writes it)
    config = {key: value for key, value in header.items() if key != "run_id"}
    header["run_id"] = run_id(header.get("variant") or header["env"], header["method"], config, header["seed"])
    path = target / "forged.agent.pt"
    torch.save(document, path)
    return path


# ---------------------------------------------------------------------------- the label itself
def test_a_recorded_plugin_name_is_refused_naming_the_field_and_the_option() -> None:
    with pytest.raises(ValueError, match=r"config\.fixed\.cat_0 names fixed policy 'subprocess:Popen'.*--allow-import"):
        recorded_entry(FORGED, "config.fixed.cat_0")
    assert recorded_entry("patrol(period=3)", "x") == {"policy": "patrol", "period": 3}
    assert recorded_entry({"policy": "stay"}, "x") == "stay"
    with pytest.raises(ValueError, match="not registered"):
        recorded_entry({"policy": "os:system", "command": "true"}, "header.fixed.cat_0")


def test_an_allowed_plugin_name_resolves_and_a_refused_one_imports_nothing(monkeypatch) -> None:
    allowed = recorded_entry("helpers_policies:AlwaysLeft", "x", {"helpers_policies:AlwaysLeft"})
    assert allowed == "helpers_policies:AlwaysLeft"
    monkeypatch.delitem(__import__("sys").modules, "helpers_broken_module", raising=False)
    with pytest.raises(ValueError, match="not registered"):
        recorded_entry("helpers_broken_module:Anything", "x", {"helpers_policies:AlwaysLeft"})
    assert "helpers_broken_module" not in __import__("sys").modules


def test_a_name_given_by_the_user_is_checked_to_be_a_policy_class_before_it_is_called(tmp_path, monkeypatch) -> None:
    monkeypatch.chdir(tmp_path)
    for name in ("os:system", "subprocess:Popen", "builtins:print"):
        with pytest.raises(ValueError, match="is not a fixed policy"):
            make_policy({"policy": name, "args": f"touch {PWNED}"} if name != "os:system" else name)
    with pytest.raises(ValueError, match=r"no reset, act|needs reset"):
        make_policy("helpers_policies:NotAPolicy")
    assert not (tmp_path / PWNED).exists()


# ---------------------------------------------------------------------------- evaluate, leaderboard, watch
def test_evaluate_refuses_a_forged_result_file_before_writing_and_runs_nothing(trained, tmp_path, monkeypatch, capsys) -> None:
    forged = forged_copy(trained, tmp_path / "forged")
    monkeypatch.chdir(tmp_path)
    assert exit_code(["evaluate", str(forged), "--no-progress", "--episodes", "1"]) == 2
    error = capsys.readouterr().err
    assert "subprocess:Popen" in error and "--allow-import" in error and "Traceback" not in error
    assert not (tmp_path / PWNED).exists()
    assert not (forged / "evaluations").exists()


def test_the_leaderboard_does_not_replay_a_forged_partner_and_runs_nothing(trained, tmp_path, monkeypatch) -> None:
    forged = forged_copy(trained, tmp_path / "forged")
    monkeypatch.chdir(tmp_path)
    result = read_result(next((forged / "runs").glob("*.json")))  # (a result file names code as data: it is read)
    with pytest.raises(ValueError, match="not registered"):
        trained_world(result)
    episodes, notes = play_row_episodes([result], tmp_path / "board", [str(forged)])
    assert episodes == [] and len(notes) == 1 and "subprocess:Popen" in notes[0] and "no episode shown" in notes[0]
    assert not (tmp_path / "board" / "figures").exists()
    assert not (tmp_path / PWNED).exists()


def test_the_trained_with_scenario_resolves_only_registered_partners(trained, tmp_path) -> None:
    forged = forged_copy(trained, tmp_path / "forged")
    path = next((forged / "runs").glob("*.json"))
    with pytest.raises(ValueError, match=r"its own partners do not make a scenario.*not registered"):
        trained_with_scenario(read_result(path))
    document = json.loads(path.read_text())
    document["config"]["fixed"] = {"cat_0": "helpers_policies:AlwaysLeft"}
    scenario = trained_with_scenario(record(renamed(document), str(path)), {"helpers_policies:AlwaysLeft"})
    assert scenario.variant.fixed_policies()["cat_0"] == "helpers_policies:AlwaysLeft"


def test_watch_refuses_a_forged_agent_file_and_runs_nothing(trained, tmp_path, monkeypatch, capsys) -> None:
    path = forged_agent_file(trained, tmp_path)
    monkeypatch.chdir(tmp_path)
    assert exit_code(["watch", str(path)]) == 2
    error = capsys.readouterr().err
    assert "header.fixed.cat_0" in error and "subprocess:Popen" in error and "Traceback" not in error
    assert not (tmp_path / PWNED).exists()


def test_watch_plays_once_the_user_replaces_the_forged_partner(trained, tmp_path, monkeypatch, capsys) -> None:
    path = forged_agent_file(trained, tmp_path)
    monkeypatch.chdir(tmp_path)
    assert main(["watch", str(path), "--fixed", "cat_0=stay"]) == 0
    assert "cat_0=stay" in capsys.readouterr().out
    assert not (tmp_path / PWNED).exists()


def test_an_agents_replaced_partner_is_not_read_at_all(trained, tmp_path) -> None:
    from empathy_zoo import load_agent

    agent = load_agent(forged_agent_file(trained, tmp_path))
    assert agent_policies(agent, {"cat_0": "stay"})["cat_0"] == "stay"
    with pytest.raises(ValueError, match="not registered"):
        agent_policies(agent)


def test_evaluate_with_allow_import_plays_a_plugin_partner(trained, tmp_path, monkeypatch) -> None:
    plugin = "helpers_policies:AlwaysLeft"
    source = forged_copy(trained, tmp_path / "plugin", plugin)
    assert exit_code(["evaluate", str(source), "--no-progress", "--episodes", "1"]) == 2
    assert main(["evaluate", str(source), "--no-progress", "--episodes", "1", "--allow-import", plugin]) == 0
    written = list((source / "evaluations").rglob("*.json"))
    assert written and json.loads(written[0].read_text())["scenarios"][0]["fixed"] == {"cat_0": plugin}


def test_allow_import_takes_only_a_plugin_name(capsys) -> None:
    assert (
        exit_code(["evaluate", "somewhere", "--allow-import", "os.system"]) == 2
        and "package.module:Name" in capsys.readouterr().err
    )


# ---------------------------------------------------------------------------- watch --gif's path
@pytest.mark.skipif(not Path("/dev/null").exists(), reason="needs /dev/null")
def test_watch_gif_never_replaces_a_device_a_link_or_a_directory(tmp_path) -> None:
    with pytest.raises(ValueError, match="no GIF file name"):
        check_gif_path("/dev/null")
    assert Path("/dev/null").is_char_device()
    os.mkfifo(tmp_path / "pipe.gif")
    with pytest.raises(ValueError, match="not a regular file"):
        check_gif_path(str(tmp_path / "pipe.gif"))
    (tmp_path / "pipe.gif").unlink()
    from empathy_zoo.names import GIF_OPENING, WATCH_GIF_MARK, figure_marker

    (tmp_path / "real.gif").write_bytes(b"GIF89a" + figure_marker(GIF_OPENING, WATCH_GIF_MARK))  # (a GIF watch wrote)
    os.symlink(tmp_path / "real.gif", tmp_path / "link.gif")
    with pytest.raises(ValueError, match="symbolic link"):
        check_gif_path(str(tmp_path / "link.gif"))
    with pytest.raises(ValueError, match="is a directory"):
        check_gif_path(str(tmp_path))
    assert check_gif_path(str(tmp_path / "real.gif")) == tmp_path / "real.gif"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["link.gif", "real.gif"]  # (the probe is gone)


@pytest.mark.skipif(os.geteuid() == 0 if hasattr(os, "geteuid") else True, reason="root writes in a read-only directory")
def test_watch_gif_into_a_read_only_directory_is_refused_before_playing(tmp_path) -> None:
    folder = tmp_path / "ro"
    folder.mkdir()
    folder.chmod(0o500)
    try:
        with pytest.raises(ValueError, match="cannot write in"):
            check_gif_path(str(folder / "x.gif"))
    finally:
        folder.chmod(0o700)


def test_watch_gif_into_an_unwritable_place_is_refused_before_any_episode(trained, tmp_path, capsys) -> None:
    agent = next((trained / "runs").glob("*.agent.pt"))
    blocker = tmp_path / "file"
    blocker.write_text("")
    assert exit_code(["watch", str(agent), "--gif", str(blocker / "x.gif")]) == 2
    captured = capsys.readouterr()
    assert "--gif" in captured.err and "episode 0" not in captured.out and "Traceback" not in captured.err


# ---------------------------------------------------------------------------- small inputs
@pytest.mark.parametrize("reason", ["two\rlines", "an \x1b[31mescape", "a bell \x07", "rtl \u202e", "x" * 501])
def test_a_scenario_reason_is_one_printable_line(reason) -> None:
    data = {
        "scenario_set": {"env": "coexistence_v0", "description": "Hand-made."},
        "scenarios": {"a": {"reason": reason, "fixed": {"cat_0": "stay"}}},
    }
    with pytest.raises(SweepConfigError, match="reason"):
        parse_scenario_set(data, "set.toml", "s")
    data["scenarios"]["a"]["reason"] = "A cat that stays."
    assert parse_scenario_set(data, "set.toml", "s").scenarios[0].reason == "A cat that stays."


def test_a_misspelt_reset_option_is_refused_and_changes_nothing() -> None:
    env = coexistence_v0.parallel_env()
    env.reset(seed=3)
    before = env.engine.state()
    with pytest.raises(ValueError, match="did you mean 'positions'"):
        env.reset(seed=0, options={"position": {"robot_0": (0, 0)}})
    after = env.engine.state()
    assert before.keys() == after.keys()
    assert all(np.array_equal(np.asarray(before[k]), np.asarray(after[k])) for k in before if not isinstance(before[k], dict))


def test_every_registered_policy_is_a_class_a_file_may_name() -> None:
    for name in POLICIES:
        assert recorded_entry(name, "x") == name


def test_the_leaderboard_replays_a_plugin_partner_only_when_allowed(trained, tmp_path, capsys) -> None:
    plugin = "helpers_policies:AlwaysLeft"
    source = forged_copy(trained, tmp_path / "plugin", plugin)
    assert exit_code(["leaderboard", str(source), "--out", str(tmp_path / "refused")]) == 0
    assert not list((tmp_path / "refused").rglob("*_episode.gif"))
    assert "not registered" in (tmp_path / "refused" / "LEADERBOARD.md").read_text()
    assert exit_code(["leaderboard", str(source), "--out", str(tmp_path / "allowed"), "--allow-import", plugin]) == 0
    assert list((tmp_path / "allowed").rglob("*_episode.gif"))


def test_a_name_past_its_bound_is_refused_before_anything_is_imported() -> None:
    from baselines.registry import get_method

    with pytest.raises(ValueError, match=r"at most 500 characters, got 100,002"):
        get_method("a" * 100_000 + ":X")
    with pytest.raises(ValueError, match="at most 500 characters"):
        make_policy("p" * 600 + ":Cat")


def test_a_rising_exploration_schedule_is_refused() -> None:
    from agents.settings import EmpathicDQNSettings

    with pytest.raises(ValueError, match=r"epsilon_end must be in \[0, epsilon_start = 0.01\].*never rises"):
        EmpathicDQNSettings(epsilon_start=0.01, epsilon_end=1.0)
    assert EmpathicDQNSettings(epsilon_start=0.5, epsilon_end=0.5).epsilon_end == 0.5  # (a constant ε is allowed)
