"""``empathy-zoo evaluate`` end to end on tiny trained runs: one checked evaluation file per run
and scenario set, reproducible to the byte; a killed evaluation resumes, skipping the file it
wrote and giving the same files; a changed agent file is refused naming both files; a loaded agent
replays its run's last greedy evaluation exactly; the leaderboard's section renders from real files."""

from __future__ import annotations

import argparse
import json
import shutil
from pathlib import Path

import pytest
from helpers_heldout import dqn_and_empathic_runs
from helpers_resume import SMALL_SETTINGS

from agents.empathic_dqn import EmpathicDQN
from agents.settings import EmpathicDQNSettings
from empathy_zoo.agent_file import RESULT_FIELD, load_run_agent, write_agent_file
from empathy_zoo.cli.evaluate import add_evaluate
from empathy_zoo.evaluation_file import TRAINED_WITH, evaluation_files, read_evaluation
from empathy_zoo.experiment import RunSpec
from empathy_zoo.policies import parse_entry_label
from empathy_zoo.randomness import STREAMS
from empathy_zoo.scenarios import load_scenario_set
from empathy_zoo.training import RunnerOptions, train_runs
from empathy_zoo.training.evaluation import STREAM_EVAL, evaluate_greedy
from empathy_zoo.training.heldout import GreedyAgent, evaluate_results

EPISODES = 3
MAX_CYCLES = 40


def specs() -> list[RunSpec]:
    """DQN and Empathic DQN (β = 0.5), two seeds each, 600 steps of 40-step episodes."""
    return dqn_and_empathic_runs((0, 1), MAX_CYCLES, 3)


@pytest.fixture(scope="module")
def trained(tmp_path_factory) -> tuple[Path, bool]:
    """A results directory of four tiny runs with the agent files the trainer kept, and whether
    every result file names its agent."""
    out = tmp_path_factory.mktemp("results")
    paths = train_runs(specs(), out, RunnerOptions(progress=False, checkpoint_interval=0, workers=1))
    return out, all(json.loads(p.read_text()).get(RESULT_FIELD) for p in paths)


@pytest.fixture(scope="module")
def evaluated(trained, tmp_path_factory) -> Path:
    """An uninterrupted evaluation of :func:`trained` (the command line, into its own folder)."""
    results, _ = trained
    out = tmp_path_factory.mktemp("evaluated")
    assert run_command(["evaluate", str(results), "--episodes", str(EPISODES), "--no-progress", "--out", str(out)]) == 0
    return out


def run_command(argv: list[str]) -> int:
    parser = argparse.ArgumentParser()
    add_evaluate(parser.add_subparsers(dest="command"))
    args = parser.parse_args(argv)
    return args.handler(args, "empathy-zoo " + " ".join(argv))


def contents(out: Path) -> dict[str, bytes]:
    return {p.relative_to(out).as_posix(): p.read_bytes() for p in evaluation_files(out)}


def test_one_checked_file_per_run_in_the_shipped_set(trained, evaluated) -> None:
    results, _ = trained
    files = evaluation_files(evaluated)
    assert [p.parent.name for p in files] == ["coexistence_v0"] * 4
    names = [TRAINED_WITH, *(s.name for s in load_scenario_set("coexistence_v0").scenarios)]
    for path in files:
        evaluation = read_evaluation(path).to_document()  # (as the file holds it, field for field)
        result = json.loads((results / "runs" / path.name).read_text())
        assert evaluation["agent"] == result[RESULT_FIELD] and evaluation["run_id"] == result["run_id"]
        assert evaluation["stream"] == STREAMS["heldout_eval"] and evaluation["episodes"] == EPISODES
        scenarios = {entry["name"]: entry for entry in evaluation["scenarios"]}
        assert list(scenarios) == names
        assert all(len(entry["metrics"]["harms"]) == EPISODES for entry in scenarios.values())
        assert scenarios[TRAINED_WITH]["env_kwargs"] == {"max_cycles": MAX_CYCLES} and not scenarios[TRAINED_WITH]["held_out"]
        assert scenarios["larger_grid"]["env_kwargs"] == {"max_cycles": MAX_CYCLES, "size": 11}  # the run's world, larger
        assert scenarios["three_random_cats"]["fixed"] == {f"cat_{i}": "random_walk" for i in range(3)}
        assert all(entry["held_out"] for name, entry in scenarios.items() if name != TRAINED_WITH)


