"""``reproduction --sensitivity DIR`` and ``--coexistence-sensitivity DIR`` take a sweep of two
conditions or more, never the results directory (or the other sweep) again, and state what made
their runs as the files show it: before, a directory of one condition was accepted, even the
results directory itself, and the page claimed it was "produced by" a profile's command."""

from __future__ import annotations

import shutil
from pathlib import Path

import pytest

from empathy_zoo.cli import main

RESULTS = Path(__file__).resolve().parents[1] / "docs" / "results"


@pytest.fixture()
def quick(tmp_path: Path) -> Path:
    shutil.copytree(RESULTS / "quick" / "runs", tmp_path / "q" / "runs")
    shutil.copytree(RESULTS / "quick" / "runs", tmp_path / "q2" / "runs")
    return tmp_path


@pytest.mark.parametrize(
    ("options", "words"),
    [
        (["--sensitivity", "q"], "--sensitivity q is given twice (as the results directory q too)"),
        (["--sensitivity", "q/runs"], "--sensitivity q/runs is given twice (as the results directory q too)"),
        (["--coexistence-sensitivity", "q/runs/."], "given twice (as the results directory q too)"),
        (
            ["--sensitivity", "q2", "--coexistence-sensitivity", "q2/runs"],
            "--coexistence-sensitivity q2/runs is given twice (as --sensitivity q2 too)",
        ),
        (["--sensitivity", "q2"], "these results hold 1 fidelity condition(s) of sharing_v0"),
        (["--coexistence-sensitivity", "q2"], "these results hold 1 condition(s) of coexistence_v0 (coexistence_v0)"),
    ],
)
def test_a_sweep_that_compares_nothing_is_refused(
    quick: Path, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch, options: list[str], words: str
) -> None:
    monkeypatch.chdir(quick)
    before = sorted(quick.rglob("*"))
    capsys.readouterr()
    assert main(["reproduction", "q", *options, "--out", "r.md"]) == 2
    out, err = capsys.readouterr()
    assert out == "" and err.count("\n") == 1 and words in err, err
    assert sorted(quick.rglob("*")) == before  # (nothing written)


def test_a_sensitivity_section_names_its_files_not_a_command_they_do_not_record() -> None:
    from empathy_zoo.cli.sweep import _sweep_source

    text = _sweep_source("some/dir", "sharing_sensitivity")
    assert text.startswith("the result files in some/dir (")  # (shown in a code block: no Markdown in it)
    assert "(empathy-zoo reproduce --profile sharing_sensitivity --out some/dir trains such a sweep)" in text
