"""``analyse tuning-summary --figure`` draws every range a study may hold (and ``tune --param``
takes no range a study may not hold), draws text read from a file as that text (never as
mathtext), refuses a figure past its size bound before anything is drawn, and a study's
``trials_done`` is an int."""

from __future__ import annotations

import json
import struct
import warnings
from collections.abc import Callable
from pathlib import Path
from typing import Any

import pytest
from matplotlib import cbook
from matplotlib.figure import Figure
from matplotlib.text import Text

import leaderboard.tuning_summary as tuning_summary
from baselines.registry import get_method
from empathy_zoo.cli import main
from empathy_zoo.experiment.search_space import parse_param
from empathy_zoo.limits import MAX_FIGURE_PIXELS, MAX_FIGURE_SIDE, MAX_RANGE_END
from empathy_zoo.training.trials_figure import render_importance_png, render_trials_png
from leaderboard.study_file import StudyFileError, check_study
from leaderboard.tuning_summary import render_studies_png

ROOT = Path(__file__).resolve().parents[1]
SHIPPED = ROOT / "docs" / "results" / "methods" / "tuning"
STUDY = SHIPPED / "coexistence_v0" / "dqn" / "study.json"
"""A shipped study: DQN's learning_rate on log:0.0001:0.003, 10 trials (finished and pruned)."""
PNG = b"\x89PNG\r\n\x1a\n"

Change = Callable[[dict[str, Any]], None]


def _document(change: Change | None = None) -> dict[str, Any]:
    document = json.loads(STUDY.read_text())
    if change is not None:
        change(document)
    return document


def _write(root: Path, document: dict[str, Any], where: str = "coexistence_v0/dqn") -> Path:
    path = root / where / "study.json"
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(json.dumps(document))
    return path


def _summary(args: list[str], capsys: Any) -> tuple[int, str, str, list[str]]:
    """Run ``analyse tuning-summary ARGS``: its exit status, stdout, stderr and the warnings it raised."""
    capsys.readouterr()
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        status = main(["analyse", "tuning-summary", *args])
    captured = capsys.readouterr()
    return status, captured.out, captured.err, [str(warning.message) for warning in caught]


def _png_size(path: Path) -> tuple[int, int]:
    """Width and height of a PNG file (its IHDR chunk)."""
    data = path.read_bytes()
    assert data[:8] == PNG
    width, height = struct.unpack(">II", data[16:24])
    return width, height


def _range(spec: str, value: float) -> Change:
    """Give the study's learning_rate the range ``spec`` and every trial (and the best) ``value``."""

    def change(document: dict[str, Any]) -> None:
        document["plan"]["params"]["learning_rate"] = spec
        for trial in document["trials"]:
            if "learning_rate" in trial["params"]:
                trial["params"]["learning_rate"] = value
        document["best"]["params"]["learning_rate"] = value

    return change


def _renamed(name: str) -> Change:
    """Rename the study's parameter learning_rate to ``name``, in its plan, every trial and the best."""

    def change(document: dict[str, Any]) -> None:
        for params in [document["plan"]["params"], document["best"]["params"]] + [t["params"] for t in document["trials"]]:
            if "learning_rate" in params:
                params[name] = params.pop("learning_rate")

    return change


def _labelled(label: str) -> Change:
    return lambda document: document["plan"].__setitem__("label", label)


# ---------------------------------------------------------------------------- 1: every range the checker takes draws
@pytest.mark.parametrize(
    ("spec", "value"),
    [
        ("log:1:1e300", 2.0),
        ("log:1e-300:1e300", 1.0),
        ("log:1e-300:1", 1e-10),
        ("log:1e299:1e300", 5e299),
        ("log:1e-300:2e-300", 1.5e-300),
        ("float:-1e300:1e300", 0.0),
        ("float:1e299:1e300", 5e299),
        ("float:0:1e-300", 0.0),
    ],
)
def test_the_figure_draws_every_range_the_checker_takes(tmp_path: Path, capsys: Any, spec: str, value: float) -> None:
    _write(tmp_path / "studies", _document(_range(spec, value)))
    figure = tmp_path / "figure.png"
    status, out, err, caught = _summary([str(tmp_path / "studies"), "--figure", str(figure)], capsys)
    assert (status, err, caught) == (0, "", [])
    assert f"wrote {figure}" in out and figure.read_bytes()[:8] == PNG