def test_evaluating_again_writes_the_same_bytes(trained, evaluated, tmp_path) -> None:
    results, _ = trained
    evaluate_results(results, episodes=EPISODES, out_dir=tmp_path, progress=False)
    assert contents(tmp_path) == contents(evaluated)


def test_threads_change_nothing_evaluated_and_are_put_back(trained, evaluated, tmp_path, monkeypatch) -> None:
    """The command line plays on one torch thread by default (several are many times slower on a
    busy machine); two give the same bytes; the caller's thread count is put back; more threads
    than CPUs are refused before anything is played."""
    import torch

    import empathy_zoo.training.heldout as heldout

    results, _ = trained
    seen: list[int] = []
    real = heldout.evaluate_run

    def recording(*args, **kwargs):
        seen.append(torch.get_num_threads())
        return real(*args, **kwargs)

    before = torch.get_num_threads()
    monkeypatch.setattr(heldout, "evaluate_run", recording)
    monkeypatch.setattr(heldout, "cpu_count", lambda: 2)
    evaluate_results(results, episodes=EPISODES, out_dir=tmp_path / "two", progress=False, threads=2)
    assert contents(tmp_path / "two") == contents(evaluated)
    assert seen and set(seen) == {2} and torch.get_num_threads() == before
    one = ["evaluate", str(results), "--episodes", str(EPISODES), "--no-progress", "--out", str(tmp_path / "one")]
    assert run_command(one) == 0
    assert seen[-1] == 1 and torch.get_num_threads() == before
    with pytest.raises(ValueError, match=r"threads must be at most 2 \(the CPUs of this machine\)"):
        evaluate_results(results, episodes=EPISODES, out_dir=tmp_path / "three", progress=False, threads=3)
    assert not (tmp_path / "three").exists()


def test_a_killed_evaluation_resumes_skipping_what_it_wrote(trained, evaluated, tmp_path) -> None:
    results, _ = trained

    def killed(path: Path) -> None:
        raise KeyboardInterrupt(f"killed after {path.name}")

    with pytest.raises(KeyboardInterrupt):
        evaluate_results(results, episodes=EPISODES, out_dir=tmp_path, progress=False, on_written=killed)
    (first,) = evaluation_files(tmp_path)
    stamp = first.stat().st_mtime_ns
    summary = evaluate_results(results, episodes=EPISODES, out_dir=tmp_path, progress=False)
    assert summary.done == [first] and len(summary.written) == 3 and first not in summary.written
    assert first.stat().st_mtime_ns == stamp
    assert contents(tmp_path) == contents(evaluated)
    again = evaluate_results(results, episodes=EPISODES, out_dir=tmp_path, progress=False)
    assert again.written == [] and len(again.done) == 4


def test_a_file_made_otherwise_is_refused_by_name(trained, evaluated) -> None:
    results, _ = trained
    with pytest.raises(ValueError, match=r"evaluation file .*\.json was made with the episodes per scenario 3, asked for 4"):
        evaluate_results(results, episodes=4, out_dir=evaluated, progress=False)


def test_a_changed_agent_file_is_refused_naming_both_files(trained, tmp_path) -> None:
    results, _ = trained
    copy = tmp_path / "results"
    shutil.copytree(results / "runs", copy / "runs")
    result_file = sorted((copy / "runs").glob("*.json"))[0]
    agent = copy / "runs" / json.loads(result_file.read_text())[RESULT_FIELD]["file"]
    data = bytearray(agent.read_bytes())
    data[-20] ^= 0xFF
    agent.write_bytes(bytes(data))
    with pytest.raises(ValueError, match=rf"agent file {agent} has SHA-256 .* its result file {result_file} records"):
        evaluate_results(copy, episodes=EPISODES, progress=False)
    assert evaluation_files(copy) == []


def test_runs_that_kept_no_agent_cannot_be_evaluated(trained, tmp_path) -> None:
    results, _ = trained
    for path in sorted((results / "runs").glob("*.json")):
        result = json.loads(path.read_text())
        result[RESULT_FIELD] = None
        (tmp_path / "runs").mkdir(exist_ok=True)
        (tmp_path / "runs" / path.name).write_text(json.dumps(result))
    with pytest.raises(ValueError, match=r"no run in .* kept a trained agent"):
        evaluate_results(tmp_path, progress=False)


