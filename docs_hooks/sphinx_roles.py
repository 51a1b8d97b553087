"""A hook of the documentation site (mkdocs.yml ``hooks``): the docstrings' Sphinx roles
(``:class:`RunSpec```, ``:meth:`~RunSpec.of```) show as the code they name, not as raw roles.

mkdocstrings renders a role's backticks as code and leaves the role's name before it
(``:class:<code>RunSpec</code>``); this drops the name, and for a ``~`` target keeps its last
dotted part, as Sphinx shows it."""

from __future__ import annotations

import re
from typing import Any

ROLE = re.compile(r":(?:py:)?(?:class|meth|func|mod|attr|data|exc|obj|const|term|ref):<code>(~?)([^<]*)</code>")
"""A role's name, then its target rendered as code (``~`` asks for the last dotted part only)."""


def shown(match: re.Match[str]) -> str:
    """The code a role names: the whole target, or its last dotted part after ``~``."""
    tilde, target = match.group(1), match.group(2)
    return f"<code>{target.rsplit('.', 1)[-1] if tilde else target}</code>"


def without_roles(html: str) -> str:
    """``html`` with every rendered role replaced by the code it names."""
    return ROLE.sub(shown, html)


def on_page_content(html: str, **kwargs: Any) -> str:
    """mkdocs' hook: each page's HTML, rendered roles replaced."""
    return without_roles(html)
