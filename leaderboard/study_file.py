"""A tuning study's file, ``study.json`` (:mod:`empathy_zoo.training.tuning`'s), found on disk
(:func:`study_files`), read bounded (:func:`read_study`) and checked field by field
(:func:`check_study`): what a study file may hold. A study file may come from anyone: nothing in it
is taken on trust before it is checked; its plan's fields are checked by
:mod:`leaderboard.study_plan_checks`.
"""

from __future__ import annotations

import math
import os
from collections.abc import Mapping
from pathlib import Path
from typing import Any

from empathy_zoo.data_files import check_input_dir
from empathy_zoo.document_checks import DocumentChecker, shown
from empathy_zoo.limits import MAX_SEEDS, MAX_STEPS, MAX_TRIALS, MAX_WALL_TIME_S
from empathy_zoo.metrics import METRIC_NAMES
from empathy_zoo.training.study_plan import DIRECTIONS, curve_value, objective_direction
from leaderboard.study_plan_checks import check_moves, check_params, metric_bounds, parameter_spec, plan_worlds, tuning_seeds

__all__ = [
    "STUDY_FILE",
    "StudyFileError",
    "check_study",
    "find_studies",
    "read_study",
    "study_files",
]

STUDY_FILE = "study.json"
"""A study's file (:data:`empathy_zoo.training.tuning.STUDY_FILE`)."""


def find_studies(root: str | os.PathLike[str]) -> list[Path]:
    """Every study file under ``root``, sorted, each file once (:func:`study_files`); ``ValueError``
    where there is none."""
    return study_files(root)[0]


def study_files(root: str | os.PathLike[str]) -> tuple[list[Path], list[tuple[Path, Path]]]:
    """Every ``study.json`` under ``root``, sorted, each file once, and the paths left out:
    ``(path, the path read in its place)``. A file reached by two paths (a symbolic link to it, a
    second hard link: one device and inode) is read by one of them, the first that is no symbolic
    link (the first of all where each is one). A path that cannot be looked at (a dangling link)
    is kept, for the read to refuse (``Path.rglob`` skips a name that does not exist: it is not used). Folders are
    walked without following links to them, as ``rglob`` walks. ``ValueError`` where there is none, or ``root`` is a loop
    of symbolic links, or is a file or missing (:func:`empathy_zoo.data_files.check_input_dir`)."""
    check_input_dir(root, "tuning directory", "name the directory holding study.json files (what tune --out wrote into)")
    found = sorted(
        Path(folder) / name for folder, folders, files in os.walk(root) for name in (*folders, *files) if name == STUDY_FILE
    )
    if not found:
        raise ValueError(f"no {STUDY_FILE} under {root}: run empathy-zoo tune first")
    by_file: dict[tuple[int, int], list[Path]] = {}
    for path in found:
        try:
            status = path.stat()
        except OSError:
            by_file[(-1, len(by_file))] = [path]  # (its own; the read names what is wrong with it)
            continue
        by_file.setdefault((status.st_dev, status.st_ino), []).append(path)
    kept: list[Path] = []
    left_out: list[tuple[Path, Path]] = []
    for paths in by_file.values():
        read = next((path for path in paths if not path.is_symlink()), paths[0])
        kept.append(read)
        left_out.extend((path, read) for path in paths if path != read)
    return sorted(kept), sorted(left_out)


MAX_STUDY_BYTES = 64 * 2**20
"""The largest ``study.json`` read (``tune`` writes a few KB per trial)."""


def read_study(path: Path) -> Any:
    """A ``study.json``: a regular file of at most :data:`MAX_STUDY_BYTES`, JSON nested within the
    suite's bound, else a ``ValueError`` naming it."""
    from empathy_zoo.bounded_read import check_json_depth, parse_json
    from empathy_zoo.limits import read_bounded

    data = read_bounded(path, MAX_STUDY_BYTES, "study file")
    check_json_depth(data, str(path))
    try:
        return parse_json(data)
    except (UnicodeDecodeError, ValueError) as error:  # (no JSON, a key given twice)
        raise ValueError(f"{path} is not JSON ({error})") from None


