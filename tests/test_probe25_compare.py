"""``compare-runs`` and ``equivalence`` match runs by a key that leaves most settings out (so a
version that adds or drops a setting still matches its runs); two experiments that the key takes
for one (another learning rate, γ, budget) are refused, in one directory or across two, never
matched or pooled (before: exit 0, tested cell by cell as one experiment)."""

from __future__ import annotations

import json
import re
from pathlib import Path

import pytest
from helpers_results import record, synthetic_document

from empathy_zoo.cli import main
from empathy_zoo.run_ids import run_id
from leaderboard.compare_runs import compare_runs, setting_differences
from leaderboard.equivalence import equivalence


def _run(seed: int, learning_rate: float = 0.001, steps: int | None = None) -> dict:
    document = synthetic_document("coexistence_v0", "dqn", 1.0, seed)
    config = document["config"]
    config["settings"]["learning_rate"] = learning_rate
    if steps is not None:
        config["steps"] = document["steps"] = steps
    document["run_id"] = run_id(document.get("variant") or document["env"], document["method"], config, seed)
    return document


def test_a_pair_of_two_learning_rates_is_refused_naming_it() -> None:
    old = [record(_run(seed)) for seed in range(3)]
    new = [record(_run(seed, 0.01)) for seed in range(3)]
    assert setting_differences(old[0], new[0]) == ["learning_rate: 0.001 against 0.01"]
    assert compare_runs(old, old)["same"]  # (one experiment against itself still matches)
    with pytest.raises(ValueError, match=re.escape("differ in learning_rate: 0.001 against 0.01")):
        compare_runs(old, new)
    with pytest.raises(ValueError, match="differ in learning_rate"):
        equivalence(old, new)


def test_two_experiments_of_one_key_in_one_directory_are_refused() -> None:
    mixed = [record(_run(0)), record(_run(1, 0.01))]  # (other seeds: no seed twice, yet two experiments)
    with pytest.raises(ValueError, match="are two experiments"):
        compare_runs(mixed, mixed)
    with pytest.raises(ValueError, match="are two experiments"):
        equivalence(mixed, mixed)


def test_the_command_refuses_two_budgets_in_one_line(tmp_path: Path, capsys) -> None:
    for name, steps in (("a", None), ("b", 2 * _run(0)["steps"])):
        (tmp_path / name / "runs").mkdir(parents=True)
        for seed in range(2):
            document = _run(seed, steps=steps)
            (tmp_path / name / "runs" / f"{document['run_id']}.json").write_text(json.dumps(document))
    assert main(["analyse", "compare-runs", str(tmp_path / "a"), str(tmp_path / "b")]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "differ in steps" in err


def test_a_sweep_label_that_reads_as_dqn_is_refused_before_anything_trains(tmp_path: Path, capsys) -> None:
    sweep = tmp_path / "sweep.toml"
    sweep.write_text(
        '[sweep]\nname = "s"\nseeds = 1\nsteps = 400\neval_interval = 200\neval_episodes = 1\n'
        "[settings]\nlearning_starts = 40\nepsilon_decay_steps = 300\n[envs.coexistence_v0]\nmax_cycles = 20\n"
        '[[methods]]\nmethod = "empathic_dqn"\nselfishness = 0.5\nlabel = "dqn"\n',
        encoding="utf-8",
    )
    out = tmp_path / "out"
    assert main(["reproduce", "--profile", str(sweep), "--out", str(out), "--no-progress"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "the label 'dqn' of empathic_dqn reads as 'DQN'" in err
    assert not out.exists(), "nothing trained or written"


def test_export_refuses_two_variants_one_to_marl_eval() -> None:
    from leaderboard.export_marl_eval import marl_eval_layout

    runs = []
    for variant in ("Coex", "coex"):
        document = _run(0)
        document["variant"] = document["config"]["variant"] = variant
        document["run_id"] = run_id(variant, document["method"], document["config"], 0)
        runs.append(record(document))
    with pytest.raises(ValueError, match="variants 'Coex' and 'coex' of coexistence_v0 are one task to marl-eval"):
        marl_eval_layout(runs)


def test_discrimination_refuses_one_exact_model_under_two_names(tmp_path: Path, capsys) -> None:
    import shutil

    shipped = Path(__file__).resolve().parents[1] / "docs" / "results" / "separation"
    for name in ("vase_v0.json", "helping_v0.json"):
        shutil.copy(shipped / name, tmp_path / name)
    shutil.copy(shipped / "vase_v0.json", tmp_path / "vase_copy.json")
    assert main(["analyse", "discrimination", str(tmp_path), "--out", str(tmp_path / "D.md")]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "vase_copy.json holds the table of vase_v0" in err, err  # (named as no other task)
    assert not (tmp_path / "D.md").exists()
