"""A run's id, derived from the configuration its result file records.

A run id is ``<variant>__<method>-<hash>__s<seed>``: the hash is the first 8 hex digits of the
SHA-256 of the configuration without its seed and description (the description is derived from
the rest), so the runs of one experiment share all but the seed. The trainer names its runs with
:func:`run_id`; the result and agent file readers recompute it, so a file whose configuration was
changed after the run cannot pass as that run (or be pooled with its experiment).
"""

from __future__ import annotations

import hashlib
import json
from collections.abc import Mapping
from typing import Any

NOT_IDENTITY = ("seed", "description")
"""Fields of a configuration that are no part of its experiment's hash."""


def config_hash(config: Mapping[str, Any]) -> str:
    """The experiment hash of ``config``: SHA-256 of its JSON (keys sorted) without
    :data:`NOT_IDENTITY`, first 8 hex digits."""
    identity = {key: value for key, value in config.items() if key not in NOT_IDENTITY}
    return hashlib.sha256(json.dumps(identity, sort_keys=True, default=str).encode()).hexdigest()[:8]


def experiment_id(variant: str, method: str, config: Mapping[str, Any]) -> str:
    """``<variant>__<method>-<hash>``: ``method`` with ``:`` and ``.`` as ``_`` (a file-safe name)."""
    return f"{variant}__{method.replace(':', '_').replace('.', '_')}-{config_hash(config)}"


def run_id(variant: str, method: str, config: Mapping[str, Any], seed: int) -> str:
    """``<variant>__<method>-<hash>__s<seed>`` (:func:`experiment_id`)."""
    return f"{experiment_id(variant, method, config)}__s{seed}"