class StudyFileError(ValueError):
    """A ``study.json`` is not what ``tune`` writes; the message names the file and the field."""


TRIAL_STATES = ("COMPLETE", "PRUNED", "REFUSED", "INTERRUPTED")
"""The states a ``study.json`` records of a trial (:func:`empathy_zoo.training.tuning.study_document`)."""
MAX_ENV_STEPS = MAX_TRIALS * MAX_SEEDS * MAX_STEPS
"""The most env steps a study may spend: its trials, each on its tuning seeds, each of its steps."""
STUDY_SCHEMA = 1
"""The layout of ``study.json`` that ``tune`` writes (:data:`empathy_zoo.training.tuning.STUDY_SCHEMA`;
a study written before it held none)."""


def check_study(document: Any, path: str | os.PathLike[str]) -> dict[str, Any]:
    """``document`` (a parsed ``study.json``) if every field this tool reads is what ``tune`` writes,
    else :class:`StudyFileError` naming ``path`` and the field. Every string anywhere one line of
    printable text, every number finite; what a table or figure shows (``plan.variant`` a name,
    ``plan.label``, each parameter's name and spec, each chosen text value) a label
    (:func:`empathy_zoo.names.check_label`); the objective's metric and its reduction the suite's, the
    metric one ``tune`` takes for the study's environment
    (:func:`~leaderboard.study_plan_checks.check_moves`), its direction the metric's
    (:func:`~empathy_zoo.training.study_plan.objective_direction`); ``experiment``, ``variant``,
    ``method``, ``env`` and ``env_kwargs`` one experiment's
    (:func:`~leaderboard.study_plan_checks.plan_worlds`); each env step count a whole number within
    ``trials × tuning seeds × steps`` at their bounds; each trial's state one ``tune`` writes, its wall
    time within ten years; every parameter value one of the plan's parameters, within its range (a
    ``choice``'s one of its values: a number or a boolean as :func:`tomllib` reads the spec's text, text
    as text), every trial but an interrupted one holding each of them; ``schema`` the one ``tune``
    writes (or none); a range's ends ``LOW < HIGH`` within :data:`~empathy_zoo.limits.MAX_RANGE_END`, so
    the figure's margins are floats; the best value finite, within its metric's range.
    The fields agree with each other: ``trials`` not empty, each trial's number its own and below their
    count (``tune`` numbers them from 0); every trial's ``steps_trained`` (``tune`` writes it) its
    curve's last step, ``env_steps_trained`` the counted trials' sum times the tuning seeds; a finished
    trial's curve up to the budget's last step, its ``value`` and every trial's ``last_value`` what its
    curve gives over the objective (last point or mean, up to float rounding), no ``value`` for a trial
    that did not finish; ``best`` set once a trial finished; ``plan.budget.trials`` the trials
    ``env_steps_at_most`` holds, ``trials_done`` (an int) the counted ones; an ``int`` range of whole
    ends, a ``log`` range above 0; every value of a trial (``value``, ``last_value``, each point of its
    ``curve`` and each seed's part of it) within its metric's range in the study's world
    (:func:`~leaderboard.study_plan_checks.metric_bounds`); each curve point's ``per_seed`` one value
    per tuning seed, its step the next of the plan's evaluation schedule (every ``eval_interval`` steps
    and the budget's last); ``best`` the finished trial its ``number`` names, with its value and
    parameters, and no finished trial better in the objective's ``direction``; the budget ``trials ×
    tuning seeds × steps`` for at most :data:`~empathy_zoo.limits.MAX_TRIALS` trials, no more trials
    than it holds (an interrupted trial, run again, not counted) and ``env_steps_trained`` within it."""
    check = DocumentChecker(
        Path(path), StudyFileError, "a study file", "a study that empathy-zoo tune wrote", "move it away (tune writes it again)"
    )
    study = check.table(document, "(the whole file)")
    for key, item in study.items():
        check.plain(item, key)  # (every string one line of printable text, every number finite)
    check.has(study, ("plan", "env_steps_trained", "best", "trials"), "")
    schema = study.get("schema", STUDY_SCHEMA)
    if isinstance(schema, bool) or not isinstance(schema, int) or schema != STUDY_SCHEMA:
        raise check.fail(
            "schema", f"{STUDY_SCHEMA}, the layout tune writes (or none, a study written before it)", study["schema"]
        )
    plan = check.table(study["plan"], "plan")
    check.has(plan, ("variant", "label", "params", "objective", "budget", "tuning_seeds"), "plan.")
    check.name(plan["variant"], "plan.variant")
    check.label(plan["label"], "plan.label")
    objective = check.table(plan["objective"], "plan.objective")
    check.has(objective, ("metric", "direction"), "plan.objective.")
    metric = objective["metric"]
    if metric not in METRIC_NAMES:
        raise check.fail("plan.objective.metric", f"one of the suite's metrics ({', '.join(METRIC_NAMES)})", metric)
    if objective.get("over", "last") not in ("last", "curve"):
        raise check.fail("plan.objective.over", "last or curve", objective["over"])
    direction = objective["direction"]
    if direction not in DIRECTIONS:
        raise check.fail("plan.objective.direction", " or ".join(DIRECTIONS), direction)
    if direction != objective_direction(metric):
        raise check.fail(
            "plan.objective.direction",
            f"{objective_direction(metric)}, how tune optimises {metric} (its fixed direction)",
            direction,
        )
    worlds = plan_worlds(check, plan)
    check_moves(check, worlds, metric)
    budget = check.table(plan["budget"], "plan.budget")
    check.has(budget, ("env_steps_at_most", "steps", "eval_interval"), "plan.budget.")
    at_most = check.integer(budget["env_steps_at_most"], "plan.budget.env_steps_at_most", 1, MAX_ENV_STEPS)
    steps = check.integer(budget["steps"], "plan.budget.steps", 1, MAX_STEPS)
    interval = check.integer(budget["eval_interval"], "plan.budget.eval_interval", 1, MAX_STEPS)
    seeds = tuning_seeds(check, plan["tuning_seeds"])
    per_trial = len(seeds) * steps
    if at_most % per_trial or not 1 <= at_most // per_trial <= MAX_TRIALS:
        raise check.fail(
            "plan.budget.env_steps_at_most",
            f"trials × {len(seeds):,} tuning seeds × {steps:,} steps, for 1 to {MAX_TRIALS:,} trials",
            at_most,
        )
    if "trials" in budget and check.integer(budget["trials"], "plan.budget.trials", 1, MAX_TRIALS) != at_most // per_trial:
        raise check.fail(
            "plan.budget.trials",
            f"{at_most // per_trial:,}, the trials of env_steps_at_most ({at_most:,} = trials × {len(seeds):,} tuning "
            f"seeds × {steps:,} steps)",
            budget["trials"],
        )
    bounds = metric_bounds(metric, worlds)
    trained = check.integer(study["env_steps_trained"], "env_steps_trained", 0, at_most)
    specs = {name: parameter_spec(check, name, spec) for name, spec in check.table(plan["params"], "plan.params").items()}
    over = objective.get("over", "last")
    trials = study["trials"]
    if not isinstance(trials, list) or not trials:
        raise check.fail("trials", "a non-empty array of trials (tune writes one once a trial has run)", trials)
    counted = sum(1 for trial in trials if not (isinstance(trial, dict) and trial.get("state") == "INTERRUPTED"))
    if counted > at_most // per_trial:
        raise check.fail(
            "trials",
            f"at most the plan's {at_most // per_trial:,} trials (an interrupted one not counted)",
            f"{counted:,} trials",
        )
    if "trials_done" in study and check.integer(study["trials_done"], "trials_done", 0, MAX_TRIALS) != counted:
        raise check.fail(
            "trials_done", f"{counted:,}, its trials but the interrupted ones (as tune counts them)", study["trials_done"]
        )
    numbers: dict[int, dict[str, Any]] = {}
    for i, trial in enumerate(trials):
        where = f"trials[{i}]"
        trial = check.table(trial, where)
        check.has(trial, ("state", "params", "steps_trained"), f"{where}.")
        if trial["state"] not in TRIAL_STATES:
            raise check.fail(f"{where}.state", f"one of {', '.join(TRIAL_STATES)}", trial["state"])
        wall = trial.get("wall_time_s")
        if wall is not None and not 0 <= check.finite(wall, f"{where}.wall_time_s") <= MAX_WALL_TIME_S:
            raise check.fail(f"{where}.wall_time_s", f"seconds in [0, {MAX_WALL_TIME_S:,}] (ten years)", wall)
        check_params(check, trial["params"], specs, f"{where}.params", whole=trial["state"] != "INTERRUPTED")
        number = check.integer(trial.get("number"), f"{where}.number", 0, len(trials) - 1)  # (tune numbers them from 0)
        if number in numbers:
            raise check.fail(f"{where}.number", "a trial number of its own (each trial is numbered once)", number)
        numbers[number] = trial
        if trial["state"] == "COMPLETE" and trial.get("value") is None:
            raise check.fail(f"{where}.value", "the value of a finished trial (tune writes one)", trial.get("value"))
        if trial["state"] != "COMPLETE" and trial.get("value") is not None:
            raise check.fail(f"{where}.value", f"null: tune writes no value of a {trial['state']} trial", trial["value"])
        for name in ("value", "last_value"):
            if trial.get(name) is not None:
                _in_range(check, trial[name], f"{where}.{name}", metric, bounds)
        curve = trial.get("curve", [])
        _curve(check, curve, f"{where}.curve", metric, bounds, len(seeds), (steps, interval))
        done = curve[-1]["step"] if curve else 0
        if check.integer(trial["steps_trained"], f"{where}.steps_trained", 0, steps) != done:
            raise check.fail(
                f"{where}.steps_trained",
                f"{done:,}, the step of its curve's last point (0 without one)",
                trial["steps_trained"],
            )
        if trial["state"] == "COMPLETE" and done != steps:
            raise check.fail(
                f"{where}.curve",
                f"points up to the budget's last step ({steps:,}): a finished trial trained all of it",
                f"{len(curve):,} points, the last at step {done:,}",
            )
        _curve_values(check, trial, where, curve, over)
    counted_steps = [trial["steps_trained"] for trial in trials if trial["state"] != "INTERRUPTED"]
    if trained != sum(counted_steps) * len(seeds):
        raise check.fail(
            "env_steps_trained",
            f"{sum(counted_steps) * len(seeds):,}: each counted trial's steps_trained × {len(seeds):,} tuning seeds",
            trained,
        )
    best = study["best"]
    if best is None and any(trial["state"] == "COMPLETE" for trial in trials):
        first = next(trial["number"] for trial in trials if trial["state"] == "COMPLETE")
        raise check.fail("best", f"the best finished trial (trial {first} and maybe others finished)", best)
    if best is not None:
        best = check.table(best, "best")
        check.has(best, ("value", "params"), "best.")
        _in_range(check, best["value"], "best.value", metric, bounds)
        check_params(check, best["params"], specs, "best.params")
        chosen = numbers.get(check.integer(best.get("number"), "best.number", 0))
        if chosen is None or chosen["state"] != "COMPLETE":
            raise check.fail("best.number", f"the number of a finished trial of its {len(numbers):,} trials", best["number"])
        for name in ("value", "params"):
            if best[name] != chosen.get(name):
                raise check.fail(f"best.{name}", f"its trial {best['number']}'s {name}, {shown(chosen.get(name))}", best[name])
        _check_best(check, best, numbers, direction)
    return study


