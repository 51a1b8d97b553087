"""The tuning journal (``study.journal``) checked line by line, field by field, against what
:func:`~empathy_zoo.training.tuning.run_study` writes into it, before Optuna reads it.

A journal may come from anyone, so :func:`check_study_lines` takes nothing on trust: every line is
one of the operations a study writes (Optuna's journal storage, one study named ``tune``, one
trial at a time), with exactly that operation's fields, each of its type and within its range:

* ``op_code`` 0 (the study opened, by each run of ``tune``): the study's name and the plan's
  direction;
* 2 (the plan, once, before any trial): equal to the plan of the command that resumes it, or the
  study is refused as one of another plan;
* 4 (a trial created): only while fewer trials than the plan's batch
  (:attr:`~empathy_zoo.training.study_plan.StudyPlan.batch`; one for a batch of 1) run, those of
  an earlier run stopped counting; trial ids are the trials' numbers, ``0, 1, …``, in the order
  they were created, and every later line of a trial names one that runs;
* 5 (a parameter drawn): the plan's parameters, each once, in the plan's order, before anything
  else of the trial; its distribution the one the plan's search space gives it, its value inside
  it (a finite number between its bounds, a whole one for an int field, an index of a choice);
* 8 (a trial's attribute): its learning curve (each greedy evaluation's step the next of the
  plan's schedule, as the runner evaluates: every ``eval_interval`` steps and at the budget's last
  step; each tuning seed's value of the objective metric, finite and within the
  metric's range; the value their mean), growing by one evaluation at a time; its wall time; the
  reason the method refused its point;
* 7 (an intermediate value): the step of the curve's last evaluation and the trial's value so
  far (:func:`~empathy_zoo.training.study_plan.curve_value`);
* 6 (a trial ended): finished (its value the last intermediate value, its point one the method
  takes), pruned (the same) or failed (refused or interrupted, no value); nothing of a trial
  follows its end; the trials ended finished, pruned or refused (those the study counts done)
  no more than the plan's :attr:`~empathy_zoo.training.study_plan.StudyPlan.trials` (a study
  resumed with a lower ``--trials`` than it has done is refused, naming the journal and the count).

Any other line, field or value is refused with a ``ValueError`` that names the file and the line.
"""

from __future__ import annotations

import json
import math
import unicodedata
from collections.abc import Sequence
from dataclasses import dataclass, field
from datetime import UTC, datetime
from pathlib import Path
from typing import Any

import numpy as np

from empathy_zoo.bounded_read import check_json_depth, parse_json
from empathy_zoo.document_checks import shown
from empathy_zoo.experiment.search_space import ParamSpec, point_runs
from empathy_zoo.limits import MAX_WALL_TIME_S
from empathy_zoo.metrics import METRIC_RANGES
from empathy_zoo.names import LABEL_REFUSED_CATEGORIES
from empathy_zoo.training.study_plan import StudyPlan, curve_value

__all__ = ["check_study_lines", "param_distribution", "stored_plan"]

STUDY_NAME = "tune"
"""The name of the one study a journal holds."""
CREATE_STUDY, SET_STUDY_USER_ATTR, CREATE_TRIAL, SET_TRIAL_PARAM = 0, 2, 4, 5
SET_TRIAL_STATE_VALUES, SET_TRIAL_INTERMEDIATE_VALUE, SET_TRIAL_USER_ATTR = 6, 7, 8
COMPLETE, PRUNED, FAIL = 1, 2, 3
"""Optuna's trial states a study's trials end in."""
DIRECTION_CODES = {"minimize": 1, "maximize": 2}
"""Optuna's code of each direction."""
MAX_WORKER_ID = 200
"""Longest worker id read (Optuna writes a UUID and a thread id: under 60 characters)."""
MAX_DATETIME = 64
"""Longest time stamp read (Optuna writes ISO 8601 with microseconds and a zone: 32 characters)."""
EARLIEST, LATEST = datetime(1971, 1, 1, tzinfo=UTC), datetime(9999, 1, 1, tzinfo=UTC)
"""The range of a time stamp read (UTC): any zone's local time of one inside it is a ``datetime``
(Optuna writes the time a trial started and ended)."""


