"""``empathy-zoo leaderboard RUNS --evaluations EVAL_DIR``: evaluation files kept apart from their
runs make the same held-out section (and pages) as the same files beside the runs; an evaluation
of another agent than its run's, of a run not read, or a forged one is refused with one line
naming the file, nothing written; bad directories are refused the same way."""

from __future__ import annotations

import csv
import io
import json
import shutil
from pathlib import Path

import pytest
from helpers_heldout import scenario_set, synthetic_run, write_synthetic

from empathy_zoo.atomic import write_json_atomic
from empathy_zoo.cli import main
from empathy_zoo.evaluation_file import EVALUATIONS_DIR
from empathy_zoo.experiment.records import RunResult
from leaderboard.evaluation_dirs import match_evaluations
from leaderboard.tables import CSV_COLUMNS

ENV = "coexistence_v0"
OWN = {"cat_0": "random_walk"}
SEEDS = range(5)
SET = scenario_set(ENV, {"still": {"cat_0": "stay"}, "chaser": {"cat_0": "chase"}})


def runs() -> list[RunResult]:
    """DQN and Empathic DQN (β = 0.5), five seeds each, every run with a kept agent."""
    return [synthetic_run(ENV, method, beta, seed) for method, beta in (("dqn", 1.0), ("empathic_dqn", 0.5)) for seed in SEEDS]


def values(run: RunResult) -> dict[str, dict[str, float]]:
    """Harms and survival per scenario: DQN harms, the empathic runs harm little."""
    harms = 0.8 if run.method == "dqn" else 0.1
    return {s: {"harms": harms + 0.01 * run.seed, "survival": 400.0} for s in ("trained_with", "still", "chaser")}


@pytest.fixture
def apart(tmp_path: Path) -> tuple[Path, Path, list[RunResult]]:
    """``(results dir, evaluations dir, runs)``: result files in one, their evaluation files in the other."""
    results, evaluations = tmp_path / "results", tmp_path / "evaluated"
    made = runs()
    for run in made:
        write_json_atomic(results / "runs" / f"{run.run_id}.json", run.to_document())
    write_synthetic(evaluations, [(run, values(run)) for run in made], SET, OWN)
    return results, evaluations, made


def one_line_error(capsys: pytest.CaptureFixture[str]) -> str:
    err = capsys.readouterr().err
    assert err.startswith("empathy-zoo: error: ") and err.count("\n") == 1 and "Traceback" not in err, err
    return err


def csv_rows(path: Path) -> list[list[str]]:
    return [row[: CSV_COLUMNS.index("command")] for row in csv.reader(io.StringIO(path.read_text(encoding="utf-8")))]


def without_command(text: str) -> list[str]:
    return [line for line in text.splitlines() if "Produced by" not in line]


def test_evaluations_apart_make_the_pages_they_make_beside_the_runs(apart, tmp_path: Path) -> None:
    results, evaluations, _ = apart
    separate, beside = tmp_path / "separate", tmp_path / "beside"
    assert main(["leaderboard", str(results), "--evaluations", str(evaluations), "--out", str(separate)]) == 0
    shutil.copytree(evaluations / EVALUATIONS_DIR, results / EVALUATIONS_DIR)
    assert main(["leaderboard", str(results), "--out", str(beside)]) == 0
    markdown = (separate / "LEADERBOARD.md").read_text(encoding="utf-8")
    assert "## Held-out partners" in markdown and "### coexistence_v0: scenario set synthetic" in markdown
    assert "Note:" not in markdown.split("## Held-out partners", 1)[1].split("\n## ", 1)[0]
    for page in ("LEADERBOARD.md", "leaderboard.html"):
        assert without_command((separate / page).read_text(encoding="utf-8")) == without_command(
            (beside / page).read_text(encoding="utf-8")
        ), page
    assert csv_rows(separate / "leaderboard.csv") == csv_rows(beside / "leaderboard.csv")
    figure = "figures/coexistence_v0_heldout_synthetic.png"
    assert (separate / figure).read_bytes() == (beside / figure).read_bytes()


def test_the_evaluations_folder_itself_may_be_given(apart, tmp_path: Path) -> None:
    results, evaluations, made = apart
    matched = match_evaluations([evaluations / EVALUATIONS_DIR], made, [results])
    assert sorted(evaluation.run_id for _, evaluation, _ in matched) == sorted(run.run_id for run in made)
    assert all(run.run_id == evaluation.run_id for run, evaluation, _ in matched)


