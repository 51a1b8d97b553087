"""The recorded commit says whether the checkout had uncommitted changes to tracked files."""

from __future__ import annotations

import shutil
import subprocess

import pytest

from empathy_zoo.provenance import checkout_commit

pytestmark = pytest.mark.skipif(shutil.which("git") is None, reason="needs git")


def git(directory, *args):
    return subprocess.run(["git", "-C", str(directory), *args], check=True, capture_output=True, text=True).stdout.strip()


def test_the_commit_carries_a_dirty_flag(tmp_path):
    git(tmp_path, "init", "-q")
    (tmp_path / "module.py").write_text("x = 1\n")
    git(tmp_path, "add", "module.py")
    git(tmp_path, "-c", "user.name=t", "-c", "user.email=t@t", "commit", "-q", "-m", "first")
    head = git(tmp_path, "rev-parse", "--short", "HEAD")
    assert checkout_commit(tmp_path) == head
    (tmp_path / "notes.txt").write_text("untracked files do not change the code that runs\n")
    assert checkout_commit(tmp_path) == head
    (tmp_path / "module.py").write_text("x = 2\n")
    assert checkout_commit(tmp_path) == f"{head}-dirty"
    git(tmp_path, "add", "module.py")  # staged but not committed: still not the commit
    assert checkout_commit(tmp_path) == f"{head}-dirty"


def test_outside_a_checkout_there_is_no_commit(tmp_path):
    assert checkout_commit(tmp_path) is None