def _printable_line(text: str) -> bool:
    """Whether ``text`` holds no control or format character and no line break (the rule of
    :meth:`empathy_zoo.document_checks.DocumentChecker.text`, which the study file's reader applies)."""
    return not any(unicodedata.category(character) in LABEL_REFUSED_CATEGORIES for character in text)


MAX_REASON = 100_000
"""Longest reason for a refused point read (the method's one-line message)."""
MAX_DISTRIBUTION = 1 << 20
"""Longest distribution (a JSON text in the line) read."""
_CURVE, _WALL, _REFUSED = "curve", "wall_time_s", "refused"
_COMMON = ("op_code", "worker_id")
_FIELDS: dict[int, tuple[str, ...]] = {
    CREATE_STUDY: ("study_name", "directions"),
    SET_STUDY_USER_ATTR: ("study_id", "user_attr"),
    CREATE_TRIAL: ("study_id", "datetime_start"),
    SET_TRIAL_PARAM: ("trial_id", "param_name", "param_value_internal", "distribution"),
    SET_TRIAL_STATE_VALUES: ("trial_id", "state", "values", "datetime_complete"),
    SET_TRIAL_INTERMEDIATE_VALUE: ("trial_id", "step", "intermediate_value"),
    SET_TRIAL_USER_ATTR: ("trial_id", "user_attr"),
}
"""The fields of every operation a study writes, but ``op_code`` and ``worker_id``."""


def stored_plan(plan: StudyPlan, update_kernel: str) -> dict[str, Any]:
    """The plan as the journal stores it (``op_code`` 2): :meth:`StudyPlan.record` without the
    number of trials (a resumed study may change it) and without ``env`` and ``env_kwargs`` (its
    ``experiment`` id's hash holds them; a journal written before the record had them resumes),
    with the update kernel its trials train with."""
    record = plan.record()
    wanted = {key: value for key, value in record.items() if key not in ("budget", "env", "env_kwargs")}
    wanted["budget"] = {k: v for k, v in record["budget"].items() if k not in ("trials", "env_steps_at_most")}
    wanted["update_kernel"] = update_kernel
    return wanted


@dataclass
class _Trial:
    """What the lines read so far say of one trial."""

    number: int
    params: dict[str, Any] = field(default_factory=dict)
    curve: list[Any] = field(default_factory=list)
    curve_line: int = 0
    """The journal's line that set :attr:`curve` (a later line that disagrees with it names it)."""
    intermediate: list[float] = field(default_factory=list)
    wall: bool = False
    refused: bool = False


class _Refusal(ValueError):
    """A line that is not what a study writes (its message names the field, the value and what it takes)."""


def _expect(condition: bool, what: str, value: Any, expected: str) -> None:
    if not condition:
        raise _Refusal(f"{what} is {shown(value)}, expected {expected}")


def _is_int(value: Any) -> bool:
    return isinstance(value, int) and not isinstance(value, bool)


def _number(value: Any, what: str) -> float:
    """``value`` as a float, refused unless it is a finite JSON number (no bool, no integer too large for a float)."""
    _expect(isinstance(value, (int, float)) and not isinstance(value, bool), what, value, "a number")
    try:
        number = float(value)
    except OverflowError:
        number = math.inf
    _expect(math.isfinite(number), what, value, "a finite number")
    return number


def _datetime(value: Any, what: str) -> None:
    """Refuse ``value`` unless it is an ISO 8601 time stamp between :data:`EARLIEST` and
    :data:`LATEST` (one without a zone taken as UTC): Optuna turns it into local time, which
    overflows a stamp near the ends of ``datetime``'s range (year 1 or 9999)."""
    expected = f"an ISO 8601 time stamp from {EARLIEST.year} to {LATEST.year - 1}"
    _expect(isinstance(value, str) and 0 < len(value) <= MAX_DATETIME, what, value, expected)
    try:
        stamp = datetime.fromisoformat(value)
        utc = stamp.astimezone(UTC) if stamp.tzinfo is not None else stamp.replace(tzinfo=UTC)
    except (ValueError, OverflowError):
        utc = None
    _expect(utc is not None and EARLIEST <= utc < LATEST, what, value, expected)


