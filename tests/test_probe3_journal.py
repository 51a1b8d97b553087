"""Three holes a hostile probe found in reading files from elsewhere, closed.

* The JSON depth check (:func:`empathy_zoo.bounded_read.json_depth`), run on every result,
  evaluation and journal line before it is parsed, scans the text once: a string of escaped quotes
  (``"\\"\\"\\"…``, 200 KB) took minutes of backtracking; it is measured at once now, and every
  valid document's depth is still the one its parsed value has.
* A journal's time stamp near the ends of ``datetime``'s range (Optuna turns it into local time,
  which overflows) is refused in one line naming the journal and the line, before anything is
  trained or written.
* A user's ``study.journal.lock`` (the name of Optuna's lock file) in the study's directory is
  left alone: Optuna's lock waited 30 seconds on it and deleted it.
"""

from __future__ import annotations

import json
import random
import shutil
from pathlib import Path
from typing import Any

import pytest
from helpers_tune import run_tune, snapshot, tiny_study

from empathy_zoo.bounded_read import check_json_depth, json_depth, read_json_data
from empathy_zoo.limits import MAX_JSON_DEPTH

ESCAPED_QUOTES = b'"' + b'\\"' * 100_000
"""200 KB: a string of escaped quotes that never closes (the old check's backtracking took minutes)."""


def _depth(value: Any) -> int:
    """How deep arrays and objects nest in the parsed JSON ``value``."""
    if isinstance(value, list):
        return 1 + max((_depth(item) for item in value), default=0)
    if isinstance(value, dict):
        return 1 + max((_depth(item) for item in value.values()), default=0)
    return 0


def _document(rng: random.Random, level: int = 0) -> Any:
    """A random JSON value whose strings hold brackets, quotes and backslashes."""
    kind = rng.random()
    if level > 8 or kind < 0.3:
        return rng.choice([0, -2.5, 1e300, None, True, "", "[{", '"]}', "\\", '\\"[', "é\\n[", "x" * rng.randint(0, 4)])
    if kind < 0.65:
        return [_document(rng, level + 1) for _ in range(rng.randint(0, 4))]
    keys = ["k", '"[', "\\", "{}", '\\"]']
    return {f"{rng.choice(keys)}{i}": _document(rng, level + 1) for i in range(rng.randint(0, 4))}


VALID = [
    "0",
    '""',
    '"[[[{{{"',
    '"\\\\"',
    '["\\\\", ["\\"", "]"]]',
    '{"a\\\\\\"[": [[{}], "\\\\\\\\"]}',
    "[[[[[[[[[[]]]]]]]]]]",
    '[{"a": [1, {"b": "]]]]"}]}, [], "\\"[\\"", {"\\\\": {"c": [[["}}}"]]]}}]',
]
"""Valid documents written out (the random ones below add more)."""


@pytest.mark.parametrize("text", VALID)
def test_the_depth_of_a_valid_document_is_the_depth_of_its_parsed_value(text: str) -> None:
    data = text.encode()
    assert json_depth(data) == _depth(json.loads(data))


def test_the_depth_of_random_valid_documents_is_the_depth_of_their_parsed_values() -> None:
    rng = random.Random(3)
    for _ in range(300):
        value = _document(rng)
        for text in (json.dumps(value), json.dumps(value, ensure_ascii=False, indent=1)):
            assert json_depth(text.encode()) == _depth(value), text


def test_a_string_of_escaped_quotes_is_measured_in_one_pass() -> None:
    """Measured, not timed: the old check would still be backtracking over these for minutes."""
    assert json_depth(ESCAPED_QUOTES) == 0
    assert json_depth(b"[" + ESCAPED_QUOTES + b'"]') == 1
    assert json_depth(b'["' + b"\\\\" * 100_000 + b'", [[]]]') == 3
    assert json_depth(b'["' + b'\\"' * 100_000 + b'[[[["]') == 1
    too_deep = b'["' + b'\\"' * 100_000 + b'"' + b"[" * MAX_JSON_DEPTH + b"]" * (MAX_JSON_DEPTH + 1)
    with pytest.raises(ValueError, match=r"^the probe's text nests arrays and objects more than \d+ deep"):
        check_json_depth(too_deep, "the probe's text")


