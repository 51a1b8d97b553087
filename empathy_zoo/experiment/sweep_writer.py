"""Writing one experiment as a sweep file: what ``empathy-zoo tune`` leaves as ``tuned.toml``.

:func:`experiment_sweep` gives the TOML text of a sweep file (:mod:`~empathy_zoo.experiment.sweep_file`)
that declares exactly the runs of one experiment on the seeds given: a ``[sweep]`` table (seeds and
budget), one ``[envs.<variant>]`` table (the environment, its arguments, its fixed agents when the
variant names them) and one ``[[methods]]`` entry (the settings and reward-transform fields that
differ from the method's, and a label). The text is read back before it is returned and must
declare those very runs (:class:`~empathy_zoo.experiment.model.RunSpec` configs equal), so a file
this module writes is a file ``empathy-zoo reproduce --profile FILE`` trains as meant.
"""

from __future__ import annotations

import json
import math
import re
import tomllib
from collections.abc import Mapping, Sequence
from dataclasses import replace
from typing import Any

from empathy_zoo.experiment.model import RunSpec
from empathy_zoo.experiment.sweep_file import REWARD_TABLE, parse_sweep

__all__ = ["experiment_sweep", "toml_value"]

_BARE_KEY = re.compile(r"[A-Za-z0-9_-]+")


def toml_value(value: Any) -> str:
    """``value`` (a bool, int, float, string, list or table of them) as a TOML value."""
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, int):
        return str(value)
    if isinstance(value, float):
        if math.isnan(value):
            return "nan"
        if math.isinf(value):
            return "inf" if value > 0 else "-inf"
        return repr(value)
    if isinstance(value, str):
        return json.dumps(value, ensure_ascii=False).replace("\x7f", "\\u007f")
    if isinstance(value, (list, tuple)):
        return "[" + ", ".join(toml_value(item) for item in value) + "]"
    if isinstance(value, Mapping):
        return "{ " + ", ".join(f"{_key(str(k))} = {toml_value(v)}" for k, v in value.items()) + " }" if value else "{}"
    raise ValueError(f"cannot write {type(value).__name__} {value!r} as a TOML value")


def _key(name: str) -> str:
    return name if _BARE_KEY.fullmatch(name) else json.dumps(name, ensure_ascii=False)


def experiment_sweep(spec: RunSpec, seeds: Sequence[int], label: str | None = None, comment: str = "", name: str = "") -> str:
    """The sweep file of ``spec``'s experiment on ``seeds``, labelled ``label`` (default: the
    entry's own), with ``comment`` (lines) at its top and ``name`` as its ``[sweep]`` name (default:
    the file's stem, as for any sweep file)."""
    entry = spec.entry
    variant = spec.variant.label
    lines = [f"# {line}".rstrip() for line in comment.splitlines()]
    if lines:
        lines.append("")
    lines.append("[sweep]")
    if name:
        lines.append(f"name = {toml_value(name)}")
    lines.append(f"seeds = {toml_value(list(seeds))}")
    for key in ("steps", "eval_interval", "eval_episodes"):
        lines.append(f"{key} = {toml_value(getattr(spec.budget, key))}")
    lines += ["", f"[envs.{_key(variant)}]", f"env = {toml_value(spec.env)}"]
    lines += [f"{_key(key)} = {toml_value(value)}" for key, value in spec.variant.kwargs.items()]
    if spec.variant.fixed is not None:
        lines.append(f"fixed = {toml_value(dict(spec.variant.fixed))}")
    lines += ["", "[[methods]]", f"method = {toml_value(entry.name)}"]
    shown = label if label is not None else entry.label
    if shown is not None:  # (braces are a label template's placeholders: these are text)
        lines.append(f"label = {toml_value(shown.replace('{', '{{').replace('}', '}}'))}")
    lines += [f"{_key(key)} = {toml_value(value)}" for key, value in entry.changed_settings().items()]
    lines += [f"{REWARD_TABLE}.{_key(key)} = {toml_value(value)}" for key, value in entry.changed_reward().items()]
    text = "\n".join(lines) + "\n"
    _check_round_trip(text, spec, seeds, shown)
    return text


def _check_round_trip(text: str, spec: RunSpec, seeds: Sequence[int], label: str | None) -> None:
    """Read ``text`` back and check it declares ``spec``'s experiment on ``seeds`` (a ``ValueError``
    names the first difference: a value TOML cannot carry as the settings class takes it)."""
    read = parse_sweep(tomllib.loads(text), source="<written sweep file>")
    expected = replace(spec, entry=replace(spec.entry, label=label))
    wanted = [replace(expected, seed=seed).config() for seed in seeds]
    got = [s.config() for s in read]
    if got != wanted:
        # (unequal on purpose: where one list is a prefix of the other, the first difference is where it ends)
        first = next((i for i, (a, b) in enumerate(zip(got, wanted, strict=False)) if a != b), min(len(got), len(wanted)))
        differs = (
            sorted(k for k in set(got[first]) | set(wanted[first]) if got[first].get(k) != wanted[first].get(k))
            if (first < min(len(got), len(wanted)))
            else ["the number of runs"]
        )
        raise ValueError(
            f"the sweep file written for {spec.experiment_id} reads back as other runs ({', '.join(differs)} differ)"
        )
