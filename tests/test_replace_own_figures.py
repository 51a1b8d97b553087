"""The suite replaces only a figure it wrote for that purpose: ``analyse tuning-summary --figure``,
``tune``'s ``trials.png`` and ``watch --gif`` refuse a user's image and a leaderboard's figure in
one line (the file unchanged), and each replaces the figure it wrote itself when run again."""

from __future__ import annotations

import io
import json
import shutil
from pathlib import Path

import pytest
from helpers_sweeps import TUNE_SWEEP
from helpers_tune import run_tune, snapshot, tiny_study
from PIL import Image
from test_tuning_summary import STUDIES

from empathy_zoo.cli import main

DOCS = Path(__file__).resolve().parents[1] / "docs" / "results"
LEADERBOARD_PNG = DOCS / "sharing_sensitivity" / "figures" / "sharing_centre_count_walk_equality.png"
"""A figure a shipped leaderboard drew (a real PNG the suite wrote, for another purpose)."""
LEADERBOARD_GIF = DOCS / "paper" / "figures" / "sharing_v0_dqn_equality_episode.gif"
"""An episode GIF a shipped leaderboard made (a real GIF the suite wrote, for another purpose)."""
QUICK = DOCS / "quick"
RUN = "coexistence_v0__dqn_harm_penalty-684a7c7f__s0"
"""A shipped run of ``QUICK`` that kept its agent (what ``watch`` plays)."""


def _image(fmt: str) -> bytes:
    """A user's own small image (no mark of the suite's), seeded: always the same bytes."""
    buffer = io.BytesIO()
    Image.new("RGB", (8, 8), (10, 120, 200)).save(buffer, format=fmt)
    return buffer.getvalue()


def _refused(argv: list[str], path: Path, capsys: pytest.CaptureFixture[str], kind: str) -> None:
    """``empathy-zoo ARGV`` exits 2 with one line naming ``path`` as no ``kind`` figure, ``path`` unchanged."""
    before = path.read_bytes()
    capsys.readouterr()
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1, err
    assert f"{path} exists and is no {kind} figure this suite wrote: move it away or choose another path" in err
    assert path.read_bytes() == before


def _studies(root: Path) -> Path:
    for k, study in enumerate(STUDIES[:1]):
        (root / f"s{k}").mkdir(parents=True)
        (root / f"s{k}" / "study.json").write_text(json.dumps(study), encoding="utf-8")
    return root


@pytest.mark.parametrize("source", ["user", "leaderboard"])
def test_tuning_summary_refuses_an_image_it_did_not_write(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], source: str
) -> None:
    root = _studies(tmp_path / "studies")
    figure = tmp_path / "picture.png"
    figure.write_bytes(_image("PNG") if source == "user" else LEADERBOARD_PNG.read_bytes())
    _refused(["analyse", "tuning-summary", str(root), "--figure", str(figure)], figure, capsys, "tuning-summary")


def test_tuning_summary_replaces_its_own_figure(tmp_path: Path) -> None:
    from empathy_zoo.names import PNG_OPENING, TUNING_SUMMARY_MARK, figure_marker

    root = _studies(tmp_path / "studies")
    figure = tmp_path / "studies.png"
    assert main(["analyse", "tuning-summary", str(root), "--figure", str(figure)]) == 0
    first = figure.read_bytes()
    assert figure_marker(PNG_OPENING, TUNING_SUMMARY_MARK) in first
    assert main(["analyse", "tuning-summary", str(root), "--figure", str(figure)]) == 0
    assert figure.read_bytes() == first


@pytest.mark.parametrize("source", ["user", "leaderboard"])
def test_tune_refuses_a_trials_png_it_did_not_write_and_writes_nothing(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], source: str
) -> None:
    sweep = tmp_path / "tiny.toml"
    sweep.write_text(TUNE_SWEEP)
    out = tmp_path / "study"
    out.mkdir()
    (out / "trials.png").write_bytes(_image("PNG") if source == "user" else LEADERBOARD_PNG.read_bytes())
    before = snapshot(out)
    capsys.readouterr()
    assert run_tune(sweep, out, 1) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1, err
    assert f"{out / 'trials.png'} exists and is no trials figure this suite wrote" in err
    assert snapshot(out) == before


def test_tune_replaces_its_own_trials_png_and_an_older_unmarked_one_beside_its_study(tmp_path: Path) -> None:
    from empathy_zoo.names import PNG_OPENING, TRIALS_MARK, figure_marker

    sweep, out = tiny_study(tmp_path, 1)
    marked = (out / "trials.png").read_bytes()
    assert figure_marker(PNG_OPENING, TRIALS_MARK) in marked
    elsewhere = tmp_path / "elsewhere"  # (its own figure, without a study beside it: replaced)
    elsewhere.mkdir()
    (elsewhere / "trials.png").write_bytes(marked)
    assert run_tune(sweep, elsewhere, 1) == 0
    (out / "trials.png").write_bytes(_image("PNG"))  # (as an older version left it: a PNG with no mark, beside its study)
    assert run_tune(sweep, out, 2) == 0
    assert figure_marker(PNG_OPENING, TRIALS_MARK) in (out / "trials.png").read_bytes()


@pytest.mark.parametrize("source", ["user", "leaderboard"])
def test_watch_refuses_a_gif_it_did_not_write(tmp_path: Path, capsys: pytest.CaptureFixture[str], source: str) -> None:
    gif = tmp_path / "episode.gif"
    gif.write_bytes(_image("GIF") if source == "user" else LEADERBOARD_GIF.read_bytes())
    _refused(["watch", RUN, "--dir", str(QUICK), "--episodes", "1", "--gif", str(gif)], gif, capsys, "watch GIF")


def test_watch_replaces_its_own_gif(tmp_path: Path) -> None:
    from empathy_zoo.names import GIF_OPENING, WATCH_GIF_MARK, figure_marker

    results = tmp_path / "quick"
    shutil.copytree(QUICK, results)
    gif = tmp_path / "episode.gif"
    argv = ["watch", RUN, "--dir", str(results), "--episodes", "1", "--gif", str(gif), "--gif-steps", "3"]
    assert main(argv) == 0
    first = gif.read_bytes()
    assert figure_marker(GIF_OPENING, WATCH_GIF_MARK) in first
    assert main(argv) == 0
    assert gif.read_bytes() == first
