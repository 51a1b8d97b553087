"""A disk that fills while a command writes its files: the line names the file (or folder) it could
not write, the exit status is 1 (a machine failure, not a refusal), and ``analyse separation``
writes its table's pair of files whole or not at all. The full disk is simulated: ``os.fsync`` (or
the journal's append) raises ``ENOSPC`` at the chosen call; nothing is mounted."""

from __future__ import annotations

import errno
import json
import os
from collections.abc import Callable
from pathlib import Path
from typing import Any

import pytest

from empathy_zoo import atomic
from empathy_zoo.cli import main

ROOT = Path(__file__).resolve().parents[1]
SHIPPED = ROOT / "docs" / "results" / "separation"
SEPARATION = ["analyse", "separation", "coexistence_v0", "size=5", "view=3", "max_cycles=3"]
"""The command of a table (:func:`_shipped_tables` stands in for computing it)."""


@pytest.fixture
def _shipped_tables(monkeypatch: pytest.MonkeyPatch) -> None:
    """``analyse separation`` gives a shipped table (of ``max_cycles`` steps, as asked) instead of
    computing one: what is tested is how its files are written."""
    from dataclasses import replace

    from baselines import separation_render

    table = separation_render.from_json((SHIPPED / "coexistence_v0.json").read_text(encoding="utf-8"))

    def model(env: str, **kwargs: Any) -> dict[str, Any]:
        return kwargs

    monkeypatch.setattr(separation_render, "tabular_model", model)
    monkeypatch.setattr(separation_render, "separation_table", lambda kwargs: replace(table, max_cycles=kwargs["max_cycles"]))


REAL_FSYNC = os.fsync


def _full_disk() -> OSError:
    return OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))


def _fsync_fails_at(monkeypatch: pytest.MonkeyPatch, call: int) -> None:
    """Make the ``call``-th ``os.fsync`` from now on (1: the first) raise ``ENOSPC``, as a full disk does."""
    calls = {"n": 0}

    def fsync(fd: int) -> None:
        calls["n"] += 1
        if calls["n"] == call:
            raise _full_disk()
        REAL_FSYNC(fd)

    monkeypatch.setattr(os, "fsync", fsync)


def _files(directory: Path) -> dict[str, bytes]:
    return {path.name: path.read_bytes() for path in sorted(directory.iterdir())}


# --------------------------------------------------------------------------- analyse separation
@pytest.mark.usefixtures("_shipped_tables")
def test_separation_writes_both_files_or_neither(tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys) -> None:
    out = tmp_path / "sep"
    _fsync_fails_at(monkeypatch, 2)  # (room for the JSON only)
    assert main([*SEPARATION, "--out", str(out)]) == 1
    captured = capsys.readouterr()
    assert captured.out == ""  # (no "wrote" line)
    assert captured.err == (
        f"empathy-zoo: error: cannot write {out / 'coexistence_v0.md'} (No space left on device): coexistence_v0.json and "
        f"coexistence_v0.md in {out} are as they were; free space or give another --out\n"
    )
    assert _files(out) == {}  # (no JSON without its page, no temporary file left)


@pytest.mark.usefixtures("_shipped_tables")
def test_separation_keeps_an_older_pair_whole_when_the_disk_fills(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys
) -> None:
    out = tmp_path / "sep"
    assert main([*SEPARATION, "--out", str(out)]) == 0
    assert capsys.readouterr().out == f"{out / 'coexistence_v0.json'}\n{out / 'coexistence_v0.md'}\n"
    before = _files(out)
    _fsync_fails_at(monkeypatch, 2)
    assert main([*SEPARATION[:-1], "max_cycles=4", "--out", str(out)]) == 1
    assert capsys.readouterr().err.count("\n") == 1
    assert _files(out) == before  # (the older table's JSON still beside its own page)
    monkeypatch.setattr(os, "fsync", REAL_FSYNC)  # (room again)
    assert main([*SEPARATION[:-1], "max_cycles=4", "--out", str(out)]) == 0
    assert _files(out) != before and sorted(_files(out)) == ["coexistence_v0.json", "coexistence_v0.md"]


@pytest.mark.usefixtures("_shipped_tables")
def test_separation_as_a_module_says_a_full_disk_in_one_line_with_status_1(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys
) -> None:
    from baselines.separation_render import module_main

    _fsync_fails_at(monkeypatch, 1)
    assert module_main([*SEPARATION[2:], "--out", str(tmp_path)]) == 1
    err = capsys.readouterr().err
    assert err.startswith(f"python -m baselines.separation_render: error: cannot write {tmp_path / 'coexistence_v0.json'} (")
    assert err.count("\n") == 1 and _files(tmp_path) == {}


