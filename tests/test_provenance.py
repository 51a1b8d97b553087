"""The recorded version is written in one place; the recorded commit says whether the checkout had
uncommitted changes to tracked files."""

from __future__ import annotations

import importlib.metadata
import shutil
import subprocess
import tomllib
from pathlib import Path

import pytest

import empathy_zoo
from empathy_zoo import _version
from empathy_zoo.provenance import checkout_commit, package_version

needs_git = pytest.mark.skipif(shutil.which("git") is None, reason="needs git")
ROOT = Path(__file__).resolve().parent.parent


def git(directory, *args):
    return subprocess.run(["git", "-C", str(directory), *args], check=True, capture_output=True, text=True).stdout.strip()


@needs_git
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


@needs_git
def test_outside_a_checkout_there_is_no_commit(tmp_path):
    assert checkout_commit(tmp_path) is None


def test_the_version_is_written_in_one_place():
    project = tomllib.loads((ROOT / "pyproject.toml").read_text())
    assert "version" not in project["project"] and project["project"]["dynamic"] == ["version"]
    assert project["tool"]["setuptools"]["dynamic"]["version"] == {"attr": "empathy_zoo._version.__version__"}
    assert package_version() == empathy_zoo.__version__ == _version.__version__
    assert importlib.metadata.version("empathy-zoo") == _version.__version__, "reinstall: pip install -e ."
