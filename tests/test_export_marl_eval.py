"""``empathy-zoo export --format marl-eval``: the layout marl-eval reads (environment → task →
algorithm → run → step, with absolute metrics), built from synthetic result files and from the
shipped quick results, every run and evaluation present with the result files' values; read back
by marl-eval's own processing where ``marl_eval`` imports; written atomically; bad input refused
with one line."""

from __future__ import annotations

import json
import os
import re
from pathlib import Path

import pytest
from helpers_results import derive_run_id, record, synthetic_document, within_env

from empathy_zoo.atomic import write_json_atomic
from empathy_zoo.cli import main
from empathy_zoo.experiment.records import RunResult
from empathy_zoo.metrics import HIGHER_IS_BETTER, METRIC_NAMES
from leaderboard.aggregate import load_results, table_env
from leaderboard.export_marl_eval import (
    ABSOLUTE_METRICS,
    STEP_COUNT,
    algorithm_name,
    marl_eval_layout,
    run_key,
    step_key,
)

ROOT = Path(__file__).resolve().parents[1]
QUICK = ROOT / "docs" / "results" / "quick"
ENV = "coexistence_v0"
EVAL_STEPS = (2000, 4000)
"""The training steps of every synthetic run's greedy evaluations."""


def run(
    method: str, beta: float, seed: int, variant: str | None = None, label: str | None = None, steps: int = 4000
) -> RunResult:
    """A synthetic run with a greedy evaluation at each of :data:`EVAL_STEPS` before ``steps`` and at ``steps``,
    each metric's episodes distinct per run, evaluation, metric and episode (but a count capped at
    what an episode of Coexistence holds: one harm, no battery)."""
    return record(run_document(method, beta, seed, variant, label, steps))


def run_document(
    method: str, beta: float, seed: int, variant: str | None = None, label: str | None = None, steps: int = 4000
) -> dict:
    """The result document of :func:`run`."""
    result = synthetic_document(ENV, method, beta, seed)
    result["steps"] = steps
    result["config"] = {**result["config"], "steps": steps, "eval_interval": 2000, "eval_episodes": 3}
    kept = [i for i, end in enumerate(result["train"]["episode_end_step"]) if end <= steps]  # (episodes within the budget)
    result["train"] = {name: [column[i] for i in kept] for name, column in result["train"].items()}
    if variant is not None:
        result["variant"] = variant
        result["config"] = {**result["config"], "variant": variant}
    if label is not None:
        result["method_label"] = label
    result["eval"] = [
        {
            "step": step,
            **within_env(  # (counts whole and within what an episode gives, equality within [0, 1], as the checker asks)
                ENV,
                {
                    m: [(seed + 10.0 * j + 100.0 * i + e) / (1000.0 if m == "equality" else 1.0) for e in range(3)]
                    for j, m in enumerate(METRIC_NAMES)
                },
            ),
        }
        for i, step in enumerate([*(s for s in EVAL_STEPS if s < steps), steps])  # (every 2,000 steps and the last, as trained)
    ]
    return derive_run_id(result)


def write_dir(directory: Path, runs: list[dict]) -> Path:
    for result in runs:
        write_json_atomic(directory / "runs" / f"{result['run_id']}.json", result)
    return directory


def synthetic_runs() -> list[RunResult]:
    """Two tasks of one environment (the env itself and a variant), two algorithms, three seeds."""
    return [
        run(method, beta, seed, variant)
        for variant in (None, "coexistence_wide")
        for method, beta in (("empathic_dqn", 1.0), ("empathic_dqn", 0.5))
        for seed in range(3)
    ]


