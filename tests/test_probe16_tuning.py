"""A study file's fields agree with what ``tune`` writes (every trial's ``steps_trained``, always
summed into ``env_steps_trained``; a choice's value one of its choices; a trial's values its curve's;
a finished trial trained to the budget's last step; ``best`` set once a trial finished; the schema
``tune`` writes; no value for a trial that did not finish; every parameter of the plan), a range's
ends bounded so the figure can draw them, and ``--figure`` never overwrites a study it reads."""

from __future__ import annotations

import json
import os
from pathlib import Path
from typing import Any

import pytest

from empathy_zoo.cli import main
from empathy_zoo.training.study_plan import curve_value
from leaderboard.study_file import StudyFileError, check_study

ROOT = Path(__file__).resolve().parents[1]
STUDY = ROOT / "docs" / "results" / "methods" / "tuning" / "coexistence_v0" / "dqn" / "study.json"
"""A shipped study: DQN's learning_rate on log:0.0001:0.003, survival over the curve, 10 trials
(finished and pruned), tuning seeds 10000 and 10001, 50,000 steps evaluated every 10,000."""


def _document(change: Any = None) -> dict[str, Any]:
    document = json.loads(STUDY.read_text())
    if change is not None:
        change(document)
    return document


def _study_at(tmp_path: Path, change: Any = None) -> Path:
    """A copy of :data:`STUDY` under ``tmp_path/study/``, edited by ``change(document)``; its path."""
    path = tmp_path / "study" / "study.json"
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(json.dumps(_document(change)))
    return path


def _refused_by_the_command(tmp_path: Path, capsys: Any, args: list[str], *names: str) -> str:
    """Run ``analyse tuning-summary ARGS``: exit 2, nothing on stdout, one line on stderr holding ``names``."""
    capsys.readouterr()
    assert main(["analyse", "tuning-summary", *args]) == 2
    captured = capsys.readouterr()
    assert not captured.out and captured.err.count("\n") == 1 and "Traceback" not in captured.err
    for name in names:
        assert name in captured.err
    return captured.err


def _finished(document: dict[str, Any]) -> list[dict[str, Any]]:
    return [trial for trial in document["trials"] if trial["state"] == "COMPLETE"]


def _not_best(document: dict[str, Any]) -> dict[str, Any]:
    """A finished trial that is not the best."""
    return next(trial for trial in _finished(document) if trial["number"] != document["best"]["number"])


def _pruned(document: dict[str, Any]) -> dict[str, Any]:
    return next(trial for trial in document["trials"] if trial["state"] == "PRUNED")


def _seeds(document: dict[str, Any]) -> int:
    return len(document["plan"]["tuning_seeds"])


# ---------------------------------------------------------------------------- 1: steps_trained always summed
def _no_steps_trained(document: dict[str, Any]) -> None:
    for trial in document["trials"]:
        del trial["steps_trained"]
    document["env_steps_trained"] = 12345


def _one_without_steps_trained(document: dict[str, Any]) -> None:
    del _pruned(document)["steps_trained"]  # (env_steps_trained still the sum of them all)


@pytest.mark.parametrize(
    "change", [_no_steps_trained, _one_without_steps_trained], ids=["none has steps_trained", "one lacks it"]
)
def test_every_trial_holds_its_steps_trained(tmp_path: Path, capsys: Any, change: Any) -> None:
    path = _study_at(tmp_path, change)
    index = next(i for i, trial in enumerate(json.loads(path.read_text())["trials"]) if "steps_trained" not in trial)
    _refused_by_the_command(tmp_path, capsys, [str(tmp_path)], str(path), f"trials[{index}].steps_trained")


def test_env_steps_trained_is_always_the_trials_sum(tmp_path: Path) -> None:
    document = _document(lambda d: d.__setitem__("env_steps_trained", d["env_steps_trained"] - 2 * _seeds(d)))
    with pytest.raises(StudyFileError, match=r"field env_steps_trained: expected"):
        check_study(document, tmp_path / "study.json")


