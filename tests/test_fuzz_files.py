"""Property-based attack on the files the suite reads: sweep files (``reproduce --profile``) and
result files (``leaderboard``, ``reproduction``). A valid file is changed in one place (a key
removed, a value of the wrong kind, an unknown key, a name that is no file name, cut short); a
file that is then invalid gives exit status 2 and one line ``empathy-zoo: error: …`` naming the
file and the key, never a traceback, and nothing is written.

Seeded (``derandomize``): the same examples on every run. ``-m slow`` runs a longer variant.
"""

from __future__ import annotations

import copy
import json
import math
import tempfile
import tomllib
from collections import Counter
from pathlib import Path
from typing import Any

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import empathy_zoo.cli as cli
import empathy_zoo.training.runner as runner
from empathy_zoo.experiment.model import RunSpec
from empathy_zoo.result_file import REQUIRED_FIELDS
from empathy_zoo.training import RunnerOptions, train_runs

TALLY: Counter[str] = Counter()
"""What the attack tried (printed at the end of the module with ``-s``)."""
FAST = settings(max_examples=300, deadline=None, derandomize=True, suppress_health_check=list(HealthCheck))
LONG = settings(max_examples=2000, deadline=None, derandomize=True, suppress_health_check=list(HealthCheck))
WRONG = ["x", "../evil", -3, 0, 2.5, True, [], [1, 2], {"a": 1}, 10**6, math.inf]
"""Values put where another belongs."""

SWEEP: dict[str, Any] = {
    "sweep": {"name": "fuzz", "seeds": 2, "steps": 300, "eval_interval": 150, "eval_episodes": 2},
    "settings": {"learning_starts": 32, "replay_capacity": 300, "hidden_size": 8},
    "envs": {
        "coexistence_v0": {"max_cycles": 50, "fixed": {"cat_0": "random_walk"}},
        "sharing_v0": {"max_cycles": 50, "start": "centre"},
    },
    "methods": [
        {"method": "empathic_dqn", "selfishness": [1.0, 0.5], "label": "E {selfishness:g}"},
        {"method": "dqn_harm_penalty", "envs": ["coexistence_v0"]},
    ],
}


# ---------------------------------------------------------------------------- TOML, written by hand
def _key(key: str) -> str:
    return key if key and all(c.isalnum() or c in "_-" for c in key) else json.dumps(key)


def _value(value: Any) -> str:
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, float) and not math.isfinite(value):
        return "inf" if value > 0 else "-inf" if value < 0 else "nan"
    if isinstance(value, (int, float)):
        return repr(value)
    if isinstance(value, str):
        return json.dumps(value)
    if isinstance(value, list):
        return "[" + ", ".join(_value(v) for v in value) + "]"
    return "{" + ", ".join(f"{_key(k)} = {_value(v)}" for k, v in value.items()) + "}"


def to_toml(document: dict[str, Any]) -> str:
    """TOML text of ``document``: scalars first, then ``[tables]``, ``[a.b]`` tables and ``[[arrays]]``."""
    lines = [
        f"{_key(k)} = {_value(v)}"
        for k, v in document.items()
        if not isinstance(v, dict) and not (isinstance(v, list) and v and all(isinstance(i, dict) for i in v))
    ]
    for name, value in document.items():
        if isinstance(value, dict):
            inner = [f"{_key(k)} = {_value(v)}" for k, v in value.items() if not (name == "envs" and isinstance(v, dict))]
            lines += ["", f"[{_key(name)}]", *inner]
            for sub, table in value.items() if name == "envs" else ():
                if isinstance(table, dict):
                    lines += ["", f"[{_key(name)}.{_key(sub)}]", *(f"{_key(k)} = {_value(v)}" for k, v in table.items())]
        elif isinstance(value, list) and value and all(isinstance(i, dict) for i in value):
            for table in value:
                lines += ["", f"[[{_key(name)}]]", *(f"{_key(k)} = {_value(v)}" for k, v in table.items())]
    return "\n".join(lines) + "\n"


def test_the_toml_writer_round_trips_the_base_sweep():
    assert tomllib.loads(to_toml(SWEEP)) == SWEEP