@pytest.mark.parametrize(
    "text",
    [
        f"learning_rate=float:0:{MAX_RANGE_END * 10:g}",
        f"learning_rate=float:{-MAX_RANGE_END * 10:g}:0",
        "learning_rate=log:1e-301:1e-2",
        "learning_rate=log:5e-324:1e-2",
        "batch_size=int:1:1" + "0" * 301,
    ],
    ids=["float HIGH 1e301", "float LOW -1e301", "log LOW 1e-301", "log LOW 5e-324", "int HIGH 10**301"],
)
def test_tune_takes_no_range_a_study_may_not_hold(text: str) -> None:
    with pytest.raises(ValueError, match="--param") as error:
        parse_param(text, get_method("dqn"))
    assert "1e+300" in str(error.value) and "1e-300" in str(error.value)


def test_tune_takes_the_widest_range_a_study_may_hold(tmp_path: Path) -> None:
    spec = parse_param("learning_rate=log:1e-300:1e300", get_method("dqn"))
    assert (spec.low, spec.high) == (1 / MAX_RANGE_END, MAX_RANGE_END)
    document = _document(_range(spec.text.partition("=")[2], 1.0))
    assert check_study(document, tmp_path / "study.json")["plan"]["params"]["learning_rate"] == "log:1e-300:1e+300"


# ---------------------------------------------------------------------------- 2: text from a file is drawn as text
@pytest.mark.parametrize(
    "change",
    [_labelled("$\\foo$"), _renamed("$\\foo$"), _labelled("$x^{$")],
    ids=["plan.label $\\foo$", "a parameter named $\\foo$", "plan.label $x^{$"],
)
def test_a_label_with_mathtext_draws(tmp_path: Path, capsys: Any, change: Change) -> None:
    _write(tmp_path / "studies", _document(change))
    figure = tmp_path / "figure.png"
    status, _, err, _ = _summary([str(tmp_path / "studies"), "--figure", str(figure)], capsys)
    assert (status, err) == (0, "")
    assert figure.read_bytes()[:8] == PNG


def _drawn(text: Text) -> str | None:
    """What ``text`` shows: its string, or ``None`` where Matplotlib draws it as mathtext."""
    shown = text.get_text()
    if not text.get_parse_math():
        return shown
    return None if cbook.is_math_text(shown) else shown.replace("\\$", "$")


def _texts_drawn(monkeypatch: Any, module: Any, draw: Callable[[], bytes]) -> set[str | None]:
    """Every text of the figure ``draw()`` makes (through ``module.Figure``), as drawn."""
    made: list[Figure] = []

    class Recorded(Figure):
        def __init__(self, *args: Any, **kwargs: Any) -> None:
            super().__init__(*args, **kwargs)
            made.append(self)

    monkeypatch.setattr(module, "Figure", Recorded)
    assert draw()[:8] == PNG
    (figure,) = made
    return {_drawn(text) for text in figure.findobj(Text)}


def test_the_summary_figure_draws_dollars_as_dollars(monkeypatch: Any) -> None:
    document = _document(_renamed("$y$"))
    document["plan"]["label"] = "$x$ \\alpha \\$ $"
    texts = _texts_drawn(monkeypatch, tuning_summary, lambda: render_studies_png([document]))
    assert "$x$ \\alpha \\$ $" in texts and "$y$" in texts


def test_the_trials_figures_draw_dollars_as_dollars(monkeypatch: Any) -> None:
    import matplotlib.figure

    document = _document(_labelled("$x$"))
    texts = _texts_drawn(monkeypatch, matplotlib.figure, lambda: render_trials_png(document))
    assert any(text is not None and text.startswith("$x$ on coexistence_v0") for text in texts)
    document = _document(lambda d: d["plan"].__setitem__("params", {"$y$": "float:0:1", "$\\foo$": "float:0:1"}))
    texts = _texts_drawn(monkeypatch, matplotlib.figure, lambda: render_importance_png(document, {"$y$": 0.75, "$\\foo$": 0.25}))
    assert "$y$\n(float:0:1)" in texts and "$\\foo$\n(float:0:1)" in texts