# ---------------------------------------------------------------------------- 2: --figure never a study
def test_the_figure_is_never_written_over_a_study(tmp_path: Path, capsys: Any) -> None:
    path = _study_at(tmp_path)
    before = path.read_bytes()
    _refused_by_the_command(tmp_path, capsys, [str(tmp_path), "--figure", str(path)], str(path), ".png")
    link = tmp_path / "figure.png"
    link.symlink_to(path)
    _refused_by_the_command(tmp_path, capsys, [str(tmp_path), "--figure", str(link)], str(link))
    hard = tmp_path / "elsewhere.png"
    os.link(path, hard)  # (the same file under a .png name)
    _refused_by_the_command(tmp_path, capsys, [str(tmp_path), "--figure", str(hard)], str(hard), "is no tuning-summary figure")
    assert path.read_bytes() == before and hard.read_bytes() == before


def test_the_figure_is_a_png_file_name(tmp_path: Path, capsys: Any) -> None:
    _study_at(tmp_path)
    out = tmp_path / "figure.svg"
    _refused_by_the_command(tmp_path, capsys, [str(tmp_path), "--figure", str(out)], str(out), ".png")
    directory = tmp_path / "figures.png"
    directory.mkdir()
    _refused_by_the_command(tmp_path, capsys, [str(tmp_path), "--figure", str(directory)], str(directory))
    assert not out.exists()
    good = tmp_path / "figure.png"
    assert main(["analyse", "tuning-summary", str(tmp_path), "--figure", str(good)]) == 0
    assert good.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n" and f"wrote {good}" in capsys.readouterr().out


# ---------------------------------------------------------------------------- 3: fields tune writes agree
def _choice_outside(document: dict[str, Any]) -> None:
    document["plan"]["params"]["learning_rate"] = "choice:0.001,0.002"
    for trial in document["trials"]:
        trial["params"]["learning_rate"] = 0.5
    document["best"]["params"]["learning_rate"] = 0.5


def _short_finished(document: dict[str, Any]) -> None:
    trial = _not_best(document)
    trial["curve"] = trial["curve"][:1]
    trial["steps_trained"] = trial["curve"][-1]["step"]
    document["env_steps_trained"] = sum(t["steps_trained"] for t in document["trials"]) * _seeds(document)


def _pruned_with_value(document: dict[str, Any]) -> None:
    _not_best(document)["state"] = "PRUNED"


def _param_missing(document: dict[str, Any]) -> None:
    _not_best(document)["params"] = {}


FORGERIES = {
    "choice value not a choice": (_choice_outside, r"trials\[0\]\.params\.learning_rate"),
    "value not its curve's": (lambda d: _not_best(d).__setitem__("value", 1.0), r"trials\[\d+\]\.value"),
    "last value not its curve's": (lambda d: _not_best(d).__setitem__("last_value", 3.0), r"trials\[\d+\]\.last_value"),
    "pruned last value not its curve's": (
        lambda d: _pruned(d).__setitem__("last_value", _pruned(d)["last_value"] + 1.0),
        r"trials\[\d+\]\.last_value",
    ),
    "finished short of the budget": (_short_finished, r"trials\[\d+\]\.curve"),
    "best null while a trial finished": (lambda d: d.__setitem__("best", None), r"best"),
    "schema not tune's": (lambda d: d.__setitem__("schema", 99), r"schema"),
    "pruned trial with a value": (_pruned_with_value, r"trials\[\d+\]\.value"),
    "a parameter missing": (_param_missing, r"trials\[\d+\]\.params\.learning_rate"),
}
"""Each forgery of the shipped study: ``(how, the field its refusal names)``."""


@pytest.mark.parametrize("name", list(FORGERIES))
def test_a_study_tune_could_not_write_is_refused(tmp_path: Path, name: str) -> None:
    change, field = FORGERIES[name]
    check_study(_document(), STUDY)  # (as shipped)
    with pytest.raises(StudyFileError, match=rf"field {field}: expected"):
        check_study(_document(change), tmp_path / "study.json")


def test_the_command_names_the_file_and_field_of_a_choice_outside(tmp_path: Path, capsys: Any) -> None:
    path = _study_at(tmp_path, _choice_outside)
    _refused_by_the_command(tmp_path, capsys, [str(tmp_path)], str(path), "trials[0].params.learning_rate")


