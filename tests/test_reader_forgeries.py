"""Whatever lies in a read file's place is refused, in one line naming it, before anything is written.

A FIFO, a link to ``/dev/zero``, a directory, a link to a directory, a dangling link or a loop of
links named as a result file (``runs/<id>.json``), an evaluation file
(``evaluations/<set>/<id>.json``), an agent file (``runs/<id>.agent.pt``) or a checkpoint is refused
by every command that reads that place (exit status 2, one line on stderr naming it), and the
directory it lies in is left exactly as it was: no run is left out without a word. ``evaluate``
checks every agent before it writes its first evaluation file, removes the directories it created
when it fails, and refuses an empty ``--out``. The bounded reader refuses a file past its cap by its
size, without reading it.
"""

from __future__ import annotations

import errno
import json
import os
import re
import shutil
import stat
from collections.abc import Callable
from pathlib import Path
from typing import Any

import pytest
import test_check_then_write as check_then_write
from test_check_then_write import agent_file_of, one_line_refusal

from empathy_zoo import limits
from empathy_zoo.cli import main
from empathy_zoo.data_files import data_files
from empathy_zoo.limits import read_bounded
from empathy_zoo.names import confined
from empathy_zoo.training import ensemble, heldout
from empathy_zoo.training.heldout import evaluate_results

trained = check_then_write.trained
"""Two tiny runs (DQN, Empathic DQN) that kept their agents (the fixture of tests/test_check_then_write.py)."""


# ---------------------------------------------------------------------------- what lies in a file's place
def fifo(path: Path, elsewhere: Path) -> None:
    os.mkfifo(path)


def dev_zero(path: Path, elsewhere: Path) -> None:
    path.symlink_to("/dev/zero")


def directory(path: Path, elsewhere: Path) -> None:
    path.mkdir()
    (path / "inside.json").write_text("{}")


def link_to_directory(path: Path, elsewhere: Path) -> None:
    elsewhere.mkdir(exist_ok=True)
    path.symlink_to(elsewhere, target_is_directory=True)


def dangling(path: Path, elsewhere: Path) -> None:
    path.symlink_to(elsewhere / "nothing-here")


def loop(path: Path, elsewhere: Path) -> None:
    path.symlink_to(path.name)


FORGERIES: list[Callable[[Path, Path], None]] = [fifo, dev_zero, directory, link_to_directory, dangling, loop]


def forge(path: Path, kind: Callable[[Path, Path], None], elsewhere: Path) -> Path:
    """Put ``kind`` in the place of the file ``path`` (removed first, if there); returns ``path``."""
    if path.is_symlink() or path.is_file():
        path.unlink()
    kind(path, elsewhere)
    return path


def listing(root: Path) -> list[tuple[str, int, Any]]:
    """Every entry below ``root``, links not followed: its path, its type, and its bytes (a regular
    file), its target (a link) or nothing (a directory, a FIFO)."""
    entries = []
    for folder, folders, files in os.walk(root):
        for name in sorted([*folders, *files]):
            path = Path(folder) / name
            mode = path.lstat().st_mode
            content: Any = None
            if stat.S_ISLNK(mode):
                content = os.readlink(path)
            elif stat.S_ISREG(mode):
                content = path.read_bytes()
            entries.append((path.relative_to(root).as_posix(), stat.S_IFMT(mode), content))
    return sorted(entries)


def refused_naming(status: int, capsys: pytest.CaptureFixture[str], path: Path) -> str:
    """The one line of a refusal (exit status 2) that names ``path``."""
    err = one_line_refusal(capsys)
    assert status == 2, err
    assert str(path) in err, err
    return err


# ---------------------------------------------------------------------------- result files
def first_run(results: Path) -> str:
    """The run id of the run whose file is read first."""
    return sorted(path.stem for path in (results / "runs").glob("*.json"))[0]


@pytest.mark.parametrize("kind", FORGERIES, ids=lambda kind: kind.__name__)
def test_a_result_files_place_is_refused_by_the_leaderboard(trained, tmp_path, capsys, kind):
    results = Path(shutil.copytree(trained, tmp_path / "results"))
    path = forge(results / "runs" / f"{first_run(results)}.json", kind, tmp_path / "elsewhere")
    before = listing(results)
    status = main(["leaderboard", str(results), "--out", str(tmp_path / "out")])
    refused_naming(status, capsys, path)
    assert listing(results) == before and not (tmp_path / "out").exists()


@pytest.mark.parametrize("kind", FORGERIES, ids=lambda kind: kind.__name__)
def test_a_result_files_place_is_refused_by_export(trained, tmp_path, capsys, kind):
    results = Path(shutil.copytree(trained, tmp_path / "results"))
    path = forge(results / "runs" / f"{first_run(results)}.json", kind, tmp_path / "elsewhere")
    before = listing(results)
    status = main(["export", str(results), "--format", "marl-eval", "--out", str(tmp_path / "out" / "ex.json")])
    refused_naming(status, capsys, path)
    assert listing(results) == before and not (tmp_path / "out").exists()


