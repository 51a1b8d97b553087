"""Plug-in names resolved to what they name: a registered entry, or the object a
``package.module:Name`` string imports (shared by every plug-in point: fixed policies, learning
methods)."""

from __future__ import annotations

import importlib
import os
import re
import sys
from collections.abc import Mapping
from typing import Any

__all__ = ["resolve_name", "is_registered", "PLUGIN_NAME", "MAX_PLUGIN_NAME"]

MAX_PLUGIN_NAME = 500
"""Most characters a registered name or a ``package.module:Name`` may have (docs/limits.md)."""

_IDENTIFIER = r"[A-Za-z_][A-Za-z0-9_]*"
PLUGIN_NAME = re.compile(rf"{_IDENTIFIER}(?:\.{_IDENTIFIER})*:{_IDENTIFIER}")
"""What a ``package.module:Name`` plug-in name looks like."""


def is_registered(spec: Any, registry: Mapping[str, Any], kind: str) -> bool:
    """Whether ``spec`` is a name in ``registry`` (``True``) or a well-formed ``package.module:Name``
    (``False``; nothing is imported); any other ``spec`` raises ``ValueError`` saying why."""
    if not isinstance(spec, str) or not spec:
        raise ValueError(f"a {kind} is named by a non-empty string, got {spec!r:.80}")
    if len(spec) > MAX_PLUGIN_NAME:
        raise ValueError(f"a {kind}'s name is at most {MAX_PLUGIN_NAME} characters, got {len(spec):,} ({spec[:40]!r}...)")
    if spec in registry:
        return True
    if ":" not in spec:
        raise ValueError(f"unknown {kind} {spec!r}; registered: {sorted(registry)} (or give 'package.module:ClassName')")
    if not PLUGIN_NAME.fullmatch(spec):
        raise ValueError(
            f"{spec!r} is not a valid 'package.module:Name' (dotted module path, a colon, a name) "
            f"nor a registered {kind}: {sorted(registry)}"
        )
    return False


def resolve_name(spec: str, registry: Mapping[str, Any], kind: str) -> Any:
    """Return ``registry[spec]``, or the object named by a ``package.module:Name`` string
    (importable from ``sys.path`` or the working directory). Importing it runs that module's
    code: name only modules you trust (docs/limits.md).

    Raises ``ValueError`` naming the unknown entry and what is registered, a malformed name, or
    what importing the module raised.
    """
    if is_registered(spec, registry, kind):
        return registry[spec]
    module_name, _, attribute = spec.partition(":")
    if os.getcwd() not in sys.path:  # like `python -m`: modules of the working directory resolve
        sys.path.append(os.getcwd())
    try:
        module = importlib.import_module(module_name)
    except ImportError as error:
        raise ValueError(f"cannot import module {module_name!r} for {kind} {spec!r}: {error}") from error
    except Exception as error:  # a plug-in's own code failed while it was imported
        raise ValueError(
            f"importing module {module_name!r} for {kind} {spec!r} raised {type(error).__name__}: {error}"
        ) from error
    try:
        return getattr(module, attribute)
    except AttributeError:
        raise ValueError(f"module {module_name!r} has no {attribute!r} (for {kind} {spec!r})") from None
