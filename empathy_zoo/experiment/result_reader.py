"""Reading a result file: :func:`check_result` and :func:`read_result`, the one way every reader
(the leaderboard, the verdicts, the command line, a resumed sweep) takes a run's result in.

:func:`empathy_zoo.result_file.check_result_fields` checks the schema, field by field; this
module adds what needs the method registry (:mod:`baselines.registry`): a registered method's
settings, each of the type its settings class declares and within :data:`MAX_SETTING`, then given
to the class (its own range checks), its reward transform (the method's own, by name), and the
description the method gives a run of those settings (:meth:`agents.base.Method.describe`), which the file's must be: a
description that contradicts its settings (a β, a DQN reference) is refused. A
``package.module:NAME`` method is never imported here, so its settings are checked for their shape
only. :func:`read_result` also refuses a file not named ``<run id>.json`` (a copy under another name
would count its run twice), and gives the run as a typed, frozen record
(:class:`~empathy_zoo.experiment.records.RunResult`), made only of a document :func:`check_result` accepted.
"""

from __future__ import annotations

import json
from collections.abc import Mapping
from pathlib import Path
from typing import Any

from empathy_zoo.atomic import read_json
from empathy_zoo.document_checks import DocumentChecker, one_line
from empathy_zoo.experiment.records import RunResult
from empathy_zoo.result_file import ResultFileError, check_result_fields, check_run_id, result_checker
from empathy_zoo.setting_values import MAX_SETTING, recorded_problem

__all__ = ["MAX_SETTING", "check_result", "read_result"]


def check_result(document: Any, path: str | Path) -> dict[str, Any]:
    """``document`` (a parsed result file) if it follows the schema and a registered method's
    settings, reward transform and description are ones it gives a run, and its run id is the one
    its config gives (:func:`~empathy_zoo.result_file.check_run_id`), else
    :class:`~empathy_zoo.result_file.ResultFileError` naming ``path`` and the field."""
    from baselines.registry import METHODS  # (lazily: the registry imports the learners, and torch)

    result = check_result_fields(document, path)
    method = METHODS.get(result["method"])
    if method is not None:
        check = result_checker(Path(path))
        settings = _settings(check, method, result)
        reward = _reward(check, method, result)
        _check_described(check, method, settings, reward, result)
    check_run_id(result_checker(Path(path)), result, document["config"])
    return result


def read_result(path: str | Path, *, named: bool = True) -> RunResult:
    """Read a result file as a :class:`~empathy_zoo.experiment.records.RunResult`; a corrupted or
    malformed one raises ``ValueError`` naming it (and the field), as does (where ``named``) one
    not named ``<run id>.json`` of the run it holds (where a sweep writes it: a file renamed or
    copied under another name would count its run twice; the leaderboard, which reads a whole
    directory, refuses a run counted twice by its own check)."""
    result = check_result(read_json(path), path)
    return RunResult.from_checked(_named(result, path) if named else result)


def _named(result: dict[str, Any], path: str | Path) -> dict[str, Any]:
    """``result`` (checked) if ``path`` is named ``<run id>.json`` of its run, else :class:`ResultFileError`."""
    name = Path(path).name
    if name != f"{result['run_id']}.json":
        raise ResultFileError(
            f"{path}: field run_id: the file is named {name}, but it holds run {result['run_id']} "
            f"({result['run_id']}.json): renamed or copied; move it away (a run is counted once, from its own file)"
        )
    return result


def _settings(check: DocumentChecker, method: Any, result: Mapping[str, Any]) -> Any:
    """The settings object of ``result``'s ``config.settings``: each field one of ``method``'s
    settings class, of the type it declares (:func:`empathy_zoo.setting_values.recorded_problem`, the rule
    every run's settings are built by: :meth:`agents.base.Method.make_settings`), then accepted by the class
    itself (its ranges). A refusal names ``config.settings`` and,
    in it, the setting: ``expected settings of dqn (selfishness: a finite number ...)``."""
    settings = result["config"]["settings"]

    def refuse(why: str, value: Any) -> ValueError:
        return check.fail("config.settings", f"settings of {result['method']} ({one_line(why, 300)})", value)

    problem = recorded_problem(method.settings, settings)
    if problem is not None:
        raise refuse(f"{problem[0]}: {problem[1]}", problem[2])
    try:
        return method.settings(**settings)
    except (TypeError, ValueError, OverflowError) as error:
        raise refuse(str(error), settings) from None


def _reward(check: DocumentChecker, method: Any, result: Mapping[str, Any]) -> Any:
    """The reward transform ``config.reward`` records, which must be ``method``'s: ``null`` for a
    method without one, else a record of the same name (its fields are the file's: a transform may
    have gained a field since the run was made); ``None`` or the method's own transform with the
    file's values of its fields, each checked as a run's is when it is configured
    (:func:`agents.transform_fields.configure_transform`: of its type, within its bound, then the transform's
    own checks), a field it no longer has left as recorded."""
    from agents.transform_fields import TransformFieldError, check_field_value  # (lazily, as the registry: agents imports torch)

    recorded = result["config"].get("reward")
    own = method.reward
    matches = own is None if recorded is None else own is not None and recorded.get("name") == own.name
    if not matches:
        expected = "null (it trains on the environment's reward)" if own is None else f"a reward named {own.name!r}"
        raise check.fail("config.reward", f"{expected}, as {result['method']} trains", recorded)
    if recorded is None:
        return own
    kinds = method.reward_fields()
    fields = {name: value for name, value in recorded.items() if name in kinds}
    for name, value in fields.items():
        try:
            check_field_value(own, name, value, method.name)
        except TransformFieldError as error:
            raise check.fail(f"config.reward.{name}", f"{error.wanted}, as a reward field of {method.name}", value) from None
    try:
        return method.make_reward(fields)
    except (TypeError, ValueError, OverflowError) as error:
        why = one_line(str(error), 300)
        raise check.fail("config.reward", f"reward fields {result['method']} takes ({why})", recorded) from None


def _check_described(check: DocumentChecker, method: Any, settings: Any, reward: Any, result: Mapping[str, Any]) -> None:
    """``config.description`` is what ``method`` describes a run of ``settings`` as
    (:meth:`agents.base.Method.describe`): its family, target, swap, β, γ and exploration schedule;
    ``dqn_reference`` only for a reference method's run on the environment's reward at β = 1; the
    reward it records ``config.reward``. The first field that differs (a β or a DQN reference its
    settings contradict) is named."""
    config = result["config"]
    try:
        expected = _as_json(method.describe(settings, reward))
    except (TypeError, ValueError, OverflowError) as error:
        why = one_line(str(error), 200)
        raise check.fail("config.settings", f"settings {result['method']} describes ({why})", config["settings"]) from None
    expected["reward"] = config.get("reward")
    expected["dqn_reference"] = bool(
        method.dqn_reference and config.get("reward") is None and expected["selfishness"] in (None, 1.0)
    )
    described = config["description"]
    first = ("selfishness", "gamma", "exploration")  # (what the settings give, before what follows from it)
    for field in sorted(expected, key=lambda name: name not in first):
        value = expected[field]
        if described.get(field) != value:
            raise check.fail(
                f"config.description.{field}",
                f"{value!r}, what {result['method']} describes a run of these settings as (it contradicts them)",
                described.get(field),
            )


def _as_json(value: Any) -> Any:
    """``value`` as a JSON file holds it (tuples as lists)."""
    return json.loads(json.dumps(value))
