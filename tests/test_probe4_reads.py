"""A fourth probe's findings on reads: a leaderboard page handed to ``analyse verdict-changes`` is
read bounded (a device, a FIFO, a directory or a missing file is one line, status 2), and a result
file's evaluations hold at least one greedy episode."""

from __future__ import annotations

import copy
import os
from pathlib import Path

import pytest
from helpers_results import synthetic_document

from empathy_zoo.cli import main
from empathy_zoo.experiment.result_reader import check_result

PAGE = Path(__file__).resolve().parents[1] / "docs" / "results" / "quick" / "LEADERBOARD.md"


@pytest.mark.parametrize("kind", ["device", "fifo", "directory", "missing"])
def test_verdict_changes_reads_pages_bounded(tmp_path: Path, capsys, kind: str) -> None:
    path = {"device": Path("/dev/zero"), "directory": tmp_path, "missing": tmp_path / "none.md"}.get(kind, tmp_path / "fifo")
    if kind == "fifo":
        os.mkfifo(path)
    assert main(["analyse", "verdict-changes", str(path), str(PAGE)]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and str(path) in err


def test_verdict_changes_of_a_page_with_its_copy_lists_no_change(tmp_path: Path, capsys) -> None:
    copy_of_page = tmp_path / "LEADERBOARD.md"
    copy_of_page.write_bytes(PAGE.read_bytes())
    assert main(["analyse", "verdict-changes", str(PAGE), str(copy_of_page)]) == 0
    out = capsys.readouterr().out
    assert "|" in out and " 0 marks differ" in out, out


@pytest.mark.parametrize("second", ["same", "link", "dotted"])
def test_verdict_changes_refuses_one_page_given_twice(tmp_path: Path, capsys, second: str) -> None:
    page = tmp_path / "LEADERBOARD.md"
    page.write_bytes(PAGE.read_bytes())
    other = {"same": page, "link": tmp_path / "link.md", "dotted": tmp_path / "." / "LEADERBOARD.md"}[second]
    if second == "link":
        other.symlink_to(page)
    capsys.readouterr()
    assert main(["analyse", "verdict-changes", str(page), str(other)]) == 2
    out, err = capsys.readouterr()
    assert out == "" and err.count("\n") == 1 and f"{other} is given twice (as {page} too)" in err, err


def test_an_evaluation_of_no_episode_is_refused() -> None:
    run = copy.deepcopy(synthetic_document("coexistence_v0", "dqn", 1.0, 0))
    run["config"].pop("eval_episodes", None)
    for evaluation in run["eval"]:
        for name in evaluation:
            if name != "step":
                evaluation[name] = []
    with pytest.raises(ValueError, match=r"at least one greedy episode"):
        check_result(run, "x.json")


@pytest.mark.parametrize("there", ["directory", "link"])
def test_an_unreadable_list_of_runs_is_not_set_aside_over_a_directory_or_link(tmp_path: Path, there: str) -> None:
    from empathy_zoo.experiment.model import RunSpec
    from empathy_zoo.training.checkpoint import save_checkpoint
    from empathy_zoo.training.resume import checkpoint_path, plan_ensembles

    todo = [RunSpec.of(steps=100, eval_interval=100, eval_episodes=1, seed=0)]
    out = tmp_path / "out"
    checkpoint = checkpoint_path(out, todo)
    save_checkpoint(checkpoint, {"run_ids": [s.run_id for s in todo]})
    manifest = checkpoint.with_name(checkpoint.stem + ".runs.json")
    manifest.write_text("{")
    aside = manifest.with_name(manifest.name + ".unreadable")
    target = tmp_path / "user.txt"
    target.write_text("mine")
    aside.mkdir() if there == "directory" else aside.symlink_to(target)
    plan_ensembles(todo, out, 1, lambda _: None)  # (set aside under the next free name: tests/test_probe6.py)
    assert manifest.with_name(manifest.name + ".unreadable.2").read_text() == "{" and target.read_text() == "mine"
    assert aside.is_dir() if there == "directory" else aside.is_symlink()


@pytest.mark.parametrize("command", ["a\nb", "x\x1b[31m", "", "y" * 2_001])
def test_produced_by_is_one_line_of_printable_text(tmp_path: Path, capsys, command: str) -> None:
    assert main(["reproduction", str(PAGE.parent), "--out", str(tmp_path / "r.md"), "--produced-by", command]) == 2
    assert "--produced-by" in capsys.readouterr().err and not (tmp_path / "r.md").exists()


def test_a_stale_leaderboard_stage_holding_a_users_file_is_left(tmp_path: Path) -> None:
    from helpers_results import synthetic_document

    from empathy_zoo.atomic import write_json_atomic
    from leaderboard import report

    results = tmp_path / "results"
    run = synthetic_document("coexistence_v0", "dqn", 1.0, 0)
    write_json_atomic(results / "runs" / f"{run['run_id']}.json", run)
    users, rendered = (
        results / ".leaderboard.ezoo-2000000001-deadbeef.tmp",
        results / ".leaderboard.ezoo-2000000002-deadbeef.tmp",
    )  # (no such pid)
    users.mkdir()
    (users / "own").write_text("mine")
    (rendered / "figures").mkdir(parents=True)
    (rendered / "LEADERBOARD.md").write_text("# empathy-zoo leaderboard\n\nhalf")  # (what a render stages, as it begins)
    (rendered / "figures" / "a.png").write_bytes(b"\x89PNG\r\n\x1a\n...")
    folder, notes = (results / f".leaderboard.ezoo-200000000{i}-deadbeef.tmp" for i in (3, 4))  # (probe 26: names of
    (folder / "LEADERBOARD.md").mkdir(parents=True)  # pages, but a folder and a user's text: no render's)
    (folder / "LEADERBOARD.md" / "notes.txt").write_text("precious")
    notes.mkdir()
    (notes / "leaderboard.csv").write_text("my own notes, not a page")
    report.write_leaderboard(results, n_resamples=50, on_note=lambda _: None)
    assert (users / "own").read_text() == "mine" and not rendered.exists()
    assert (folder / "LEADERBOARD.md" / "notes.txt").read_text() == "precious"
    assert (notes / "leaderboard.csv").read_text() == "my own notes, not a page"


@pytest.mark.parametrize("text", ["{}", "[" * 100_000 + "]" * 100_000, "{not json", '{"plan": 3, "trials": []}'])
def test_tuning_summary_refuses_a_forged_study_in_one_line(tmp_path: Path, capsys, text: str) -> None:
    study = tmp_path / "a" / "study.json"
    study.parent.mkdir()
    study.write_text(text)
    assert main(["analyse", "tuning-summary", str(tmp_path)]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and str(study) in err