def test_a_users_scenario_file_and_a_set_of_another_environment(trained, tmp_path) -> None:
    results, _ = trained
    mine = tmp_path / "still_cats.toml"
    mine.write_text(
        '[scenario_set]\nenv = "coexistence_v0"\n[scenarios.still]\nreason = "A cat that stays."\nfixed = { cat_0 = "stay" }\n'
    )
    summary = evaluate_results(results, [mine], episodes=2, out_dir=tmp_path / "out", progress=False)
    assert [p.parent.name for p in summary.written] == ["still_cats"] * 4
    assert [e.name for e in read_evaluation(summary.written[0]).scenarios] == [TRAINED_WITH, "still"]
    with pytest.raises(ValueError, match="no scenario set is for the environments of the kept agents"):
        evaluate_results(results, ["sharing_v0"], episodes=2, out_dir=tmp_path / "out", progress=False)


def test_a_loaded_agent_replays_its_runs_last_greedy_evaluation(trained) -> None:
    results, kept_by_trainer = trained
    assert kept_by_trainer, "every finished run keeps its agent beside its result file"
    for result_file in sorted((results / "runs").glob("*.json")):
        result = json.loads(result_file.read_text())
        config = result["config"]
        fixed = {agent: parse_entry_label(label) for agent, label in config["fixed"].items()}
        agent = GreedyAgent(load_run_agent(result_file))
        (replayed,) = evaluate_greedy(
            agent, result["env"], [result["seed"]], config["eval_episodes"], fixed, config["env_kwargs"], STREAM_EVAL
        )
        last = result["eval"][-1]
        assert {name: replayed[name] for name in replayed} == {name: last[name] for name in replayed}, result_file.name


def test_the_leaderboard_section_renders_from_real_files(trained, evaluated, tmp_path) -> None:
    from leaderboard.aggregate import load_results
    from leaderboard.heldout import heldout_section
    from leaderboard.page_markdown import section_markdown

    results, _ = trained
    shutil.copytree(results / "runs", tmp_path / "runs")
    shutil.copytree(evaluated / "evaluations", tmp_path / "evaluations")
    found = heldout_section(tmp_path, load_results(tmp_path), tmp_path)
    assert found is not None
    markdown, figures = section_markdown(found.section), found.figures
    assert "## Held-out partners" in markdown and "### coexistence_v0: scenario set coexistence_v0" in markdown
    assert "| Empathic DQN (β=0.5) | 2 |" in markdown and "Reading rule" in markdown
    assert [p.name for p in figures.values()] == ["coexistence_v0_heldout_coexistence_v0.png"]


def test_the_command_is_registered() -> None:
    from empathy_zoo.cli import build_parser

    parser = build_parser()
    choices = next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction)).choices
    assert choices["evaluate"].get_default("handler").__name__ == "cmd_evaluate"


def test_a_loaded_agent_evaluates_as_its_learner_did(tmp_path) -> None:
    """What the replay above checks through the trainer, here without it: two runs trained in one
    ensemble and each run's agent file, read back, give the same greedy episodes, metric by metric."""
    from empathy_zoo.agent_file import load_agent
    from empathy_zoo.training.ensemble import learner_batch
    from empathy_zoo.vector import VectorEnv

    seeds, fixed, kwargs = [3, 8], {"cat_0": "random_walk"}, {"max_cycles": MAX_CYCLES}
    venv = VectorEnv("coexistence_v0", len(seeds), fixed=fixed, **kwargs)
    learner = EmpathicDQN([EmpathicDQNSettings(selfishness=b, **SMALL_SETTINGS) for b in (0.5, 1.0)], seeds, 25, 5)
    obs = venv.reset(seed=seeds)[:, 0]
    for _ in range(400):
        actions = learner.act(obs[:, None, :])
        step = venv.step(actions.reshape(len(seeds), 1))
        learner.observe(learner_batch(obs, actions, step))
        obs = step.observations[:, 0]
    assert learner.grad_steps > 0
    together = evaluate_greedy(learner, "coexistence_v0", seeds, 6, fixed, kwargs)
    for run, seed in enumerate(seeds):
        header = {"method": "empathic_dqn", "settings": {}, "env": "coexistence_v0", "env_kwargs": kwargs}
        name, sha = write_agent_file(learner, run, tmp_path / f"r{run}.agent.pt", header)
        agent = GreedyAgent(load_agent(tmp_path / name, sha))
        assert evaluate_greedy(agent, "coexistence_v0", [seed], 6, fixed, kwargs) == [together[run]]
