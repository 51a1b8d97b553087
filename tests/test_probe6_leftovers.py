"""The sixth probe's leftovers (issue 33, "files from elsewhere are inert"): a run of γ = 1 costs the
leaderboard its reference curve, not the page; the reference curves of a page share one bound on
their work; an evaluation file already in place is checked against its run before it is skipped;
an agent's method is checked wherever an agent is played; one leaderboard at a time writes into a
directory."""

from __future__ import annotations

import json
import shutil
from pathlib import Path

import numpy as np
import pytest
from helpers_results import derive_run_id, record, synthetic_schema_1

from empathy_zoo.experiment.records import RunResult
from empathy_zoo.limits import MAX_REFERENCE_CYCLES, MAX_REFERENCE_SIZE, MAX_REFERENCE_WORK
from leaderboard import write_leaderboard
from leaderboard.reference_curves import reference_curve, reference_refusal, reference_refusals

RESULTS = Path(__file__).resolve().parents[1] / "docs" / "results" / "quick"
RUN = RESULTS / "runs" / "coexistence_v0__dqn_harm_penalty-684a7c7f__s0.json"
AGENT = RUN.with_name(RUN.stem + ".agent.pt")
EVALUATION = RESULTS / "evaluations" / "coexistence_v0" / RUN.name


def _document(seed: int, gamma: float = 0.99, beta: float = 0.5, **env_kwargs: int) -> dict:
    document = synthetic_schema_1("coexistence_v0", "empathic_dqn", beta, seed, harms=0.1, survival=400)
    document["config"]["settings"]["gamma"] = gamma
    document["config"]["env_kwargs"] = env_kwargs
    return derive_run_id(document)


def _never(*args: object, **kwargs: object) -> None:
    raise AssertionError("the reference was computed")


# ---------------------------------------------------------------------------- γ = 1 (#2)
def test_a_run_of_gamma_one_gets_no_reference_curve_and_says_why(monkeypatch) -> None:
    import empathy_zoo.reference as reference

    monkeypatch.setattr(reference, "coexistence_optimum", _never)
    runs = [record(_document(seed, gamma=1.0)) for seed in range(2)]
    why = reference_refusal(runs)
    assert why is not None and "γ 1.0" in why and "[0, 1)" in why and "\n" not in why
    assert reference_curve(runs, "harms", np.array([100.0])) is None


def test_the_leaderboard_of_a_gamma_one_run_is_written_with_a_note(tmp_path: Path) -> None:
    (tmp_path / "runs").mkdir()
    for seed in range(2):
        document = _document(seed, gamma=1.0)
        (tmp_path / "runs" / f"{record(document).run_id}.json").write_text(json.dumps(document))
    notes: list[str] = []
    written = write_leaderboard(tmp_path, tmp_path / "out", on_note=notes.append)
    assert written["markdown"].is_file()
    assert len(notes) == 1 and "γ 1.0" in notes[0] and "no reference curve" in notes[0]


# ---------------------------------------------------------------------------- one bound per page (#4)
def _groups(count: int, **env_kwargs: int) -> dict[tuple[str, str], list[RunResult]]:
    """``count`` groups of two runs each (β = 0.1, 0.2, …: one label each) at ``env_kwargs``."""
    groups = {}
    for i in range(count):
        runs = [record(_document(seed, beta=round(0.1 * (i + 1), 1), **env_kwargs)) for seed in range(2)]
        groups[(runs[0].env, runs[0].method_label)] = runs
    return groups


def test_the_pages_reference_curves_share_one_bound_on_their_work() -> None:
    largest = {"size": MAX_REFERENCE_SIZE, "max_cycles": MAX_REFERENCE_CYCLES}
    one = 50 * MAX_REFERENCE_CYCLES * (MAX_REFERENCE_SIZE**2 + 2) ** 2
    assert one <= MAX_REFERENCE_WORK < 2 * one  # (the bound admits one group at both bounds, not two)
    groups = _groups(3, **largest)
    refused = reference_refusals(groups, 50)
    keys = list(groups)
    assert keys[0] not in refused and set(refused) == set(keys[1:])
    assert all("MAX_REFERENCE_WORK" in why and "\n" not in why for why in refused.values())
    assert reference_refusals(_groups(3), 50) == {}  # (the paper's size: far below it)


