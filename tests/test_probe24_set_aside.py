"""``train`` and ``reproduce`` remove only the set-aside files they made (``<name>.superseded-<pid>-<mark>``
of this process or of one no longer alive, regular files): a user's ``<run id>.agent.pt.superseded``
backup, a FIFO, a link or a directory of such a name is left alone, and nothing is refused late."""

from __future__ import annotations

import os
from pathlib import Path

from test_probe24_logs import TRAIN

from empathy_zoo.cli import main
from empathy_zoo.training.set_aside import settle_superseded


def _dead_pid() -> int:
    """A process id no live process has (a child that has exited and been reaped)."""
    pid = os.fork()
    if pid == 0:
        os._exit(0)
    os.waitpid(pid, 0)
    return pid


def test_a_users_files_named_like_set_aside_ones_survive_a_train(tmp_path: Path, capsys) -> None:
    out = tmp_path / "out"
    assert main([*TRAIN, "--out", str(out)]) == 0
    (result,) = (out / "runs").glob("*.json")
    run = result.with_suffix("")
    backup = Path(f"{run}.agent.pt.superseded")
    backup.write_text("my backup\n", encoding="utf-8")
    os.mkfifo(f"{run}.json.superseded")
    victim = tmp_path / "victim.txt"
    victim.write_text("mine\n", encoding="utf-8")
    os.symlink(victim, f"{run}.agent.zip.superseded")
    os.mkdir(f"{run}.json.superseded-1-0123abcd")  # (our form, but a directory: no file of ours)
    before = sorted(p.name for p in (out / "runs").iterdir())
    assert main([*TRAIN, "--out", str(out)]) == 0  # (the same run: nothing trains; set-aside files are settled)
    assert main([*[a if a != "0" else "1" for a in TRAIN], "--out", str(out)]) == 0  # (seed 1: a run trains)
    after = sorted(p.name for p in (out / "runs").iterdir())
    assert set(before) <= set(after), "nothing of the user's is removed"
    assert backup.read_text(encoding="utf-8") == "my backup\n" and victim.read_text(encoding="utf-8") == "mine\n"


def test_a_set_aside_file_of_a_process_no_longer_alive_is_settled_and_a_live_ones_is_not(tmp_path: Path) -> None:
    runs = tmp_path / "runs"
    runs.mkdir()
    (runs / "r__s0.json").write_text("{}", encoding="utf-8")  # (its run has a new result file)
    dead = runs / f"r__s0.json.superseded-{_dead_pid()}-0123abcd"
    live = runs / f"r__s0.agent.pt.superseded-{os.getppid()}-0123abcd"
    for path in (dead, live):
        path.write_text("old\n", encoding="utf-8")
    settle_superseded(runs)
    assert not dead.exists() and live.exists()