def param_distribution(spec: ParamSpec) -> Any:
    """The Optuna distribution ``spec``'s parameter is drawn from (as :meth:`ParamSpec.suggest` draws it)."""
    from optuna.distributions import CategoricalDistribution, FloatDistribution, IntDistribution

    if spec.kind == "choice":
        return CategoricalDistribution(list(spec.choices))
    if spec.integer:
        return IntDistribution(int(spec.low), int(spec.high), log=spec.kind == "log")
    return FloatDistribution(spec.low, spec.high, log=spec.kind == "log")


def _distribution_json(spec: ParamSpec) -> Any:
    """The distribution Optuna stores for ``spec``, parsed."""
    from optuna.distributions import distribution_to_json

    return json.loads(distribution_to_json(param_distribution(spec)))


class _StudyLines:
    """The check of a journal's lines, in order, against ``plan`` (see the module documentation)."""

    def __init__(self, plan: StudyPlan, update_kernel: str, out: Path) -> None:
        self.plan = plan
        self.out = out
        self.wanted = stored_plan(plan, update_kernel)
        self.specs = {spec.name: spec for spec in plan.params}
        self.order = [spec.name for spec in plan.params]
        self.distributions = {spec.name: _distribution_json(spec) for spec in plan.params}
        low, high = METRIC_RANGES[plan.metric]
        if plan.metric == "survival":
            high = _max_cycles(plan)
        self.low, self.high = low, high
        self.opened = False
        self.has_plan = False
        self.trials: list[_Trial] = []
        self.running: dict[int, _Trial] = {}
        """The trials created since the study was last opened and not ended, by number."""
        self.number = 0
        """The number of the line being checked (in the journal)."""
        self.done = 0
        """The trials that ended counted (finished, pruned or refused), as the study counts them."""

    def line(self, entry: dict[str, Any]) -> None:
        """Check one line (a JSON object), given every line before it was checked."""
        op: Any = entry.get("op_code")
        _expect(_is_int(op) and op in _FIELDS, "op_code", op, f"one of {sorted(_FIELDS)} (what a study writes)")
        expected = {*_COMMON, *_FIELDS[op]}
        extra, missing = sorted(set(entry) - expected), sorted(expected - set(entry))
        if extra or missing:
            raise _Refusal(
                f"operation {op} has "
                + "; ".join(
                    part
                    for part in (
                        f"field(s) {shown(extra)} it never has" if extra else "",
                        f"no field(s) {', '.join(missing)}" if missing else "",
                    )
                    if part
                )
            )
        worker = entry["worker_id"]
        _expect(
            isinstance(worker, str) and 0 < len(worker) <= MAX_WORKER_ID and _printable_line(worker),
            "worker_id",
            worker,
            "a worker's id (one line of printable text)",
        )
        if op != CREATE_STUDY and not self.opened:
            raise _Refusal(f"operation {op} comes before the study was created (operation 0)")
        if op in (SET_STUDY_USER_ATTR, CREATE_TRIAL):
            _expect(_is_int(entry["study_id"]) and entry["study_id"] == 0, "study_id", entry["study_id"], "0 (the one study)")
        getattr(self, f"_op_{op}")(entry)

    def _op_0(self, entry: dict[str, Any]) -> None:
        _expect(entry["study_name"] == STUDY_NAME, "study_name", entry["study_name"], repr(STUDY_NAME))
        direction = DIRECTION_CODES[self.plan.direction]
        _expect(
            entry["directions"] == [direction] and _is_int(entry["directions"][0]),
            "directions",
            entry["directions"],
            f"[{direction}] (the plan's objective: {self.plan.direction})",
        )
        self.opened = True
        self.running = {}  # (a run of tune opens the study: a trial its last run left unended stays so)

    def _op_2(self, entry: dict[str, Any]) -> None:
        attr = entry["user_attr"]
        _expect(isinstance(attr, dict) and list(attr) == ["plan"], "user_attr", attr, 'the plan ({"plan": {...}})')
        if self.has_plan:
            raise _Refusal("the plan is stored twice")
        stored = attr["plan"]
        _expect(isinstance(stored, dict), "user_attr.plan", stored, "the plan (an object)")
        if stored != self.wanted:
            differs = ", ".join(sorted(key for key in set(stored) | set(self.wanted) if stored.get(key) != self.wanted.get(key)))
            differs = differs if differs.isprintable() and len(differs) <= 200 else shown(differs)
            raise ValueError(
                f"{self.out} holds a study of another plan ({differs} differ): give another --out, "
                "or the same sweep file, method, parameters, objective, seeds and budget to resume it (--trials may change)"
            )
        self.has_plan = True

    def _op_4(self, entry: dict[str, Any]) -> None:
        _datetime(entry["datetime_start"], "datetime_start")
        if not self.has_plan:
            raise _Refusal("a trial is created before the plan is stored")
        batch = self.plan.batch
        if len(self.running) >= batch:
            numbers = sorted(self.running)
            raise _Refusal(
                f"a trial is created while trial(s) {numbers} run (a study of batch {batch} runs at most {batch} at a time)"
            )
        trial = _Trial(len(self.trials))
        self.trials.append(trial)
        self.running[trial.number] = trial

    def _trial(self, entry: dict[str, Any]) -> _Trial:
        """The trial a line names: one created since the study was opened, still running."""
        trial_id = entry["trial_id"]
        numbers = sorted(self.running)
        expected = f"one of {numbers} (the trials still running)" if numbers else "no trial (none runs)"
        _expect(_is_int(trial_id) and trial_id in self.running, "trial_id", trial_id, expected)
        return self.running[trial_id]

    def _op_5(self, entry: dict[str, Any]) -> None:
        trial = self._trial(entry)
        name = entry["param_name"]
        drawn = len(trial.params)
        if trial.curve or trial.wall or trial.refused or trial.intermediate or drawn == len(self.order):
            raise _Refusal(f"param_name {shown(name)} is drawn after the trial's parameters were all drawn and used")
        _expect(
            isinstance(name, str) and name == self.order[drawn],
            "param_name",
            name,
            f"{self.order[drawn]!r} (the plan's next parameter)",
        )
        spec = self.specs[name]
        text = entry["distribution"]
        _expect(isinstance(text, str) and len(text) <= MAX_DISTRIBUTION, "distribution", text, f"the distribution of {spec.text}")
        try:
            check_json_depth(text.encode("utf-8", "surrogatepass"), "the distribution")
            parsed = parse_json(text)  # (a key given twice is no distribution tune writes)
        except (ValueError, RecursionError):
            parsed = None
        _expect(parsed == self.distributions[name], "distribution", text, f"the distribution of {spec.text}")
        trial.params[name] = _param_value(spec, entry["param_value_internal"])

    def _op_8(self, entry: dict[str, Any]) -> None:
        trial = self._drawn(entry)
        attr = entry["user_attr"]
        _expect(
            isinstance(attr, dict) and len(attr) == 1 and next(iter(attr)) in (_CURVE, _WALL, _REFUSED),
            "user_attr",
            attr,
            f"one of {_CURVE}, {_WALL}, {_REFUSED}",
        )
        ((key, value),) = attr.items()
        if trial.wall or trial.refused:
            raise _Refusal(f"user_attr.{key} is set after the trial stopped")
        if key == _REFUSED:
            _expect(
                isinstance(value, str) and 0 < len(value) <= MAX_REASON and _printable_line(value),
                "user_attr.refused",
                value,
                "the method's reason, one line of printable text (as the study file holds it)",
            )
            if trial.curve:
                raise _Refusal("user_attr.refused is set on a trial that trained")
            trial.refused = True
        elif key == _WALL:
            seconds = _number(value, "user_attr.wall_time_s")
            _expect(0 <= seconds <= MAX_WALL_TIME_S, "user_attr.wall_time_s", value, f"seconds in [0, {MAX_WALL_TIME_S:,}]")
            trial.wall = True
        else:
            self._curve(trial, value)

    def _curve(self, trial: _Trial, curve: Any) -> None:
        what = "user_attr.curve"
        grown = len(trial.curve) + 1
        _expect(isinstance(curve, list) and len(curve) == grown, what, curve, f"a list of {grown} evaluation(s)")
        _expect(curve[:-1] == trial.curve, what, curve, "the trial's curve so far and one more evaluation")
        if len(trial.intermediate) != len(trial.curve):
            raise _Refusal(f"{what} grows before its last evaluation was reported (operation 7)")
        point = curve[-1]
        where = f"{what}[{len(curve) - 1}]"
        _expect(
            isinstance(point, dict) and sorted(point) == ["per_seed", "step", "value"], where, point, "{step, value, per_seed}"
        )
        step, after = point["step"], trial.curve[-1]["step"] if trial.curve else 0
        interval, budget = self.plan.base.eval_interval, self.plan.base.steps
        if after >= budget:
            raise _Refusal(f"{what} grows past its evaluation at the budget's last step ({budget:,})")
        due = min((after // interval + 1) * interval, budget)
        _expect(
            _is_int(step) and step == due,
            f"{where}.step",
            step,
            f"{due:,}, the next greedy evaluation of the plan's schedule (every {interval:,} steps, and the last: {budget:,})",
        )
        per_seed = point["per_seed"]
        seeds = len(self.plan.seeds)
        _expect(isinstance(per_seed, list) and len(per_seed) == seeds, f"{where}.per_seed", per_seed, f"{seeds} value(s)")
        values = [self._metric(value, f"{where}.per_seed[{i}]") for i, value in enumerate(per_seed)]
        value = self._metric(point["value"], f"{where}.value")
        _expect(
            math.isclose(value, float(np.mean(values)), rel_tol=1e-9, abs_tol=1e-12),
            f"{where}.value",
            point["value"],
            "the mean of per_seed",
        )
        trial.curve, trial.curve_line = curve, self.number

    def _metric(self, value: Any, what: str) -> float:
        """``value``, a value of the objective metric, within its range."""
        number = _number(value, what)
        high = "" if self.high is None else f" and <= {self.high:g}"
        _expect(
            self.low <= number and (self.high is None or number <= self.high),
            what,
            value,
            f"{self.plan.metric}, a number >= {self.low:g}{high}",
        )
        return number

    def _drawn(self, entry: dict[str, Any]) -> _Trial:
        """The trial a line names, every parameter of it drawn."""
        trial = self._trial(entry)
        if len(trial.params) != len(self.order):
            raise _Refusal(f"operation {entry['op_code']} comes before the trial's parameters were all drawn")
        return trial

    def _op_7(self, entry: dict[str, Any]) -> None:
        trial = self._drawn(entry)
        if len(trial.curve) != len(trial.intermediate) + 1:
            raise _Refusal("an intermediate value without a new evaluation on the trial's curve")
        step = entry["step"]
        _expect(
            _is_int(step) and step == trial.curve[-1]["step"],
            "step",
            step,
            f"{trial.curve[-1]['step']} (the last step of the curve line {trial.curve_line} set)",
        )
        value = self._metric(entry["intermediate_value"], "intermediate_value")
        expected = curve_value([point["value"] for point in trial.curve], self.plan.over)
        _expect(
            math.isclose(value, expected, rel_tol=1e-9, abs_tol=1e-12),
            "intermediate_value",
            entry["intermediate_value"],
            f"{expected!r} (the trial's value over the curve line {trial.curve_line} set)",
        )
        trial.intermediate.append(value)

    def _op_6(self, entry: dict[str, Any]) -> None:
        trial = self._trial(entry)
        state, values = entry["state"], entry["values"]
        _expect(_is_int(state) and state in (COMPLETE, PRUNED, FAIL), "state", state, f"{COMPLETE}, {PRUNED} or {FAIL} (ended)")
        _datetime(entry["datetime_complete"], "datetime_complete")
        if state == FAIL:
            _expect(values is None, "values", values, "null (a failed trial has no value)")
        else:
            if trial.refused or not trial.intermediate or len(trial.params) != len(self.order):
                raise _Refusal(f"state is {state} (finished or pruned) for a trial that reported no value")
            if state == COMPLETE and not trial.wall:
                raise _Refusal("state is 1 (finished) for a trial without its wall time")
            _expect(isinstance(values, list) and len(values) == 1, "values", values, "a list of one value")
            value = self._metric(values[0], "values[0]")
            _expect(
                value == trial.intermediate[-1],
                "values[0]",
                values[0],
                f"{trial.intermediate[-1]!r} (its last intermediate value)",
            )
            if state == COMPLETE:
                try:
                    point_runs(self.plan.base, self.plan.params, trial.params, self.plan.seeds[:1])
                except ValueError as error:
                    raise _Refusal(
                        f"the finished trial's point is one method {self.plan.base.method!r} refuses ({error})"
                    ) from None
        if state != FAIL or trial.refused:
            self.done += 1
        del self.running[trial.number]


def _param_value(spec: ParamSpec, value: Any) -> Any:
    """The value of ``spec``'s parameter stored as ``value`` (Optuna's internal form: a float, or a
    choice's index), refused unless it lies in ``spec``'s search space."""
    what = "param_value_internal"
    if spec.kind == "choice":
        count = len(spec.choices)
        _expect(_is_int(value) and 0 <= value < count, what, value, f"the index of one of {spec.text}'s {count} choices")
        return spec.choices[value]
    number = _number(value, what)
    low, high = (int(spec.low), int(spec.high)) if spec.integer else (spec.low, spec.high)
    kind = "a whole number" if spec.integer else "a number"
    _expect(
        low <= number <= high and (not spec.integer or number == int(number)),
        what,
        value,
        f"{kind} in [{low!r}, {high!r}] ({spec.text})",
    )
    return int(number) if spec.integer else number


def _max_cycles(plan: StudyPlan) -> float | None:
    """The longest episode of the plan's environment variant (a survival's ceiling), or ``None`` where it has none."""
    from empathy_zoo.engine.arguments import argument_defaults
    from empathy_zoo.environments import ENGINES

    kwargs = plan.base.env_kwargs
    if "max_cycles" in kwargs:
        return float(kwargs["max_cycles"])
    defaults = argument_defaults(ENGINES[plan.base.env]) if plan.base.env in ENGINES else {}
    return float(defaults["max_cycles"]) if isinstance(defaults.get("max_cycles"), int) else None


def check_study_lines(lines: Sequence[tuple[int, dict[str, Any]]], path: Path, plan: StudyPlan, update_kernel: str) -> None:
    """Check the journal ``path``'s lines ``lines`` (``(line number, JSON object)``, in order)
    against what a study of ``plan``, trained with ``update_kernel``, writes (see the module
    documentation); a study of another plan, or any line that is not what the study writes, is
    refused with a one-line ``ValueError`` naming the file (and the line), and so is a journal that
    holds more trials done than ``plan.trials`` (naming the file, ``--trials`` and the count done)."""
    check = _StudyLines(plan, update_kernel, path.parent)
    for number, entry in lines:
        check.number = number
        try:
            check.line(entry)
        except _Refusal as error:
            raise ValueError(
                f"tuning journal {path}, line {number}: {error}; the journal is damaged or not this study's: "
                "move it away to start the study again"
            ) from None
    if check.done > plan.trials:  # (a study of fewer trials than its journal holds done is no study its reader takes)
        raise ValueError(
            f"tuning journal {path} holds {check.done} trial(s) done, more than --trials {plan.trials}: resume it "
            f"with --trials {check.done} or more (--trials may change on resume, never below the trials done)"
        )