def _check_best(
    check: DocumentChecker, best: Mapping[str, Any], numbers: Mapping[int, Mapping[str, Any]], direction: Any
) -> None:
    """Refuse a ``best`` whose value another finished trial (each holds one) beats in the plan's ``direction``."""
    finished = [trial for trial in numbers.values() if trial["state"] == "COMPLETE"]
    top = (max if direction == "maximize" else min)(finished, key=lambda trial: trial["value"])
    if (best["value"] < top["value"]) if direction == "maximize" else (best["value"] > top["value"]):
        raise check.fail(
            "best.number", f"the best finished trial ({direction}: trial {top['number']}, value {top['value']!r})", best["number"]
        )


def _curve_values(check: DocumentChecker, trial: Mapping[str, Any], where: str, curve: list[Any], over: str) -> None:
    """A trial's ``value`` (a finished one's) and ``last_value`` what its ``curve`` gives over the
    objective (:func:`~empathy_zoo.training.study_plan.curve_value`: its last point or their mean, as
    ``tune`` computes them; equal up to float rounding), ``last_value`` null without a curve."""
    given = curve_value([point["value"] for point in curve], over) if curve else None
    for name in ("value", "last_value") if trial["state"] == "COMPLETE" else ("last_value",):
        value = trial.get(name)
        agrees = value is None if given is None else value is not None and math.isclose(value, given, rel_tol=1e-9, abs_tol=1e-12)
        if not agrees:
            expected = (
                "null, as a trial without a curve has"
                if given is None
                else f"{given!r}, what its curve gives ({'its last point' if over == 'last' else 'the mean of its points'})"
            )
            raise check.fail(f"{where}.{name}", expected, value)