def test_the_leaderboard_computes_no_reference_past_the_pages_bound(tmp_path: Path, monkeypatch) -> None:
    import empathy_zoo.reference as reference

    computed: list[tuple[object, ...]] = []
    real = reference.coexistence_optimum

    def counting(*args: object, **kwargs: object) -> object:
        computed.append((args, tuple(sorted(kwargs.items()))))
        return real(*args, **{**kwargs, "max_cycles": 20, "size": 7})  # (a stand-in, fast)

    monkeypatch.setattr(reference, "coexistence_optimum", counting)
    (tmp_path / "runs").mkdir()
    for beta in (0.1, 0.2, 0.3):
        for seed in range(2):
            document = _document(seed, beta=beta, size=MAX_REFERENCE_SIZE, max_cycles=MAX_REFERENCE_CYCLES)
            (tmp_path / "runs" / f"{record(document).run_id}.json").write_text(json.dumps(document))
    notes: list[str] = []
    write_leaderboard(tmp_path, tmp_path / "out", on_note=notes.append)
    assert sum("MAX_REFERENCE_WORK" in note for note in notes) == 2
    betas = {args[0] for args, _ in computed}
    assert betas == {0.1}, betas  # (only the first group's curve was computed)


# ---------------------------------------------------------------------------- evaluate's skipped files (#5)
def _planted(tmp_path: Path, change) -> Path:
    """A copy of the shipped quick run, its agent and its evaluation, the evaluation ``change``d."""
    (tmp_path / "runs").mkdir()
    shutil.copy(RUN, tmp_path / "runs" / RUN.name)
    shutil.copy(AGENT, tmp_path / "runs" / AGENT.name)
    folder = tmp_path / "evaluations" / "coexistence_v0"
    folder.mkdir(parents=True)
    document = json.loads(EVALUATION.read_text())
    change(document)
    (folder / RUN.name).write_text(json.dumps(document))
    return folder / RUN.name


def test_evaluate_skips_an_evaluation_of_its_run_as_done(tmp_path: Path) -> None:
    from empathy_zoo.training.heldout import evaluate_results

    planted = _planted(tmp_path, lambda document: None)
    before = planted.read_bytes()
    summary = evaluate_results(tmp_path, ["coexistence_v0"], episodes=100, progress=False)
    assert summary.done == [planted] and not summary.written and planted.read_bytes() == before


@pytest.mark.parametrize(
    "key, value, named",
    [
        ("method", "dqn", "method: 'dqn', its run has 'dqn_harm_penalty'"),
        ("scenarios", "own partner", "scenarios[0].fixed (trained_with): {'cat_0': 'chase'}"),
    ],
)
def test_evaluate_refuses_an_evaluation_in_place_that_is_not_of_its_run(tmp_path: Path, capsys, key, value, named) -> None:
    from empathy_zoo.cli import main

    def change(document: dict) -> None:
        if key == "scenarios":
            document["scenarios"][0]["fixed"] = {"cat_0": "chase"}
        else:
            document[key] = value

    planted = _planted(tmp_path, change)
    before = planted.read_bytes()
    assert main(["evaluate", str(tmp_path), "--scenarios", "coexistence_v0", "--episodes", "100", "--progress", "plain"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "is not of its run's result file" in err and named in err
    assert planted.read_bytes() == before and sorted(p.name for p in planted.parent.iterdir()) == [RUN.name]


# ---------------------------------------------------------------------------- the agent's method (#5)
def test_evaluate_and_the_leaderboard_check_the_agents_method(tmp_path: Path, monkeypatch) -> None:
    """Both call the registry's check on every agent they play (a header whose method the result
    file shares passes the reader below the registry; the check is where an unregistered one stops)."""
    import empathy_zoo.experiment.agent_method as agent_method
    import empathy_zoo.training.heldout as heldout
    import leaderboard.episodes as episodes

    checked: list[object] = []

    def recording(agent: object) -> object:
        checked.append(agent)
        return agent_method.check_agent_method(agent)

    monkeypatch.setattr(heldout, "check_agent_method", recording)
    monkeypatch.setattr(episodes, "check_agent_method", recording)
    (tmp_path / "runs").mkdir()
    shutil.copy(RUN, tmp_path / "runs" / RUN.name)
    shutil.copy(AGENT, tmp_path / "runs" / AGENT.name)
    heldout.run_agent(tmp_path / "runs" / RUN.name, record(json.loads(RUN.read_text()), str(RUN)))
    assert len(checked) == 1
    write_leaderboard(tmp_path, tmp_path / "out")
    assert len(checked) == 2


# ---------------------------------------------------------------------------- one leaderboard at a time (#6)
def test_a_second_leaderboard_into_the_same_directory_is_refused(tmp_path: Path) -> None:
    from empathy_zoo.output_lock import DirectoryInUse, hold_output_dir

    (tmp_path / "runs").mkdir()
    shutil.copy(RUN, tmp_path / "runs" / RUN.name)
    out = tmp_path / "out"
    with hold_output_dir(out / "figures", "another leaderboard"):
        with pytest.raises(DirectoryInUse, match="another leaderboard"):
            write_leaderboard(tmp_path, out)
        assert sorted(p.name for p in out.iterdir()) == ["figures"]
    with hold_output_dir(tmp_path, "training"):  # (training in the directory read does not stop it)
        written = write_leaderboard(tmp_path, out)
    assert written["markdown"].is_file() and not (out / "figures" / ".empathy-zoo.lock").exists()