# ---------------------------------------------------------------------------- mutations
def paths(value: Any, prefix: tuple = ()) -> list[tuple]:
    """Every path into ``value`` (keys and list indices), parents before children."""
    found = [prefix] if prefix else []
    items = value.items() if isinstance(value, dict) else enumerate(value) if isinstance(value, list) else ()
    for key, item in items:
        found += paths(item, (*prefix, key))
    return found


def mutate(document: Any, path: tuple, operation: str, value: Any) -> Any:
    document = copy.deepcopy(document)
    parent = document
    for key in path[:-1]:
        parent = parent[key]
    if operation == "delete":
        del parent[path[-1]]
    elif operation == "add":
        target = parent[path[-1]]
        if not isinstance(target, dict):
            return None
        target["zz_unknown"] = 1
    else:
        parent[path[-1]] = value
    return document


def key_named(path: tuple, operation: str) -> str:
    """The word the refusal must contain: the changed key (or the list holding the changed item)."""
    if operation == "add":
        return "zz_unknown"
    words = [key for key in path if isinstance(key, str)]
    return words[-1]


# ---------------------------------------------------------------------------- sweep files
class SweepWasValid(Exception):
    """Training would start: the change left a valid sweep."""


def refuse_to_train(*args: Any, **kwargs: Any) -> None:
    raise SweepWasValid


def run_sweep(text: str) -> tuple[str, int | None, str, bool]:
    """``(outcome, status, stderr, anything written)`` of ``reproduce`` on a sweep file holding ``text``."""
    import contextlib
    import io

    with tempfile.TemporaryDirectory() as scratch:
        path, out = Path(scratch) / "sweep.toml", Path(scratch) / "out"
        path.write_text(text, encoding="utf-8")
        err = io.StringIO()
        with contextlib.redirect_stderr(err), contextlib.redirect_stdout(io.StringIO()), pytest.MonkeyPatch.context() as patch:
            patch.setattr(runner, "train_ensemble", refuse_to_train)
            try:
                status = cli.main(["reproduce", "--profile", str(path), "--out", str(out), "--no-progress", "--workers", "1"])
            except SweepWasValid:
                return "valid", None, "", False
        written = out.exists() or sorted(p.name for p in Path(scratch).iterdir()) != ["sweep.toml"]
        return "refused", status, err.getvalue(), written


SWEEP_PATHS = paths(SWEEP)


@st.composite
def sweep_change(draw: st.DrawFn) -> tuple[str, tuple, str]:
    if draw(st.integers(0, 14)) == 0:  # cut short: not TOML any more (or a smaller valid one)
        text = to_toml(SWEEP)
        return text[: draw(st.integers(1, len(text) - 1))], (), "cut"
    path = draw(st.sampled_from(SWEEP_PATHS))
    operation = draw(st.sampled_from(["delete", "replace", "replace", "replace", "add"]))
    changed = mutate(
        SWEEP, path, operation, draw(st.sampled_from([v for v in WRONG if v != 10**6]))
    )  # (10**6 seeds: valid, slow)
    if changed is None:
        changed, operation = mutate(SWEEP, path, "replace", "x"), "replace"
    return to_toml(changed), path, operation


def check_sweep_change(change: tuple[str, tuple, str]) -> None:
    text, path, operation = change
    outcome, status, err, written = run_sweep(text)
    TALLY[f"sweep {outcome}"] += 1
    if outcome == "valid":
        return
    assert status == 2 and err.startswith("empathy-zoo: error: ") and err.count("\n") == 1, (path, operation, err)
    assert "Traceback" not in err and "sweep.toml" in err, err
    if operation != "cut":
        assert key_named(path, operation) in err, (path, operation, err)
    assert not written


@FAST
@given(sweep_change())
def test_a_changed_sweep_file_is_refused_in_one_line_naming_file_and_key(change):
    check_sweep_change(change)


@pytest.mark.slow
@LONG
@given(sweep_change())
def test_a_changed_sweep_file_is_refused_in_one_line_naming_file_and_key_long(change):
    check_sweep_change(change)