def assert_layout_holds(layout: dict, results: list[RunResult]) -> None:
    """Every run of ``results`` is in ``layout`` where the mapping puts it, with every evaluation
    (in step order, its metrics' lists as the result file holds them) and the last as its absolute
    metrics; nothing else is in ``layout``."""
    for result in results:
        steps = layout[result.env][table_env(result)][algorithm_name(result.method_label)][run_key(result.seed)]
        evaluations = result.to_document()["eval"]  # (as the file holds them: by step)
        assert list(steps) == [*(step_key(i) for i in range(len(evaluations))), ABSOLUTE_METRICS]
        for i, entry in enumerate(evaluations):
            assert steps[step_key(i)] == {STEP_COUNT: entry["step"], **{m: entry[m] for m in METRIC_NAMES}}
        assert steps[ABSOLUTE_METRICS] == {m: evaluations[-1][m] for m in METRIC_NAMES}
    written = {
        (env, task, algorithm, seed)
        for env, tasks in layout.items()
        for task, algorithms in tasks.items()
        for algorithm, runs in algorithms.items()
        for seed in runs
    }
    expected = {(r.env, table_env(r), algorithm_name(r.method_label), run_key(r.seed)) for r in results}
    assert written == expected


def test_the_layout_of_synthetic_runs_nests_environment_task_algorithm_run_step() -> None:
    results = synthetic_runs()
    layout = marl_eval_layout(results)
    assert list(layout) == [ENV]
    assert list(layout[ENV]) == [ENV, "coexistence_wide"]
    for task in layout[ENV].values():
        assert list(task) == ["empathic_dqn 0.5", "empathic_dqn 1.0"]  # the leaderboard's row order
        for runs in task.values():
            assert list(runs) == ["seed_0", "seed_1", "seed_2"]
            for steps in runs.values():
                assert [steps[key][STEP_COUNT] for key in ("step_0", "step_1")] == list(EVAL_STEPS)
                assert STEP_COUNT not in steps[ABSOLUTE_METRICS] and "elapsed_time" not in steps["step_0"]
    assert layout[ENV]["coexistence_wide"]["empathic_dqn 1.0"]["seed_2"]["step_1"]["survival"] == [102.0, 103.0, 104.0]
    assert_layout_holds(layout, results)


def test_evaluations_are_written_in_step_order() -> None:
    result = run("empathic_dqn", 0.5, 0)  # (a file's evaluations are by step: the checker refuses others)
    steps = marl_eval_layout([result])[ENV][ENV]["empathic_dqn 0.5"]["seed_0"]
    assert [steps[key][STEP_COUNT] for key in ("step_0", "step_1")] == list(EVAL_STEPS)
    assert steps[ABSOLUTE_METRICS]["survival"] == result.eval[-1].metrics["survival"].tolist()  # the one at step 4000
    assert all(type(value) is float for value in steps[ABSOLUTE_METRICS]["survival"])  # (written as the file holds them)


def test_the_shipped_quick_results_are_all_exported_with_their_values() -> None:
    results = load_results(QUICK)
    layout = marl_eval_layout(results)
    assert sorted(layout) == ["coexistence_v0", "sharing_v0"]
    assert sum(len(runs) for tasks in layout.values() for algorithms in tasks.values() for runs in algorithms.values()) == len(
        results
    )
    assert_layout_holds(layout, results)


def test_commas_are_dropped_from_algorithm_names_and_names_one_to_marl_eval_are_refused() -> None:
    assert algorithm_name("Empathic DQN, mean (β=0.5)") == "Empathic DQN mean (β=0.5)"
    assert algorithm_name("DQN · 30,000 steps") == "DQN · 30000 steps"
    layout = marl_eval_layout([run("empathic_dqn", 0.5, 0, label="Empathic DQN, mean (β=0.5)")])
    assert list(layout[ENV][ENV]) == ["Empathic DQN mean (β=0.5)"]
    for other in ("Empathic DQN mean (β=0.5)", "empathic dqn, MEAN (β=0.5)"):
        clash = [run("empathic_dqn", 0.5, 0, label="Empathic DQN, mean (β=0.5)"), run("empathic_dqn", 1.0, 0, label=other)]
        with pytest.raises(ValueError, match=r"one algorithm to marl-eval.*give one its own label"):
            marl_eval_layout(clash)
    # one name in two tasks is no clash
    marl_eval_layout([run("empathic_dqn", 0.5, 0, label="X"), run("empathic_dqn", 1.0, 0, variant="coexistence_wide", label="X")])


