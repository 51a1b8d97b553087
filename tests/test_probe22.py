"""The twenty-second probe's findings: ``tune`` replaces only files a study wrote, never the
sweep file it reads nor a user's file named like one of its outputs."""

from __future__ import annotations

from pathlib import Path

import pytest

pytest.importorskip("optuna")

from helpers_sweeps import TUNE_SWEEP
from helpers_tune import run_tune, snapshot


def test_tune_never_replaces_the_sweep_file_it_reads(tmp_path: Path, capsys) -> None:
    out = tmp_path / "study"
    out.mkdir()
    sweep = out / "tuned.toml"
    sweep.write_text(TUNE_SWEEP, encoding="utf-8")
    before = snapshot(out)
    capsys.readouterr()
    assert run_tune(sweep, out, 1) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "is the sweep file" in err, err
    assert snapshot(out) == before


@pytest.mark.parametrize(
    ("name", "content"),
    [
        ("tuned.toml", "# my notes\nx = 1\n"),
        ("study.json", '{"my": "notes"}'),
        ("trials.png", "not a png"),
        ("study.journal", "notes"),
    ],
)
def test_tune_never_replaces_a_users_file_named_like_its_outputs(tmp_path: Path, capsys, name: str, content: str) -> None:
    sweep = tmp_path / "tiny.toml"
    sweep.write_text(TUNE_SWEEP, encoding="utf-8")
    out = tmp_path / "study"
    out.mkdir()
    (out / name).write_text(content, encoding="utf-8")
    before = snapshot(out)
    capsys.readouterr()
    assert run_tune(sweep, out, 1) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and f"{out / name} exists and is no" in err, err
    assert snapshot(out) == before


ROOT = Path(__file__).resolve().parents[1]
QUICK_RUNS = ROOT / "docs" / "results" / "quick" / "runs"


@pytest.mark.parametrize("dropped", [("fixed",), ("run_id",), ("fixed", "run_id"), ("label", "steps")])
def test_watch_refuses_a_re_signed_header_that_drops_a_field_of_its_run(tmp_path: Path, capsys, dropped: tuple) -> None:
    import hashlib
    import json
    import shutil

    import torch

    from empathy_zoo.cli import main

    agent = sorted(QUICK_RUNS.glob("coexistence_v0__empathic_dqn-*__s0.agent.pt"))[0]
    result = agent.with_name(agent.name.removesuffix(".agent.pt") + ".json")
    runs = tmp_path / "runs"
    runs.mkdir()
    shutil.copy(result, runs / result.name)
    document = torch.load(agent, weights_only=True)
    for key in dropped:
        del document["header"][key]
    torch.save(document, runs / agent.name)
    recorded = json.loads((runs / result.name).read_text(encoding="utf-8"))
    recorded["agent"]["sha256"] = hashlib.sha256((runs / agent.name).read_bytes()).hexdigest()
    (runs / result.name).write_text(json.dumps(recorded), encoding="utf-8")
    capsys.readouterr()
    assert main(["watch", result.stem, "--dir", str(tmp_path), "--episodes", "1"]) == 2
    captured = capsys.readouterr()
    assert captured.err.count("\n") == 1 and "its header has no field" in captured.err, captured.err
    assert "survival" not in captured.out


def test_a_row_is_compared_only_with_a_dqn_of_its_own_world(tmp_path: Path) -> None:
    import json

    from empathy_zoo.run_ids import run_id
    from leaderboard.aggregate import load_results
    from leaderboard.improvement import improvements_over_dqn, uncompared_rows

    runs = tmp_path / "runs"
    runs.mkdir()
    for source in sorted(QUICK_RUNS.glob("coexistence_v0__empathic_dqn-*.json")):
        document = json.loads(source.read_text(encoding="utf-8"))
        beta = document["config"]["description"]["selfishness"]
        if beta not in (0.5, 1.0):
            continue
        document["agent"] = None
        if beta == 1.0:  # (the DQN reference, trained beside a cat that stays)
            document["config"]["fixed"] = {"cat_0": "stay"}
            document["run_id"] = run_id(document["variant"], document["method"], document["config"], document["seed"])
        (runs / f"{document['run_id']}.json").write_text(json.dumps(document), encoding="utf-8")
    results = load_results(tmp_path)
    assert len(results) == 6
    assert improvements_over_dqn(results, {"coexistence_v0": ["harms"]}) == []
    assert [label for _, label in uncompared_rows(results)] == ["Empathic DQN (β=0.5)"]


