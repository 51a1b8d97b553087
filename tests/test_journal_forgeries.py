"""A forged tuning journal (``study.journal``: a file anyone may hand over) is refused before
anything is trained or written: one line ``empathy-zoo: error: …`` naming the journal and the
line, exit status 2, and the journal and the output directory byte for byte as they were.

Every forgery edits one line of a genuine journal: a study of two trials, the second resumed
(two 300-step trials of one tuning seed, the smallest budget of tests/test_tune.py)."""

from __future__ import annotations

import json
import re
import shutil
from collections.abc import Callable
from pathlib import Path
from typing import Any

import pytest

pytest.importorskip("optuna")

from helpers_sweeps import TUNE_PARAMS, TUNE_SWEEP
from helpers_tune import run_tune, snapshot, tiny_plan, tiny_study

from empathy_zoo.training.tuning import JOURNAL_FILE, check_journal

SWEEP = TUNE_SWEEP

PARAMS = TUNE_PARAMS


def _tune(sweep: Path, out: Path, trials: int, params: list[str] = PARAMS) -> int:
    return run_tune(sweep, out, trials, params=params)


@pytest.fixture(scope="module")
def genuine(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, Path]:
    """``(sweep file, study directory)`` of a genuine study: one trial, then a second resumed."""
    return tiny_study(tmp_path_factory.mktemp("genuine"), 1, 2)


_snapshot = snapshot


Entry = dict[str, Any]


def _nth(op_code: int, n: int = 0, has: str | None = None) -> Callable[[list[Entry]], int]:
    """The index of the ``n``-th line of operation ``op_code`` (with a ``user_attr`` ``has``, where given)."""

    def find(entries: list[Entry]) -> int:
        found = [
            i
            for i, entry in enumerate(entries)
            if entry["op_code"] == op_code and (has is None or has in entry.get("user_attr", {}))
        ]
        return found[n]

    return find


def _set(key: str, value: Any) -> Callable[[Entry], None]:
    def forge(entry: Entry) -> None:
        entry[key] = value

    return forge


def _curve(forge_point: Callable[[dict[str, Any]], None]) -> Callable[[Entry], None]:
    def forge(entry: Entry) -> None:
        forge_point(entry["user_attr"]["curve"][-1])

    return forge


def _curve_string(entry: Entry) -> None:
    entry["user_attr"]["curve"] = "x"


def _drop(key: str) -> Callable[[dict[str, Any]], None]:
    def forge(point: dict[str, Any]) -> None:
        del point[key]

    return forge


def _point(key: str, value: Any) -> Callable[[dict[str, Any]], None]:
    def forge(point: dict[str, Any]) -> None:
        point[key] = value

    return forge