# ---------------------------------------------------------------------------- result files
@pytest.fixture(scope="module")
def real_results(tmp_path_factory) -> list[dict[str, Any]]:
    """Two result files of a tiny real run."""
    specs = [
        RunSpec.of(
            settings={"learning_starts": 32, "replay_capacity": 200, "hidden_size": 8},
            seed=seed,
            steps=200,
            eval_interval=100,
            eval_episodes=2,
            env_kwargs={"max_cycles": 30},
        )
        for seed in (0, 1)
    ]
    out = tmp_path_factory.mktemp("real")
    return [json.loads(path.read_text()) for path in train_runs(specs, out, RunnerOptions(progress=False))]


def result_targets(result: dict[str, Any]) -> list[tuple]:
    """Paths whose change the schema must refuse (the settings' own values are their class's business)."""
    return [path for path in paths(result) if path[:2] != ("config", "settings") or path == ("config", "settings")]


def wrong_for(original: Any) -> list[Any]:
    kinds = {bool: "bool", int: "number", float: "number", str: "string", list: "array", dict: "object"}
    return [value for value in (*WRONG, None) if kinds.get(type(value)) != kinds.get(type(original))]


@st.composite
def result_change(draw: st.DrawFn, base: dict[str, Any]) -> tuple[dict[str, Any], str]:
    path = draw(st.sampled_from(result_targets(base)))
    original = base
    for key in path:
        original = original[key]
    names = {"run_id", "env", "variant"}
    if path in {(name,) for name in names} and draw(st.booleans()):
        changed = mutate(base, path, "replace", draw(st.sampled_from(["../x", "/abs", "a/b", ".hidden", ""])))
    elif (
        isinstance(path[-1], str)
        and draw(st.integers(0, 3)) == 0
        and (len(path) == 1 or path[0] != "config")
        and ((path[0] in REQUIRED_FIELDS and len(path) == 1) or path[0] in ("train", "eval"))
    ):
        changed = mutate(base, path, "delete", None)
    else:
        nullable = path in {("commit",), ("variant",), ("config", "variant")}  # (null is a fine value there)
        changed = mutate(
            base, path, "replace", draw(st.sampled_from([v for v in wrong_for(original) if not (nullable and v is None)]))
        )
    field = "".join(f"[{key}]" if isinstance(key, int) else f".{key}" for key in path).lstrip(".")
    return changed, field


def check_result_change(other: dict[str, Any], change: tuple[dict[str, Any], str]) -> None:
    import contextlib
    import io

    document, field = change
    with tempfile.TemporaryDirectory() as scratch:
        runs = Path(scratch) / "runs"
        runs.mkdir()
        (runs / "a.json").write_text(json.dumps(other), encoding="utf-8")
        (runs / "b.json").write_text(json.dumps(document), encoding="utf-8")
        before = sorted((p.name, p.stat().st_mtime_ns) for p in Path(scratch).rglob("*"))
        for command in ("leaderboard", "reproduction"):
            err = io.StringIO()
            with contextlib.redirect_stderr(err), contextlib.redirect_stdout(io.StringIO()):
                status = cli.main([command, scratch])
            message = err.getvalue()
            TALLY[f"result file refused by {command}"] += status == 2
            assert status == 2 and message.startswith("empathy-zoo: error: ") and message.count("\n") == 1, (field, message)
            assert "Traceback" not in message and str(runs / "b.json") in message, (field, message)
            parent = field.split("[")[0].split(".")[0]
            assert f"field {field}" in message or f"field {parent}" in message, (field, message)
        assert sorted((p.name, p.stat().st_mtime_ns) for p in Path(scratch).rglob("*")) == before


@st.composite
def result_case(draw: st.DrawFn, results: list[dict[str, Any]]) -> tuple[dict[str, Any], tuple]:
    return results[0], draw(result_change(results[1]))


def test_a_changed_result_file_is_refused_in_one_line_naming_file_and_field(real_results):
    @FAST
    @given(result_case(real_results))
    def attack(case):
        check_result_change(*case)

    attack()


@pytest.mark.slow
def test_a_changed_result_file_is_refused_in_one_line_naming_file_and_field_long(real_results):
    @LONG
    @given(result_case(real_results))
    def attack(case):
        check_result_change(*case)

    attack()


@pytest.fixture(scope="module", autouse=True)
def report_tally():
    yield
    if TALLY:
        print(f"\nfile fuzz: {dict(sorted(TALLY.items()))}")