def test_write_all_atomic_removes_its_temporary_files_and_names_the_file(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    first, second = tmp_path / "a.json", tmp_path / "a.md"
    first.write_bytes(b"old a\n")
    _fsync_fails_at(monkeypatch, 2)
    with pytest.raises(OSError) as raised:
        atomic.write_all_atomic([(first, b"new a\n"), (second, b"new b\n")])
    assert raised.value.errno == errno.ENOSPC and raised.value.filename == str(second)
    assert _files(tmp_path) == {"a.json": b"old a\n"}
    monkeypatch.undo()
    assert atomic.write_all_atomic([(first, b"new a\n"), (second, b"new b\n")]) == [first, second]
    assert _files(tmp_path) == {"a.json": b"new a\n", "a.md": b"new b\n"}


# ------------------------------------------------------------------------ analyse discrimination
def test_discrimination_names_its_page_when_the_disk_is_full(tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys) -> None:
    page = tmp_path / "d" / "D.md"
    _fsync_fails_at(monkeypatch, 1)
    assert main(["analyse", "discrimination", str(ROOT / "docs" / "results" / "separation"), "--out", str(page)]) == 1
    captured = capsys.readouterr()
    assert captured.out == ""
    assert captured.err == (
        f"empathy-zoo analyse discrimination: error: cannot write {page} (No space left on device): "
        "nothing half-written is left; free space or give another --out\n"
    )
    assert not page.exists() and list(page.parent.iterdir()) == []


# ------------------------------------------------------------------------ analyse tuning-summary
def test_tuning_summary_says_a_full_disk_as_a_machine_failure_naming_the_figure(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys
) -> None:
    from test_tuning_summary import STUDIES

    studies = tmp_path / "studies"
    for study in STUDIES:
        where = studies / study["plan"]["variant"] / "dqn"
        where.mkdir(parents=True)
        (where / "study.json").write_text(json.dumps(study))
    figure = tmp_path / "d" / "t.png"
    _fsync_fails_at(monkeypatch, 1)
    assert main(["analyse", "tuning-summary", str(studies), "--figure", str(figure)]) == 1
    captured = capsys.readouterr()
    assert captured.err == (
        f"empathy-zoo analyse tuning-summary: error: cannot write {figure} (No space left on device): "
        "nothing half-written is left; free space or give another --figure\n"
    )
    assert "wrote" not in captured.out and not figure.exists() and list(figure.parent.iterdir()) == []


# ---------------------------------------------------------------------------------------- tune
def _journal_fails_at(monkeypatch: pytest.MonkeyPatch, call: int) -> None:
    """Make the ``call``-th append to a study's journal raise ``ENOSPC`` (and every one after it:
    the disk stays full)."""
    from optuna.storages.journal import JournalFileBackend

    real: Callable[..., Any] = JournalFileBackend.append_logs
    calls = {"n": 0}

    def append_logs(self: Any, logs: list[dict[str, Any]]) -> None:
        calls["n"] += 1
        if calls["n"] >= call:
            raise _full_disk()
        real(self, logs)

    monkeypatch.setattr(JournalFileBackend, "append_logs", append_logs)


def _tiny_study(tmp_path: Path) -> tuple[Path, Path, Callable[..., int]]:
    """The tiny tuning sweep written into ``tmp_path``, the study's folder, and what runs ``tune``."""
    pytest.importorskip("optuna")
    from helpers_sweeps import TUNE_SWEEP
    from helpers_tune import run_tune

    sweep = tmp_path / "tiny.toml"
    sweep.write_text(TUNE_SWEEP)
    return sweep, tmp_path / "tun", run_tune


def test_tune_names_the_journal_when_the_disk_fills_mid_study_and_resumes(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys
) -> None:
    sweep, out, run_tune = _tiny_study(tmp_path)
    _journal_fails_at(monkeypatch, 18)  # (the study and its first trial stored; the disk fills in the second)
    assert run_tune(sweep, out, 2) == 1
    err = capsys.readouterr().err
    assert err.endswith(
        f"empathy-zoo: error: cannot write {out / 'study.journal'} (No space left on device); free space, then run the "
        "same command again to resume the study (the trials told so far are kept)\n"
    ), err
    assert err.count("\n") == 1 and json.loads((out / "study.json").read_text())["trials_done"] == 1
    monkeypatch.undo()
    assert run_tune(sweep, out, 2) == 0  # (the study as it was left resumes)
    assert json.loads((out / "study.json").read_text())["trials_done"] == 2


def test_tune_names_its_folder_for_a_file_whose_write_says_no_name(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys
) -> None:
    sweep, out, run_tune = _tiny_study(tmp_path)
    from empathy_zoo.training import tuning

    def full(path: Any, payload: Any) -> Path:
        raise _full_disk()

    monkeypatch.setattr(tuning, "write_json_atomic", full)  # (study.json: its write names no file)
    assert run_tune(sweep, out, 1) == 1
    err = capsys.readouterr().err
    assert err.endswith(
        f"empathy-zoo: error: cannot write {out} (No space left on device); free space, then run the "
        "same command again to resume the study (the trials told so far are kept)\n"
    ), err