def test_an_evaluation_of_another_agent_is_refused_naming_it(apart, tmp_path: Path, capsys) -> None:
    results, evaluations, made = apart
    retrained = made[3].to_document()
    retrained["agent"]["sha256"] = "0" * 64
    write_json_atomic(results / "runs" / f"{retrained['run_id']}.json", retrained)
    out = tmp_path / "out"
    assert main(["leaderboard", str(results), "--evaluations", str(evaluations), "--out", str(out)]) == 2
    err = one_line_error(capsys)
    assert f"{retrained['run_id']}.json: made of another agent" in err and str(evaluations) in err
    assert not out.exists()


def test_an_evaluation_of_a_run_not_read_is_refused_naming_it(apart, tmp_path: Path, capsys) -> None:
    results, evaluations, made = apart
    (results / "runs" / f"{made[0].run_id}.json").unlink()
    out = tmp_path / "out"
    assert main(["leaderboard", str(results), "--evaluations", str(evaluations), "--out", str(out)]) == 2
    err = one_line_error(capsys)
    assert f"{made[0].run_id}.json: its run {made[0].run_id} is in none of the results directories read" in err
    assert not out.exists()


@pytest.mark.parametrize(
    "forge",
    [
        lambda document: document["scenarios"][1]["metrics"]["harms"].__setitem__(0, -1.0),
        lambda document: document.__setitem__("format", "empathy_zoo.result"),
        lambda document: document["agent"].__setitem__("sha256", "not a hash"),
    ],
    ids=["negative harms", "another format", "no hash"],
)
def test_a_forged_evaluation_file_is_refused_with_nothing_written(apart, tmp_path: Path, capsys, forge) -> None:
    results, evaluations, _made = apart
    forged = next((evaluations / EVALUATIONS_DIR / "synthetic").glob("*.json"))
    document = json.loads(forged.read_text(encoding="utf-8"))
    forge(document)
    forged.write_text(json.dumps(document), encoding="utf-8")
    out = tmp_path / "out"
    out.mkdir()
    (out / "mine.txt").write_text("kept", encoding="utf-8")
    assert main(["leaderboard", str(results), "--evaluations", str(evaluations), "--out", str(out)]) == 2
    assert str(forged) in one_line_error(capsys)
    assert sorted(p.name for p in out.iterdir()) == ["mine.txt"]


def test_an_evaluation_beside_the_runs_and_apart_is_refused(apart, tmp_path: Path, capsys) -> None:
    results, evaluations, _made = apart
    shutil.copytree(evaluations / EVALUATIONS_DIR, results / EVALUATIONS_DIR)
    assert main(["leaderboard", str(results), "--evaluations", str(evaluations), "--out", str(tmp_path / "out")]) == 2
    err = one_line_error(capsys)
    assert "is evaluated in" in err and str(results / EVALUATIONS_DIR) in err
    assert not (tmp_path / "out").exists()


def test_bad_evaluation_directories_are_refused_in_one_line(apart, tmp_path: Path, capsys) -> None:
    results, evaluations, _ = apart
    (tmp_path / "empty").mkdir()
    (tmp_path / "file.txt").write_text("x", encoding="utf-8")
    cases = [
        ([str(tmp_path / "missing")], "does not exist"),
        ([str(tmp_path / "empty")], "holds no evaluation files"),
        ([str(tmp_path / "file.txt")], "is not a directory"),
        ([str(results)], "is the results directory"),
        ([str(evaluations), str(evaluations)], "is given twice"),
        ([""], "an empty path"),
    ]
    for given, expected in cases:
        argv = ["leaderboard", str(results), "--out", str(tmp_path / "out")]
        for directory in given:
            argv += ["--evaluations", directory]
        assert main(argv) == 2, given
        err = capsys.readouterr().err
        if given == [""]:  # (argparse's own refusal: its usage, then one line)
            err = err.splitlines()[-1] + "\n"
        assert err.startswith("empathy-zoo") and err.count("\n") == 1 and expected in err, (given, err)
        assert not (tmp_path / "out").exists()


def test_an_evaluation_beside_its_runs_that_is_not_its_runs_is_refused(tmp_path, capsys):
    """Beside the runs too (not only through --evaluations), an evaluation of the run's agent whose
    other fields are not the run's (a forged seed) is refused naming the file, nothing written."""
    import json
    import shutil

    from empathy_zoo.evaluation_file import evaluation_files

    source = Path(__file__).resolve().parents[1] / "docs" / "results" / "quick"
    results = tmp_path / "quick"
    shutil.copytree(source / "runs", results / "runs")
    shutil.copytree(source / "evaluations", results / "evaluations")
    path = evaluation_files(results)[0]
    document = json.loads(path.read_text())
    document["scenarios"][0]["fixed"] = {"cat_0": "stay"}
    path.write_text(json.dumps(document))
    out = tmp_path / "page"
    assert main(["leaderboard", str(results), "--out", str(out)]) == 2
    err = capsys.readouterr().err
    assert str(path) in err and "not an evaluation of run" in err and err.count("\n") == 1
    assert not out.exists()