def test_a_run_without_greedy_evaluation_is_refused_naming_it() -> None:
    document = run_document("empathic_dqn", 0.5, 0)
    del document["config"]["eval_interval"]  # (a file made before it was recorded: any evaluations, or none)
    empty = record(derive_run_id({**document, "eval": []}))
    with pytest.raises(ValueError, match=re.escape(f"run {empty.run_id} has no greedy evaluation")):
        marl_eval_layout([empty])


def test_export_writes_json_that_reads_back_as_the_layout(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    out = tmp_path / "out" / "quick.json"
    assert main(["export", str(QUICK), "--format", "marl-eval", "--out", str(out)]) == 0
    assert "30 runs of 10 algorithms on 2 tasks of 2 environments" in capsys.readouterr().out
    assert json.loads(out.read_text(encoding="utf-8")) == marl_eval_layout(load_results(QUICK))


def test_several_directories_keep_their_rows_apart_as_the_leaderboard_does(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    mine = write_dir(tmp_path / "mine", [run_document("empathic_dqn", 0.5, seed) for seed in range(2)])
    theirs = write_dir(tmp_path / "theirs", [run_document("empathic_dqn", 0.5, seed, steps=3000) for seed in range(2)])
    out = tmp_path / "both.json"
    argv = ["export", str(mine), str(theirs), "--format", "marl-eval", "--out", str(out)]
    assert main(argv) == 0  # two budgets: every label ends with its budget (commas dropped)
    assert list(json.loads(out.read_text())[ENV][ENV]) == ["empathic_dqn 0.5 · 3000 steps", "empathic_dqn 0.5 · 4000 steps"]
    other_experiment = run_document("empathic_dqn", 0.5, 0)  # (another learning rate: another experiment, one label)
    other_experiment["config"]["settings"] = {**other_experiment["config"]["settings"], "learning_rate": 0.0005}
    derive_run_id(other_experiment)
    same_budget = write_dir(tmp_path / "same", [other_experiment])
    out.unlink()
    assert main(["export", str(mine), str(same_budget), "--format", "marl-eval", "--out", str(out)]) == 2
    error = capsys.readouterr().err
    assert error.count("\n") == 1 and f"--label {same_budget}=PREFIX" in error and not out.exists()
    argv = ["export", str(mine), str(same_budget), "--format", "marl-eval", "--out", str(out), "--label", f"{same_budget}=new:"]
    assert main(argv) == 0
    assert list(json.loads(out.read_text())[ENV][ENV]) == ["empathic_dqn 0.5", "new: empathic_dqn 0.5"]


def test_the_write_is_atomic(tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]) -> None:
    out = tmp_path / "quick.json"
    assert main(["export", str(QUICK), "--format", "marl-eval", "--out", str(out)]) == 0
    previous = out.read_text()
    capsys.readouterr()

    def fail(source: object, destination: object) -> None:
        raise OSError(28, "No space left on device")

    monkeypatch.setattr(os, "replace", fail)
    assert main(["export", str(QUICK), "--format", "marl-eval", "--out", str(out)]) == 1
    error = capsys.readouterr().err
    assert error == f"empathy-zoo: error: --out {out}: cannot write it (No space left on device)\n"
    assert out.read_text() == previous
    assert [path.name for path in tmp_path.iterdir()] == ["quick.json"]  # no temporary file left


@pytest.mark.parametrize(
    ("argv", "expected"),
    [
        (["--format", "csv", "--out", "{tmp}/x.json"], "invalid choice: 'csv' (choose from 'marl-eval')"),
        (["--out", "{tmp}/x.json"], "the following arguments are required: --format"),
        (["--format", "marl-eval"], "the following arguments are required: --out"),
        (["--format", "marl-eval", "--out", "{tmp}"], "is a directory: name the JSON file to write"),
        (["--format", "marl-eval", "--out", "{tmp}/export.txt"], "is no JSON file name"),
        (["--format", "marl-eval", "--out", "{tmp}/a_file/x.json"], "a_file is a file, not a directory"),
        (["--format", "marl-eval", "--out", "{results}/runs/x.json"], "folder of a results directory"),
        (["--format", "marl-eval", "--out", "{tmp}/x.json", "--label", "nowhere"], "--label takes DIR=PREFIX"),
        (["--format", "marl-eval", "--out", "{tmp}/x.json", "--label", "other=p"], "is not one of the results directories read"),
    ],
)
def test_bad_input_is_refused_with_one_line_and_writes_nothing(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], argv: list[str], expected: str
) -> None:
    results = write_dir(tmp_path / "results", [run_document("empathic_dqn", 0.5, 0)])
    (tmp_path / "a_file").write_text("")
    before = sorted(tmp_path.rglob("*"))
    filled = [arg.replace("{tmp}", str(tmp_path)).replace("{results}", str(results)) for arg in argv]
    assert main(["export", str(results), *filled]) == 2
    error = capsys.readouterr().err
    assert expected in error and error.splitlines()[-1].startswith("empathy-zoo")
    assert sorted(tmp_path.rglob("*")) == before