def _choice_of(values: list[Any], spec: str) -> Any:
    def change(document: dict[str, Any]) -> None:
        document["plan"]["params"]["learning_rate"] = spec
        for i, trial in enumerate(document["trials"]):
            trial["params"]["learning_rate"] = values[i % len(values)]
        best = next(t for t in document["trials"] if t["number"] == document["best"]["number"])
        document["best"]["params"] = dict(best["params"])

    return change


@pytest.mark.parametrize(
    ("values", "spec"),
    [
        ([0.001, 0.002], "choice:0.001,0.002"),  # (numbers, as tune reads a float field's choices)
        ([1.0, 2.0], "choice:1,2"),  # (a number, compared as a number)
        ([True, False], "choice:true,false"),
        (["closest", "min"], "choice:closest,min"),  # (text)
        (["0.5", "min"], "choice:0.5,min"),  # (a text field's value that reads like a number)
    ],
    ids=["floats", "whole floats", "booleans", "text", "text like a number"],
)
def test_a_choice_value_among_its_choices_reads(tmp_path: Path, values: list[Any], spec: str) -> None:
    assert check_study(_document(_choice_of(values, spec)), tmp_path / "study.json")["trials"]


@pytest.mark.parametrize(
    ("values", "spec"),
    [([True, 0.001], "choice:0.001,0.002"), (["0.001"], "choice:true,false"), ([1, 2], "choice:true,false")],
    ids=["a boolean among numbers", "text among booleans", "a number among booleans"],
)
def test_a_choice_value_of_another_type_is_refused(tmp_path: Path, values: list[Any], spec: str) -> None:
    with pytest.raises(StudyFileError, match=r"field trials\[0\]\.params\.learning_rate: expected one of"):
        check_study(_document(_choice_of(values, spec)), tmp_path / "study.json")


def test_what_tune_writes_reads(tmp_path: Path) -> None:
    from empathy_zoo.training import tuning
    from leaderboard import study_file

    assert tuning.STUDY_SCHEMA == study_file.STUDY_SCHEMA
    assert check_study(_document(lambda d: d.pop("schema")), tmp_path / "study.json")  # (a study before schemas)

    def interrupted(document: dict[str, Any]) -> None:  # (stopped between its ask and its parameters)
        document["trials"].append(
            {
                "number": len(document["trials"]),
                "state": "INTERRUPTED",
                "params": {},
                "value": None,
                "last_value": None,
                "steps_trained": 0,
                "curve": [],
                "wall_time_s": None,
            }
        )

    assert check_study(_document(interrupted), tmp_path / "study.json")
    document = _document()
    for trial in document["trials"]:  # (the shipped values are exactly their curves')
        if trial["curve"]:
            values = [point["value"] for point in trial["curve"]]
            assert trial["last_value"] == curve_value(values, document["plan"]["objective"]["over"])


# ---------------------------------------------------------------------------- 4: a range the figure can draw
@pytest.mark.parametrize(
    "spec", ["float:-1e308:1e308", "log:1e-5:1e308", "float:0:1.7e308", "log:1e-320:0.003", "float:0.001:0.001"]
)
def test_a_range_the_figure_cannot_draw_is_refused(tmp_path: Path, capsys: Any, spec: str) -> None:
    path = _study_at(tmp_path, lambda d: d["plan"]["params"].__setitem__("learning_rate", spec))
    figure = tmp_path / "figure.png"
    _refused_by_the_command(tmp_path, capsys, [str(tmp_path), "--figure", str(figure)], str(path), "plan.params.learning_rate")
    assert not figure.exists()


@pytest.mark.parametrize(
    ("change", "field"),
    [
        (lambda d: d.__setitem__("trials_done", d["trials_done"] + 1), "trials_done"),
        (lambda d: d["plan"]["params"].__setitem__("learning_rate", "int:1.5:3"), "plan.params.learning_rate"),
    ],
    ids=["trials_done not its trials'", "an int range of no whole ends"],
)
def test_a_study_s_count_of_trials_and_its_int_ranges_agree(tmp_path: Path, change: Any, field: str) -> None:
    with pytest.raises(StudyFileError, match=rf"field {field}: expected"):
        check_study(_document(change), tmp_path / "study.json")
