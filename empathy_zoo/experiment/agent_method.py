"""An agent file's method, checked against the methods registered here.

The agent file's reader (:mod:`empathy_zoo.agent_file`) sits below the method registry, so it checks
a header's ``method`` only for its shape: a registered method's name, or a ``package.module:NAME``
plug-in kept as text. :func:`check_agent_method` adds what needs the registry, as
:func:`empathy_zoo.experiment.result_reader.check_result` does for a result file: a name that says
it is registered (no ``package.module:`` form) must be one, and its header's ``settings`` that
method's settings, each in its range (the method's own settings check). A plug-in's name is never
imported.
"""

from __future__ import annotations

from typing import Any

from empathy_zoo.agent_file import AgentFileError
from empathy_zoo.document_checks import one_line, shown
from empathy_zoo.import_names import PLUGIN_NAME

__all__ = ["check_agent_method"]


def check_agent_method(agent: Any) -> Any:
    """``agent`` (loaded by :func:`~empathy_zoo.agent_file.load_agent`) when its header's ``method``
    is a method registered here or a ``package.module:NAME`` plug-in (kept as text, nothing
    imported); else :class:`~empathy_zoo.agent_file.AgentFileError` naming its file and the field."""
    from baselines.registry import METHODS  # (lazily: the registry imports the learners, and torch)

    described = agent.describe()
    method = described.get("method")
    if isinstance(method, str) and method in METHODS:
        try:
            METHODS[method].make_settings(dict(described.get("settings") or {}))
        except (ValueError, TypeError) as error:  # (a setting of another type fails its range check with TypeError)
            raise AgentFileError(
                f"agent file {described.get('file')}: field header.settings: expected {method}'s settings, each in its "
                f"range ({one_line(str(error), 200)}); move it away (train the run again to make it anew)"
            ) from None
        return agent
    if isinstance(method, str) and PLUGIN_NAME.fullmatch(method):
        return agent
    raise AgentFileError(
        f"agent file {described.get('file')}: field header.method: expected a method registered here (one of "
        f"{len(METHODS)}: {', '.join(sorted(METHODS)[:4])}, ...) or a package.module:NAME plug-in (kept as text, never "
        f"imported), got {shown(method)}; move it away (train the run again to make it anew)"
    )
