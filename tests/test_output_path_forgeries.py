"""Whatever lies in the place of a file the suite writes is refused, in one line naming it, before
anything is written: only nothing, or a regular file that is no link, is ever replaced.

A symbolic link, a FIFO, a character device or a directory where ``export --out`` would go, where
the leaderboard's pages and figures go, where ``tune`` writes ``study.json``, ``tuned.toml``,
``trials.png`` or appends to ``study.journal``, or where ``train --log csv`` logs (a linked
``OUT/logs``, a linked ``scalars.csv``) is refused with exit status 2 naming it (a link with its
target), and the place is left exactly as it was: no target written through, no page published
(every target is checked before the first is moved), no directory created. A refusal of ``watch
--gif`` (an unknown run, an unknown partner) creates no directory for the GIF, and ``--gif ""`` is
refused as an empty path; ``check_output_dir`` checks every subdirectory before it creates one.
"""

from __future__ import annotations

import errno
import os
import shutil
from collections.abc import Callable
from pathlib import Path

import pytest
import test_check_then_write as check_then_write
from test_check_then_write import one_line_refusal, write_results
from test_inert_files import call_within
from test_reader_forgeries import listing

from empathy_zoo import atomic
from empathy_zoo.atomic import check_output_dir, write_text_atomic
from empathy_zoo.cli import main
from empathy_zoo.names import check_replaceable
from empathy_zoo.training.tracking import EnsembleTracker, log_dir

trained = check_then_write.trained
"""Two tiny runs (DQN, Empathic DQN) that kept their agents (the fixture of tests/test_check_then_write.py)."""


# ---------------------------------------------------------------------------- what lies in a written file's place
def link_to_a_file(path: Path, elsewhere: Path) -> None:
    elsewhere.write_text("victim\n")
    path.symlink_to(elsewhere)


def dangling_link(path: Path, elsewhere: Path) -> None:
    path.symlink_to(elsewhere / "nothing-here")


def fifo(path: Path, elsewhere: Path) -> None:
    os.mkfifo(path)


def char_device(path: Path, elsewhere: Path) -> None:
    try:
        os.mknod(path, 0o600 | 0o020000, os.makedev(1, 3))  # (the device /dev/null is)
    except (PermissionError, AttributeError):
        pytest.skip("making a device needs root")


def directory(path: Path, elsewhere: Path) -> None:
    path.mkdir()
    (path / "inside.txt").write_text("kept\n")


PLACES: list[Callable[[Path, Path], None]] = [link_to_a_file, dangling_link, fifo, char_device, directory]


def forge(path: Path, kind: Callable[[Path, Path], None], elsewhere: Path) -> Path:
    """Put ``kind`` in the place of ``path`` (a file there removed first); returns ``path``."""
    if path.is_symlink() or path.is_file():
        path.unlink()
    kind(path, elsewhere)
    return path


def refused_naming(status: int, capsys: pytest.CaptureFixture[str], path: Path) -> str:
    err = one_line_refusal(capsys)
    assert status == 2, err
    assert str(path) in err, err
    if path.is_symlink():
        assert os.readlink(path) in err, err  # (a link is named with its target)
    return err


def snapshot(*roots: Path) -> list[object]:
    return [listing(root) if root.is_dir() else (root.exists(), root.is_symlink()) for root in roots]


# ---------------------------------------------------------------------------- the one check
@pytest.mark.parametrize("kind", PLACES, ids=lambda kind: kind.__name__)
def test_only_nothing_or_a_regular_file_may_be_replaced(tmp_path, kind):
    assert check_replaceable(tmp_path / "nothing.json") == tmp_path / "nothing.json"
    (tmp_path / "regular.json").write_text("{}")
    assert check_replaceable(tmp_path / "regular.json") == tmp_path / "regular.json"
    path = forge(tmp_path / "x.json", kind, tmp_path / "elsewhere")
    with pytest.raises(ValueError, match="not a regular file") as refused:
        check_replaceable(path)
    assert str(path) in str(refused.value) and "\n" not in str(refused.value)
    before = snapshot(tmp_path)
    with pytest.raises(ValueError, match=str(path)):
        write_text_atomic(path, "new\n")
    assert snapshot(tmp_path) == before  # (nothing written through it, no temporary file left)


def test_check_output_dir_checks_every_subdirectory_before_creating_one(tmp_path):
    out, elsewhere = tmp_path / "out", tmp_path / "elsewhere"
    out.mkdir()
    elsewhere.mkdir()
    (out / "checkpoints").symlink_to(elsewhere, target_is_directory=True)
    with pytest.raises(ValueError, match=f"{out / 'checkpoints'} is a symbolic link"):
        check_output_dir(out, ("runs", "checkpoints"))
    assert sorted(path.name for path in out.iterdir()) == ["checkpoints"] and not any(elsewhere.iterdir())