# ---------------------------------------------------------------------------- evaluation files
@pytest.mark.parametrize("kind", FORGERIES, ids=lambda kind: kind.__name__)
def test_an_evaluation_files_place_is_refused_by_the_leaderboard(trained, tmp_path, capsys, kind):
    results = Path(shutil.copytree(trained, tmp_path / "results"))
    folder = results / "evaluations" / "coexistence_v0"
    folder.mkdir(parents=True)
    path = forge(folder / f"{first_run(results)}.json", kind, tmp_path / "elsewhere")
    before = listing(results)
    status = main(["leaderboard", str(results), "--out", str(tmp_path / "out")])
    refused_naming(status, capsys, path)
    assert listing(results) == before and not (tmp_path / "out").exists()


# ---------------------------------------------------------------------------- agent files
@pytest.mark.parametrize("kind", FORGERIES, ids=lambda kind: kind.__name__)
def test_an_agent_files_place_is_refused_by_the_leaderboard(trained, tmp_path, capsys, kind):
    results = Path(shutil.copytree(trained, tmp_path / "results", symlinks=True))
    _, agent = agent_file_of(results, "empathic_dqn")
    path = forge(agent, kind, tmp_path / "elsewhere")
    before = listing(results)
    status = main(["leaderboard", str(results), "--out", str(tmp_path / "out")])
    refused_naming(status, capsys, path)
    assert listing(results) == before and not (tmp_path / "out").exists()


@pytest.mark.parametrize("kind", FORGERIES, ids=lambda kind: kind.__name__)
def test_an_agent_files_place_is_refused_by_evaluate(trained, tmp_path, capsys, kind):
    results = Path(shutil.copytree(trained, tmp_path / "results", symlinks=True))
    _, agent = agent_file_of(results, "empathic_dqn")
    path = forge(agent, kind, tmp_path / "elsewhere")
    before = listing(results)
    status = main(["evaluate", str(results), "--episodes", "1", "--no-progress"])
    refused_naming(status, capsys, path)
    assert listing(results) == before and not (results / "evaluations").exists()


def test_a_loop_of_links_is_refused_where_a_path_is_resolved(tmp_path):
    forge(tmp_path / "x.agent.pt", loop, tmp_path)
    with pytest.raises(ValueError, match="loop of symbolic links") as caught:
        confined(tmp_path, "x.agent.pt")
    assert str(tmp_path / "x.agent.pt") in str(caught.value) and "\n" not in str(caught.value)


def test_only_the_names_read_must_be_regular_files(tmp_path):
    (tmp_path / "a.json").write_text("{}")
    (tmp_path / "b.json").symlink_to(tmp_path / "a.json")
    os.mkfifo(tmp_path / ".c.json")  # (a write in progress: not read)
    os.mkfifo(tmp_path / "notes.txt")
    (tmp_path / "plots").mkdir()
    assert data_files(tmp_path, "*.json") == [tmp_path / "a.json", tmp_path / "b.json"]


# ---------------------------------------------------------------------------- checkpoints
def train_command(out: Path) -> list[str]:
    return [
        "train",
        *("--method", "dqn", "--steps", "300", "--eval-interval", "300", "--eval-episodes", "1", "--seeds", "0"),
        *(
            "--learning-starts",
            "32",
            "--replay-capacity",
            "300",
            "--hidden-size",
            "8",
            "--max-cycles",
            "40",
            "--epsilon-decay-steps",
            "100",
        ),
        *("--checkpoint-interval", "200", "--update-kernel", "torch", "--no-progress", "--out", str(out)),
    ]