# ---------------------------------------------------------------------------- 3: the figure's size is bounded up front
class _Drawn(Exception):
    """Raised where a figure would be made: the size check let it through."""


def _no_drawing(*args: Any, **kwargs: Any) -> Any:
    raise _Drawn


def _rename_variant(document: dict[str, Any], variant: str) -> None:
    """Name the study's variant ``variant``, its experiment id with it (as ``tune`` names both)."""
    plan = document["plan"]
    plan["experiment"] = variant + plan["experiment"].removeprefix(plan["variant"])
    plan["variant"] = variant


def _variants(counts: list[int]) -> list[dict[str, Any]]:
    """Studies of ``len(counts)`` variants, ``counts[i]`` of variant ``i`` (one document, shared)."""
    studies = []
    for i, count in enumerate(counts):
        document = _document(lambda d, i=i: _rename_variant(d, f"variant_{i:03d}"))
        studies += [document] * count
    return studies


def _most_rows(dpi: int = 110) -> int:
    """The most studies of one variant the figure's side bound lets it draw."""
    return int((MAX_FIGURE_SIDE / dpi - 0.9) / 0.38)


def _most_panels(dpi: int = 110) -> int:
    """The most variants the figure's side bound lets it draw."""
    return int(MAX_FIGURE_SIDE / dpi / 6.2)


@pytest.mark.parametrize(
    "counts",
    [[_most_rows() + 1], [1] * (_most_panels() + 1), [1] * 20 + [60]],
    ids=["too tall", "too wide", "too many pixels"],
)
def test_a_figure_past_its_bound_is_refused_before_it_is_drawn(monkeypatch: Any, counts: list[int]) -> None:
    monkeypatch.setattr(tuning_summary, "Figure", _no_drawing)
    with pytest.raises(ValueError, match=f"--figure: .*{MAX_FIGURE_SIDE:,} px a side and {MAX_FIGURE_PIXELS:,} px in all"):
        render_studies_png(_variants(counts))


@pytest.mark.parametrize("counts", [[_most_rows()], [1] * _most_panels()], ids=["tallest", "widest"])
def test_a_figure_at_its_bound_is_drawn(monkeypatch: Any, counts: list[int]) -> None:
    monkeypatch.setattr(tuning_summary, "Figure", _no_drawing)
    with pytest.raises(_Drawn):
        render_studies_png(_variants(counts))


def test_the_command_refuses_a_figure_past_its_bound_in_one_line(tmp_path: Path, capsys: Any, monkeypatch: Any) -> None:
    monkeypatch.setattr(tuning_summary, "Figure", _no_drawing)
    for i, study in enumerate(_variants([1] * 20 + [60])):
        _write(tmp_path / "studies", study, f"{study['plan']['variant']}/{i:03d}")
    figure = tmp_path / "figure.png"
    status, out, err, _ = _summary([str(tmp_path / "studies"), "--figure", str(figure)], capsys)
    assert (status, out, err.count("\n")) == (2, "", 1) and "Traceback" not in err
    assert (
        err.startswith("empathy-zoo analyse tuning-summary: error: --figure: 80 studies on 21 variants")
        and f"{MAX_FIGURE_PIXELS:,}" in err
    )
    assert not figure.exists()


def test_the_shipped_studies_still_draw(tmp_path: Path, capsys: Any) -> None:
    figure = tmp_path / "studies.png"
    status, _, err, _ = _summary([str(SHIPPED), "--figure", str(figure)], capsys)
    assert (status, err) == (0, "")
    assert _png_size(figure) == _png_size(SHIPPED / "studies.png")


# ---------------------------------------------------------------------------- 4: trials_done is an int
@pytest.mark.parametrize("value", [10.0, True, "10"], ids=repr)
def test_trials_done_is_an_int(tmp_path: Path, value: Any) -> None:
    with pytest.raises(StudyFileError, match="field trials_done: expected an int"):
        check_study(_document(lambda d: d.__setitem__("trials_done", value)), tmp_path / "study.json")