def test_a_result_file_of_escaped_quotes_is_refused_in_one_line_naming_it(tmp_path: Path) -> None:
    path = tmp_path / "run.json"
    path.write_bytes(b'{"schema": ' + ESCAPED_QUOTES)
    with pytest.raises(ValueError, match=rf"^{path} is corrupted \(") as error:
        read_json_data(path, "result file")
    assert "\n" not in str(error.value)


def test_a_journal_line_of_escaped_quotes_is_refused_naming_file_and_line(tmp_path: Path) -> None:
    pytest.importorskip("optuna")
    from empathy_zoo.training.tuning import check_journal

    journal = tmp_path / "study.journal"
    journal.write_bytes(b'{"op_code": 0}\n{"worker_id": ' + ESCAPED_QUOTES + b"\n")
    before = journal.read_bytes()
    notes: list[str] = []
    with pytest.raises(ValueError, match=rf"^tuning journal {journal}, line 2 is no JSON") as error:
        check_journal(journal, notes.append)
    assert "\n" not in str(error.value) and not notes and journal.read_bytes() == before


# --- a study's journal and directory (a study of one 300-step trial, as in test_journal_forgeries.py)

LOCK = "study.journal.lock"
"""The name Optuna gives the lock file of a journal ``study.journal``."""


_tune = run_tune


_snapshot = snapshot


@pytest.fixture(scope="module")
def study(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, Path]:
    """``(sweep file, study directory)`` of a genuine study of one trial."""
    pytest.importorskip("optuna")
    return tiny_study(tmp_path_factory.mktemp("study"), 1)


OUT_OF_RANGE = {
    "start past year 9999 in UTC": (4, "datetime_start", "9999-12-31T23:59:59.999999-23:59"),
    "end before year 1 in UTC": (6, "datetime_complete", "0001-01-01T00:00:00.000000+23:59"),
}
"""Each forgery: ``(the operation whose line it edits, the field, the time stamp)``."""


@pytest.mark.parametrize("name", list(OUT_OF_RANGE))
def test_a_journal_time_stamp_out_of_range_is_refused_naming_file_and_line_and_nothing_is_written(
    name: str, study: tuple[Path, Path], tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    from empathy_zoo.training.tuning import JOURNAL_FILE

    sweep, genuine = study
    out = tmp_path / "study"
    shutil.copytree(genuine, out)
    journal = out / JOURNAL_FILE
    op_code, key, stamp = OUT_OF_RANGE[name]
    entries = [json.loads(line) for line in journal.read_text().splitlines()]
    index = next(i for i, entry in enumerate(entries) if entry["op_code"] == op_code)
    entries[index][key] = stamp
    journal.write_text("".join(json.dumps(entry) + "\n" for entry in entries))
    before = _snapshot(out)
    capsys.readouterr()
    assert _tune(sweep, out, 2) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1, err
    assert err.startswith(f"empathy-zoo: error: tuning journal {journal}, line {index + 1}: {key} is "), err
    assert "an ISO 8601 time stamp from 1971 to 9998" in err and "Traceback" not in err
    assert _snapshot(out) == before


def test_a_users_file_named_like_optunas_lock_is_left_alone(study: tuple[Path, Path], tmp_path: Path) -> None:
    """A new study and a resumed one: the file is as it was, and no lock file of Optuna's is made."""
    sweep, genuine = study
    fresh, resumed = tmp_path / "fresh", tmp_path / "resumed"
    fresh.mkdir()
    shutil.copytree(genuine, resumed)
    for out in (fresh, resumed):
        (out / LOCK).write_bytes(b"my notes\n")
        assert _tune(sweep, out, 2) == 0
        assert (out / LOCK).read_bytes() == b"my notes\n"
        assert sorted(path.name for path in out.glob(f"{LOCK}*")) == [LOCK]