def test_a_refused_output_directory_leaves_no_directory_it_created(tmp_path, monkeypatch):
    def full_disk(path: Path, data: bytes) -> Path:
        raise OSError(errno.ENOSPC, "No space left on device", str(path))

    monkeypatch.setattr(atomic, "write_bytes_atomic", full_disk)
    with pytest.raises(ValueError, match="not writable"):
        check_output_dir(tmp_path / "new" / "out", ("runs", "logs/csv"))
    assert list(tmp_path.iterdir()) == []


# ---------------------------------------------------------------------------- export --out (defect 6)
@pytest.mark.parametrize("kind", [link_to_a_file, dangling_link, fifo, char_device], ids=lambda kind: kind.__name__)
def test_export_replaces_only_a_regular_file(tmp_path, capsys, kind):
    results = write_results(tmp_path / "results")
    folder = tmp_path / "exports"
    folder.mkdir()
    path = forge(folder / "marl_eval.json", kind, tmp_path / "victim.txt")
    before = snapshot(folder, tmp_path / "victim.txt")
    status = main(["export", str(results), "--format", "marl-eval", "--out", str(path)])
    refused_naming(status, capsys, path)
    assert snapshot(folder, tmp_path / "victim.txt") == before
    if kind is link_to_a_file:
        assert (tmp_path / "victim.txt").read_text() == "victim\n"


# ---------------------------------------------------------------------------- leaderboard pages and figures (7, 8)
@pytest.fixture(scope="module")
def published(tmp_path_factory) -> Path:
    """A leaderboard written over synthetic results (two methods × two seeds)."""
    results = write_results(tmp_path_factory.mktemp("published") / "results")
    assert main(["leaderboard", str(results)]) == 0
    return results


def first_figure(results: Path) -> str:
    return "figures/" + sorted(path.name for path in (results / "figures").glob("*.png"))[0]


@pytest.mark.parametrize("place", ["LEADERBOARD.md", "leaderboard.csv", "leaderboard.html", "figure"])
@pytest.mark.parametrize("kind", [link_to_a_file, fifo, directory], ids=lambda kind: kind.__name__)
def test_the_leaderboard_replaces_only_regular_files(published, tmp_path, capsys, place, kind):
    results = Path(shutil.copytree(published, tmp_path / "results", symlinks=True))
    path = forge(results / (first_figure(results) if place == "figure" else place), kind, tmp_path / "victim.txt")
    (results / "runs" / next(iter(sorted(os.listdir(results / "runs"))))).unlink()  # (the new pages would differ)
    before = snapshot(results, tmp_path / "victim.txt")
    capsys.readouterr()
    status = main(["leaderboard", str(results)])
    refused_naming(status, capsys, path)
    assert snapshot(results, tmp_path / "victim.txt") == before  # (not one page or figure published)


def test_a_page_in_the_way_is_refused_before_any_file_is_moved(published, tmp_path, capsys):
    results = Path(shutil.copytree(published, tmp_path / "results", symlinks=True))
    (results / "leaderboard.html").unlink()
    (results / "leaderboard.html").mkdir()
    for run in sorted((results / "runs").glob("*__s1.json")):
        run.unlink()
    before = snapshot(results)
    capsys.readouterr()
    status = main(["leaderboard", str(results)])
    err = refused_naming(status, capsys, results / "leaderboard.html")
    assert "half-written" not in err
    assert snapshot(results) == before  # (LEADERBOARD.md, leaderboard.csv and the figures as they were)


# ---------------------------------------------------------------------------- tune's outputs (9)
TUNE_SWEEP = """
[sweep]
seeds = [0]
steps = 200
eval_interval = 100
eval_episodes = 1

[settings]
learning_starts = 32
replay_capacity = 200
hidden_size = 8
target_update_interval = 50
epsilon_decay_steps = 100

[envs.coexistence_v0]
max_cycles = 30

[[methods]]
method = "dqn_harm_penalty"
"""


@pytest.mark.parametrize("name", ["study.json", "tuned.toml", "trials.png", "study.journal"])
@pytest.mark.parametrize("kind", [link_to_a_file, fifo, char_device], ids=lambda kind: kind.__name__)
def test_tune_replaces_or_appends_to_only_regular_files(tmp_path, capsys, name, kind):
    pytest.importorskip("optuna")
    sweep = tmp_path / "tiny.toml"
    sweep.write_text(TUNE_SWEEP)
    out = tmp_path / "tu"
    out.mkdir()
    path = forge(out / name, kind, tmp_path / "outside")
    victim = "" if name == "study.journal" else "victim\n"  # (an empty journal outside: a study would append to it)
    if kind is link_to_a_file:
        (tmp_path / "outside").write_text(victim)
    before = snapshot(out, tmp_path / "outside")
    capsys.readouterr()
    status = main(
        [
            "tune",
            str(sweep),
            *("--method", "dqn_harm_penalty", "--param", "penalty=float:-50:-1", "--trials", "1"),
            *("--startup-trials", "1", "--tuning-seeds", "1", "--no-progress", "--out", str(out)),
        ]
    )
    refused_naming(status, capsys, path)
    assert snapshot(out, tmp_path / "outside") == before  # (nothing trained, written or appended)
    if kind is link_to_a_file:
        assert (tmp_path / "outside").read_text() == victim