def _in_range(check: DocumentChecker, value: Any, field: str, metric: str, bounds: tuple[float, float | None]) -> float:
    """A finite value of ``metric`` within ``bounds``."""
    low, high = bounds
    number = check.finite(value, field)
    if number < low or (high is not None and number > high):
        span = f"a number >= {low:g}" if high is None else f"a number in [{low:g}, {high:g}]"
        raise check.fail(field, f"{metric}, {span}", value)
    return number


def _curve(
    check: DocumentChecker,
    value: Any,
    where: str,
    metric: str,
    bounds: tuple[float, float | None],
    seeds: int,
    schedule: tuple[int, int],
) -> None:
    """A trial's learning curve: one point per greedy evaluation, in order, at the steps of the plan's
    schedule (``schedule``: its steps and evaluation interval; point ``i`` at ``min((i + 1) · interval,
    steps)``, none past the last), each ``value`` and each of its ``seeds`` parts within ``bounds``."""
    steps, interval = schedule
    if not isinstance(value, list) or len(value) > -(-steps // interval):
        raise check.fail(where, f"an array of at most {-(-steps // interval):,} points (one per greedy evaluation)", value)
    for i, point in enumerate(value):
        at = f"{where}[{i}]"
        point = check.table(point, at)
        check.has(point, ("step", "value", "per_seed"), f"{at}.")
        due = min((i + 1) * interval, steps)
        if check.integer(point["step"], f"{at}.step", 1, MAX_STEPS) != due:
            raise check.fail(
                f"{at}.step",
                f"{due:,}, the next greedy evaluation of the plan's schedule (every {interval:,} steps, and the last: {steps:,})",
                point["step"],
            )
        _in_range(check, point["value"], f"{at}.value", metric, bounds)
        parts = point["per_seed"]
        if not isinstance(parts, list) or len(parts) != seeds:
            raise check.fail(f"{at}.per_seed", f"one value per tuning seed ({seeds:,})", parts)
        for j, part in enumerate(parts):
            _in_range(check, part, f"{at}.per_seed[{j}]", metric, bounds)