def _vase_dqn(tmp_path: Path, change=None, label: str | None = None, seeds: range = range(3)) -> None:
    """The shipped vase_v0 DQN runs of ``seeds`` (without agents) into ``tmp_path/runs``; with
    ``change`` and ``label``, as another experiment of seeds 10 on."""
    import json

    from empathy_zoo.run_ids import run_id

    runs = tmp_path / "runs"
    runs.mkdir(exist_ok=True)
    shipped = ROOT / "docs" / "results" / "scenarios" / "runs"
    for seed in seeds:
        document = json.loads(next(shipped.glob(f"vase_v0__dqn-*__s{seed}.json")).read_text(encoding="utf-8"))
        document["agent"] = None
        if change is not None:
            change(document["config"])
            document["config"]["label"] = document["method_label"] = label
            document["seed"] = document["config"]["seed"] = seed + 10
            document["run_id"] = run_id(document["variant"], document["method"], document["config"], document["seed"])
        (runs / f"{document['run_id']}.json").write_text(json.dumps(document), encoding="utf-8")


def test_separation_reading_never_pools_two_experiments_of_one_method(tmp_path: Path) -> None:
    from leaderboard.aggregate import load_results
    from leaderboard.separation_reading import final_harms

    _vase_dqn(tmp_path)
    assert len(final_harms(load_results(tmp_path), {})[("vase_v0", "dqn")]) == 3
    _vase_dqn(tmp_path, lambda config: config["settings"].update(learning_rate=0.0005), "DQN, another rate")
    with pytest.raises(ValueError, match="are both dqn on vase_v0 but of two experiments"):
        final_harms(load_results(tmp_path), {})


def test_separation_reading_reads_only_the_world_its_tables_model(tmp_path: Path) -> None:
    from leaderboard.aggregate import load_results
    from leaderboard.separation_reading import final_harms

    _vase_dqn(tmp_path)
    _vase_dqn(tmp_path, lambda config: config["fixed"].update(cat_0="stay"), "DQN beside a still cat")
    assert len(load_results(tmp_path)) == 6
    assert len(final_harms(load_results(tmp_path), {})[("vase_v0", "dqn")]) == 3


def _tuned_copies(tmp_path: Path, change) -> tuple[Path, Path]:
    """The quick profile's Coexistence DQN-reference and β = 0.5 runs as an untuned directory, and
    as a tuned one: each run changed by ``change`` (its config), labelled ``…, tuned``."""
    import json

    from empathy_zoo.run_ids import run_id

    untuned, tuned = tmp_path / "untuned" / "runs", tmp_path / "tuned" / "runs"
    untuned.mkdir(parents=True)
    tuned.mkdir(parents=True)
    for source in sorted(QUICK_RUNS.glob("coexistence_v0__empathic_dqn-*.json")):
        document = json.loads(source.read_text(encoding="utf-8"))
        if document["config"]["description"]["selfishness"] not in (0.5, 1.0):
            continue
        document["agent"] = None
        (untuned / source.name).write_text(json.dumps(document), encoding="utf-8")
        change(document["config"])
        document["config"]["label"] = document["method_label"] = document["method_label"] + ", tuned"
        document["run_id"] = run_id(document["variant"], document["method"], document["config"], document["seed"])
        (tuned / f"{document['run_id']}.json").write_text(json.dumps(document), encoding="utf-8")
    return untuned.parent, tuned.parent


def test_tuning_effect_pairs_rows_that_differ_in_settings_only(tmp_path: Path) -> None:
    from leaderboard.aggregate import load_results
    from leaderboard.tuning_effect import tuning_effect

    untuned, tuned = _tuned_copies(tmp_path / "a", lambda config: config["settings"].update(learning_rate=0.0005))
    assert tuning_effect(load_results(untuned), load_results(tuned)).pairs
    untuned, tuned = _tuned_copies(tmp_path / "b", lambda config: config["fixed"].update(cat_0="stay"))
    with pytest.raises(ValueError, match="differ in their world and budget"):
        tuning_effect(load_results(untuned), load_results(tuned))