PARAM, STATE, INTERMEDIATE, ATTR, CREATE = 5, 6, 7, 8, 4
FORGERIES: dict[str, tuple[Callable[[list[Entry]], int], Callable[[Entry], None]]] = {
    # d01: a parameter's value outside the study's own search space, or not finite
    "param 1e300": (_nth(PARAM), _set("param_value_internal", 1e300)),
    "learning_rate 0.5 outside log:1e-4:1e-2": (_nth(PARAM, 1), _set("param_value_internal", 0.5)),
    "penalty 0 outside float:-200:-1": (_nth(PARAM), _set("param_value_internal", 0.0)),
    "param NaN": (_nth(PARAM), _set("param_value_internal", float("nan"))),
    "param -Infinity": (_nth(PARAM, 1), _set("param_value_internal", float("-inf"))),
    "distribution widened": (
        _nth(PARAM, 1),
        _set(
            "distribution",
            json.dumps({"name": "FloatDistribution", "attributes": {"step": None, "low": 1e-4, "high": 1.0, "log": True}}),
        ),
    ),
    "distribution with a key twice": (  # (read last-wins, it would equal the study's own)
        _nth(PARAM, 1),
        _set(
            "distribution",
            '{"name": "Evil", "name": "FloatDistribution", '
            '"attributes": {"step": null, "low": 0.0001, "high": 0.01, "log": true}}',
        ),
    ),
    # d02: non-finite or out-of-range values, trial ids the writer never writes
    "values Infinity": (_nth(STATE), _set("values", [float("inf")])),
    "values NaN": (_nth(STATE), _set("values", [float("nan")])),
    "values -1e9": (_nth(STATE), _set("values", [-1e9])),
    "values above max_cycles": (_nth(STATE), _set("values", [1e9])),
    "values of another value": (_nth(STATE, 1), _set("values", [0.5])),
    "intermediate NaN": (_nth(INTERMEDIATE), _set("intermediate_value", float("nan"))),
    "intermediate string": (_nth(INTERMEDIATE, 1), _set("intermediate_value", "x")),
    "intermediate step off the curve": (_nth(INTERMEDIATE), _set("step", 10**9)),
    "curve per_seed NaN": (_nth(ATTR, 0, "curve"), _curve(_point("per_seed", [float("nan")]))),
    "curve value -1": (_nth(ATTR, 0, "curve"), _curve(_point("value", -1.0))),
    "curve step past the budget": (_nth(ATTR, 0, "curve"), _curve(_point("step", 301))),
    # probe 5 (#14): a step off the schedule (every 100 steps, and the last: 300) is its own line's fault
    "curve step off the schedule": (_nth(ATTR, 0, "curve"), _curve(_point("step", 150))),
    "curve step skipping an evaluation": (_nth(ATTR, 0, "curve"), _curve(_point("step", 200))),
    "curve step off the schedule later": (_nth(ATTR, 1, "curve"), _curve(_point("step", 250))),
    "trial_id -5": (_nth(PARAM), _set("trial_id", -5)),
    "trial_id 1e9": (_nth(ATTR), _set("trial_id", 1e9)),
    "trial_id of an ended trial": (_nth(PARAM, 2), _set("trial_id", 0)),
    "trial_id true": (_nth(STATE), _set("trial_id", True)),
    "study_id 3": (_nth(CREATE), _set("study_id", 3)),
    "wall time NaN": (_nth(ATTR, 0, "wall_time_s"), _set("user_attr", {"wall_time_s": float("nan")})),
    "op_code 99": (_nth(CREATE, 1), _set("op_code", 99)),
    "worker_id with an escape": (_nth(CREATE), _set("worker_id", "w\x1b[2J")),
    "worker_id with a line break": (_nth(PARAM), _set("worker_id", "w\u2028x")),
    "directions of another objective": (_nth(0, 1), _set("directions", [1])),
    "datetime_start not a time": (_nth(CREATE), _set("datetime_start", "yesterday")),
    "an extra field": (_nth(STATE), _set("exec", "evilmod:X")),
    # d03: wrong types, which gave tracebacks after a trial was trained
    "param string": (_nth(PARAM), _set("param_value_internal", "evilmod:X")),
    "param list": (_nth(PARAM), _set("param_value_internal", [1.0])),
    "param dict": (_nth(PARAM, 1), _set("param_value_internal", {"a": 1})),
    "param_name unknown": (_nth(PARAM), _set("param_name", "evilmod:X")),
    "curve string": (_nth(ATTR, 0, "curve"), _curve_string),
    "curve entry without value": (_nth(ATTR, 0, "curve"), _curve(_drop("value"))),
    "objective string": (_nth(STATE), _set("values", ["x"])),
    "objective 400 digits": (_nth(STATE), _set("values", [10**400])),
    # probe 8 (#5): a refusal's reason the study file's reader would refuse
    "refused reason of two lines": (_nth(ATTR, 0, "curve"), _set("user_attr", {"refused": "refused\n## <script>"})),
    "refused reason with a bidi override": (_nth(ATTR, 0, "curve"), _set("user_attr", {"refused": "a \u202e b"})),
}
"""Each forgery: ``(the line it edits, how)``."""


