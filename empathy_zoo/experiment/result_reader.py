"""Reading a result file: :func:`check_result` and :func:`read_result`, the one way every reader
(the leaderboard, the verdicts, the command line, a resumed sweep) takes a run's result in.

:func:`empathy_zoo.result_file.check_result_fields` checks the schema, field by field; this
module adds what needs the method registry (:mod:`baselines.registry`): a registered method's
settings, given to its settings class. A ``package.module:NAME`` method is never imported here,
so its settings are checked for their shape only.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

from empathy_zoo.atomic import read_json
from empathy_zoo.document_checks import one_line
from empathy_zoo.result_file import check_result_fields, result_checker

__all__ = ["check_result", "read_result"]


def check_result(document: Any, path: str | Path) -> dict[str, Any]:
    """``document`` (a parsed result file) if it follows the schema and a registered method's
    settings are ones its settings class accepts, else :class:`~empathy_zoo.result_file.ResultFileError`
    naming ``path`` and the field."""
    from baselines.registry import METHODS  # (lazily: the registry imports the learners, and torch)

    result = check_result_fields(document, path)
    method = METHODS.get(result["method"])
    if method is not None:
        settings = result["config"]["settings"]
        try:
            method.settings(**settings)
        except (TypeError, ValueError, OverflowError) as error:
            raise result_checker(Path(path)).fail(
                "config.settings", f"settings of {result['method']} ({one_line(str(error), 200)})", settings
            ) from None
    return result


def read_result(path: Path) -> dict[str, Any]:
    """Read a result file; a corrupted or malformed one raises ``ValueError`` naming it (and the field)."""
    return check_result(read_json(path), path)