# ---------------------------------------------------------------------------- train --log csv (10)
def tiny_train(out: Path, *extra: str) -> list[str]:
    return [
        "train",
        *("--method", "dqn", "--steps", "100", "--eval-interval", "100", "--eval-episodes", "1", "--seeds", "0"),
        *("--learning-starts", "32", "--replay-capacity", "200", "--hidden-size", "8", "--max-cycles", "20"),
        *("--update-kernel", "torch", "--no-progress", "--out", str(out), *extra),
    ]


def test_train_logs_nothing_through_a_linked_logs_directory(tmp_path, capsys):
    out, elsewhere = tmp_path / "out", tmp_path / "elsewhere"
    out.mkdir()
    elsewhere.mkdir()
    (out / "logs").symlink_to(elsewhere, target_is_directory=True)
    before = snapshot(out)
    status = main(tiny_train(out, "--checkpoint-interval", "0", "--log", "csv"))
    refused_naming(status, capsys, out / "logs")
    assert snapshot(out) == before and not any(elsewhere.iterdir())  # (no runs/ either)


@pytest.mark.parametrize("kind", [link_to_a_file, fifo], ids=lambda kind: kind.__name__)
def test_a_runs_csv_log_is_only_a_regular_file(tmp_path, kind):
    from helpers_heldout import dqn_and_empathic_runs

    specs = dqn_and_empathic_runs((0,), 20, 1)
    place = log_dir(tmp_path, "csv", specs[1].run_id)
    place.mkdir(parents=True)
    path = forge(place / "scalars.csv", kind, tmp_path / "victim.txt")
    before = snapshot(tmp_path)
    tracker = EnsembleTracker(("csv",), tmp_path, specs)
    try:
        error = call_within(10, lambda: tracker.start(0, [None] * len(specs)))  # (a FIFO opened to append blocks)
    finally:
        if kind is fifo:  # (a reader lets a blocked writer go)
            os.close(os.open(path, os.O_RDONLY | os.O_NONBLOCK))
        tracker.close()
    assert isinstance(error, ValueError) and str(path) in str(error), error
    assert snapshot(tmp_path) == before  # (the first run's directory is not created either)


# ---------------------------------------------------------------------------- refusals create no directory (11)
def test_train_refused_for_a_linked_checkpoints_directory_creates_no_runs_directory(tmp_path, capsys):
    out, elsewhere = tmp_path / "out", tmp_path / "elsewhere"
    out.mkdir()
    elsewhere.mkdir()
    (out / "checkpoints").symlink_to(elsewhere, target_is_directory=True)
    status = main(tiny_train(out, "--checkpoint-interval", "50"))
    refused_naming(status, capsys, out / "checkpoints")
    assert sorted(os.listdir(out)) == ["checkpoints"] and not any(elsewhere.iterdir())


def test_watch_of_an_unknown_run_creates_no_directory_for_its_gif(tmp_path, capsys):
    gif = tmp_path / "d" / "new" / "sub" / "x.gif"
    status = main(["watch", "--dir", str(tmp_path), "no_such_run", "--gif", str(gif)])
    assert status == 2 and "no_such_run" in one_line_refusal(capsys)
    assert not (tmp_path / "d").exists()


def test_watch_with_an_unknown_partner_creates_no_directory_for_its_gif(trained, tmp_path, capsys):
    agent = next((trained / "runs").glob("*.agent.pt"))
    gif = tmp_path / "d" / "new" / "sub" / "x.gif"
    status = main(["watch", str(agent), "--fixed", "cat_0=nope", "--gif", str(gif)])
    assert status == 2 and "nope" in one_line_refusal(capsys)
    assert not (tmp_path / "d").exists()


def test_watch_gif_of_an_empty_path_is_refused(trained, tmp_path, capsys, monkeypatch):
    agent = next((trained / "runs").glob("*.agent.pt"))
    monkeypatch.chdir(tmp_path)
    status = main(["watch", str(agent), "--gif", ""])
    captured = capsys.readouterr()
    assert status == 2, captured
    assert captured.err.startswith("empathy-zoo: error: ") and captured.err.count("\n") == 1 and "empty" in captured.err
    assert "episode 0" not in captured.out and list(tmp_path.iterdir()) == []