def _forge(journal: Path, find: Callable[[list[Entry]], int], forge: Callable[[Entry], None]) -> int:
    """Edit the journal's line ``find`` gives with ``forge``; return its line number."""
    entries = [json.loads(line) for line in journal.read_text().splitlines()]
    index = find(entries)
    forge(entries[index])
    journal.write_text("".join(json.dumps(entry) + "\n" for entry in entries))
    return index + 1


def _refused(out: Path, line: str, capsys: pytest.CaptureFixture[str], before: dict[str, bytes | None]) -> None:
    """The command's one-line refusal starts with ``line``, and ``out`` is as ``before``."""
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and err.startswith(f"empathy-zoo: error: {line}"), err
    assert "Traceback" not in err
    assert _snapshot(out) == before


@pytest.mark.parametrize("name", list(FORGERIES))
def test_a_forged_journal_line_is_refused_naming_file_and_line_and_nothing_is_written(
    name: str, genuine: tuple[Path, Path], tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    sweep, study = genuine
    out = tmp_path / "study"
    shutil.copytree(study, out)
    journal = out / JOURNAL_FILE
    number = _forge(journal, *FORGERIES[name])
    before = _snapshot(out)
    capsys.readouterr()
    assert _tune(sweep, out, 3) == 2
    _refused(out, f"tuning journal {journal}, line {number}: ", capsys, before)


@pytest.mark.parametrize("name", ["param 1e300", "values Infinity", "curve string"])
def test_check_journal_refuses_a_forgery_and_keeps_a_torn_last_line(
    name: str, genuine: tuple[Path, Path], tmp_path: Path
) -> None:
    """The checker itself: a ``ValueError`` naming file and line; the cut last line is not dropped."""

    sweep, study = genuine
    journal = tmp_path / JOURNAL_FILE
    shutil.copy(study / JOURNAL_FILE, journal)
    number = _forge(journal, *FORGERIES[name])
    with journal.open("a") as handle:
        handle.write('{"op_code": 4, "worker_id"')
    before = journal.read_bytes()
    stored = json.loads(journal.read_text().splitlines()[1])["user_attr"]["plan"]
    plan = tiny_plan(sweep, 3)
    notes: list[str] = []
    with pytest.raises(ValueError, match=rf"^tuning journal {re.escape(str(journal))}, line {number}: ") as error:
        check_journal(journal, notes.append, plan, stored["update_kernel"])
    assert "\n" not in str(error.value) and not notes and journal.read_bytes() == before


def test_a_study_of_another_plan_is_refused_before_the_journal_gains_a_line(
    genuine: tuple[Path, Path], tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    sweep, study = genuine
    out = tmp_path / "study"
    shutil.copytree(study, out)
    before = _snapshot(out)
    capsys.readouterr()
    other = ["--param", "penalty=float:-100:-1", "--param", "learning_rate=log:1e-4:1e-2"]
    assert _tune(sweep, out, 3, other) == 2
    _refused(out, f"{out} holds a study of another plan (params differ)", capsys, before)


def test_a_curve_the_next_line_disagrees_with_is_named_by_its_line(
    genuine: tuple[Path, Path], tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """A curve point forged to agree with itself (its value the mean of its per_seed) is caught by
    the intermediate value after it: that line is refused, naming the curve's line too (either may
    be the forged one)."""
    sweep, study = genuine
    out = tmp_path / "study"
    shutil.copytree(study, out)
    journal = out / JOURNAL_FILE

    def consistent(point: dict[str, Any]) -> None:
        point["per_seed"] = [point["per_seed"][0] / 2 + 0.25]  # (within survival's range, never its own value)
        point["value"] = point["per_seed"][0]

    number = _forge(journal, _nth(ATTR, 0, "curve"), _curve(consistent))
    before = _snapshot(out)
    capsys.readouterr()
    assert _tune(sweep, out, 3) == 2
    err = capsys.readouterr().err
    assert err.startswith(f"empathy-zoo: error: tuning journal {journal}, line {number + 1}: intermediate_value is "), err
    assert f"over the curve line {number} set" in err and err.count("\n") == 1
    assert _snapshot(out) == before