@pytest.fixture(scope="module")
def checkpointed(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """The output directory of :func:`train_command`, killed just after its checkpoint at step 200."""
    out = tmp_path_factory.mktemp("checkpointed") / "out"
    real = ensemble.save_checkpoint

    def save_then_die(path: Path, payload: dict[str, Any]) -> None:
        real(path, payload)
        raise KeyboardInterrupt

    ensemble.save_checkpoint = save_then_die
    try:
        assert main(train_command(out)) != 0
    finally:
        ensemble.save_checkpoint = real
    assert len(list((out / "checkpoints").glob("*.pt"))) == 1 and len(list((out / "checkpoints").glob("*.runs.json"))) == 1
    return out


@pytest.mark.parametrize("kind", FORGERIES, ids=lambda kind: kind.__name__)
def test_a_checkpoints_place_is_refused_when_training_resumes(checkpointed, tmp_path, capsys, kind):
    out = Path(shutil.copytree(checkpointed, tmp_path / "out", symlinks=True))
    (checkpoint,) = (out / "checkpoints").glob("*.pt")
    path = forge(checkpoint, kind, tmp_path / "elsewhere")
    before = listing(out)
    capsys.readouterr()
    status = main(train_command(out))
    refused_naming(status, capsys, path)
    assert listing(out) == before  # (its list of runs too)


def test_a_checkpoint_that_is_no_torch_file_is_refused_in_one_line(checkpointed, tmp_path, capsys):
    out = Path(shutil.copytree(checkpointed, tmp_path / "out"))
    (checkpoint,) = (out / "checkpoints").glob("*.pt")
    checkpoint.write_text(json.dumps({"schema": 1}))
    before = listing(out)
    capsys.readouterr()
    refused_naming(main(train_command(out)), capsys, checkpoint)
    assert listing(out) == before


# ---------------------------------------------------------------------------- evaluate: check, then write
def spoil_agent(results: Path) -> Path:
    """Change a byte of the agent file of the run evaluated last (its SHA-256 is no longer the one recorded)."""
    _, agent = agent_file_of(results, "empathic_dqn")
    data = bytearray(agent.read_bytes())
    data[-20] ^= 0xFF
    agent.write_bytes(bytes(data))
    return agent


def test_evaluate_checks_every_agent_before_writing_one_evaluation(trained, tmp_path, capsys):
    results = Path(shutil.copytree(trained, tmp_path / "results"))
    agent = spoil_agent(results)
    before = listing(results)
    refused_naming(main(["evaluate", str(results), "--episodes", "1", "--no-progress"]), capsys, agent)
    assert listing(results) == before and not (results / "evaluations").exists()


def test_evaluate_removes_the_directories_it_created_when_it_fails(trained, tmp_path, capsys, monkeypatch):
    results = Path(shutil.copytree(trained, tmp_path / "results"))
    before = listing(results)

    def full_disk(path: Path, document: Any) -> Path:
        raise OSError(errno.ENOSPC, f"No space left on device: {path}")

    monkeypatch.setattr(heldout, "write_json_atomic", full_disk)
    assert main(["evaluate", str(results), "--episodes", "1", "--no-progress"]) == 1
    assert main(["evaluate", str(results), "--episodes", "1", "--no-progress", "--out", str(tmp_path / "new" / "out")]) == 1
    assert listing(results) == before and not (results / "evaluations").exists() and not (tmp_path / "new").exists()
    (results / "evaluations").mkdir()
    (results / "evaluations" / "mine.txt").write_text("kept")
    assert main(["evaluate", str(results), "--episodes", "1", "--no-progress"]) == 1
    assert sorted(p.name for p in (results / "evaluations").iterdir()) == ["mine.txt"]  # (only what it created goes)


def test_evaluate_refuses_an_empty_out(trained, tmp_path, capsys, monkeypatch):
    results = Path(shutil.copytree(trained, tmp_path / "results"))
    here = tmp_path / "here"
    here.mkdir()
    monkeypatch.chdir(here)
    assert main(["evaluate", str(results), "--episodes", "1", "--no-progress", "--out", ""]) == 2
    assert "an empty path" in capsys.readouterr().err
    with pytest.raises(ValueError, match="empty path"):
        evaluate_results(results, episodes=1, out_dir="", progress=False)
    assert not list(here.iterdir()) and not (results / "evaluations").exists()


# ---------------------------------------------------------------------------- the bounded reader
class ReadSpy:
    """A file whose reads are counted (in ``read``), otherwise the file it wraps."""

    def __init__(self, handle: Any, read: list[int]) -> None:
        self._handle, self._read = handle, read

    def read(self, size: int = -1) -> bytes:
        data = self._handle.read(size)
        self._read.append(len(data))
        return data

    def __getattr__(self, name: str) -> Any:
        return getattr(self._handle, name)

    def __enter__(self) -> ReadSpy:
        return self

    def __exit__(self, *exc: object) -> None:
        self._handle.close()


def test_a_file_past_its_cap_is_refused_by_its_size_without_reading_it(tmp_path, monkeypatch):
    cap = 64 << 20
    path = tmp_path / "sparse.json"
    with open(path, "wb") as handle:
        handle.truncate(cap + 1)  # (sparse: no block written)
    read: list[int] = []
    real = os.fdopen
    monkeypatch.setattr(limits.os, "fdopen", lambda fd, *args, **kwargs: ReadSpy(real(fd, *args, **kwargs), read))
    with pytest.raises(ValueError, match=re.escape("is larger than 64.0 MB")) as caught:
        read_bounded(path, cap, "result file")
    assert str(path) in str(caught.value) and sum(read) == 0, read
    path.write_bytes(b"{}")
    assert read_bounded(path, cap, "result file") == b"{}"