def test_a_directory_without_result_files_is_refused(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    (tmp_path / "empty").mkdir()
    for directory in (tmp_path / "empty", tmp_path / "missing"):
        assert main(["export", str(directory), "--format", "marl-eval", "--out", str(tmp_path / "x.json")]) == 2
        error = capsys.readouterr().err
        assert error.count("\n") == 1 and str(directory) in error and ("no result files" in error or "does not exist" in error)
    assert not (tmp_path / "x.json").exists()


def test_the_formats_page_says_which_way_every_metric_is_better() -> None:
    text = (ROOT / "docs" / "formats.md").read_text(encoding="utf-8")
    section = text.split("## marl-eval JSON", 1)[1].split("\n## ", 1)[0]
    for metric in METRIC_NAMES:
        direction = "higher" if HIGHER_IS_BETTER[metric] else "lower"
        assert re.search(rf"\| `{metric}` \| {direction} \|", section), metric


def test_marl_evals_own_processing_reads_the_export() -> None:
    """marl-eval's ``data_process_pipeline``, ``create_matrices_for_rliable`` and ``DiagnoseData`` over
    the quick results' export (skipped where ``marl_eval`` does not import: ``id-marl-eval`` pins
    pandas 1.4.4, which does not install on this suite's Pythons)."""
    processing = pytest.importorskip("marl_eval.utils.data_processing_utils")
    diagnose = pytest.importorskip("marl_eval.utils.diagnose_data_errors")
    results = load_results(QUICK)
    layout = json.loads(json.dumps(marl_eval_layout(results)))
    checks = diagnose.DiagnoseData(layout).check_data()
    assert checks and all(all(check.values()) for check in checks.values())
    processed = processing.data_process_pipeline(layout, ["return"])
    assert "extra" in processed  # (on a layout it cannot read, it prints why and returns the data as given)
    assert processed["extra"]["number_of_runs"] == 3 and processed["extra"]["number_of_steps"] == 3
    absolute, over_steps = processing.create_matrices_for_rliable(processed, ENV, ["return"])
    for result in (r for r in results if r.env == ENV):
        algorithm = algorithm_name(result.method_label).lower()
        row = sorted(r.seed for r in results if r.method_label == result.method_label and r.env == ENV)
        last = result.eval[-1].metrics["harms"]
        seed_row = row.index(result.seed)
        assert absolute["mean_harms"][algorithm][seed_row, 0] == pytest.approx(sum(last) / len(last))
        assert over_steps["mean_survival"][algorithm].shape == (3, 1, 3)
