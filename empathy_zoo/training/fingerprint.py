"""Which code made a run: :class:`CodeFingerprint`, and whether finished runs were made by the code
that runs now (:func:`code_changes`).

A run is identified by its configuration only (:attr:`RunSpec.run_id`), so its result file's name
says nothing of the code that made it. Each result file records, beside ``version`` (the
empathy-zoo version) and ``commit`` (the git commit it ran from), ``plugin_sha256``: for every
plug-in the run names by module path (its ``package.module:NAME`` method, its
``package.module:ClassName`` fixed policies, written as a string or as a table
``{"policy": "package.module:ClassName", ...}``) the SHA-256 of that module's source file, by
module name. Built-in methods and policies are part of empathy-zoo: its version covers them.

What counts when a finished run is asked for again:

* the empathy-zoo version and the plug-in hashes: when either differs, the result file was made
  by other code (*changed*), and :func:`train_runs` refuses to reuse it unless told to retrain it;
* the update kernel (``update_kernel``: ``"numba"`` or ``"torch"``, :attr:`RunnerOptions.update_kernel
  <empathy_zoo.training.options.RunnerOptions.update_kernel>`), for learners that have a choice:
  the two sum in another order, so a run made by the other kernel has other last bits (*changed*);
  a file without the field (written before it was recorded, all by the torch kernel, under an
  older version that already counts as changed) or a learner without a choice is not compared;
* not the commit: it is recorded for provenance only, since most commits do not touch a given
  method, and a new commit alone would throw away results that are still right;
* a file without ``plugin_sha256`` (written before the hashes were recorded) counts as made by
  the version in its ``version`` with unknown plug-in hashes: with another version it is changed;
  with the same one a built-in run is the same code, a plug-in run *cannot be told* (reused, with
  a note). So is a run whose file or current code has a plug-in hash ``null`` (below).

The hash is of the module's source file (:func:`inspect.getsourcefile`); a module loaded without
one (a compiled extension, a sourceless ``.pyc``) is hashed by the file it was loaded from; a
module with no file at all (built in memory, frozen) has hash ``None``: whether it changed cannot
be told. Each loaded module is hashed once, the first time it is asked for (:func:`train_runs`
asks before training), so the hash is of the code as it was loaded, not of later edits; a module
imported again (a new process, or removed from ``sys.modules``) is hashed again. Only the named
module is hashed: edits to other modules it imports are not seen.
"""

from __future__ import annotations

import hashlib
import inspect
import sys
from collections.abc import Iterable, Mapping
from dataclasses import dataclass
from functools import cache
from pathlib import Path
from types import ModuleType
from typing import TYPE_CHECKING, Any

from empathy_zoo.import_names import PLUGIN_NAME, resolve_name
from empathy_zoo.policies import policy_entry
from empathy_zoo.provenance import git_commit, package_version

if TYPE_CHECKING:
    from empathy_zoo.experiment.model import RunSpec
    from empathy_zoo.experiment.records import RunResult

__all__ = [
    "CodeFingerprint",
    "kernel_argument",
    "update_kernel_of",
    "expected_update_kernel",
    "run_fingerprint",
    "recorded_fingerprint",
    "plugin_names",
    "module_sha256",
    "code_changes",
    "listing",
    "SHOWN_RUNS",
]

SHOWN_RUNS = 3
"""Run ids named per reason in a message; the rest are counted."""
_SHOWN_HASH = 12
"""Hex digits of a hash quoted in a message."""


@dataclass(frozen=True)
class CodeFingerprint:
    """The code that made (or would make) a run."""

    version: str | None
    """empathy-zoo version (it covers the built-in methods and policies); ``None`` = not recorded."""
    commit: str | None
    """Git commit of the checkout empathy-zoo ran from (provenance only: never compared)."""
    plugins: Mapping[str, str | None] | None
    """SHA-256 of each plug-in module's source file by module name (``None``: a module without a
    file); ``None`` = not recorded (a result file written before the hashes were)."""
    update_kernel: str | None = None
    """The update kernel of the run's learner (``"numba"`` or ``"torch"``); ``None`` = its learner
    has no choice of kernels, or not recorded."""

    def fields(self) -> dict[str, Any]:
        """The fingerprint as a result file records it (``version``, ``commit``, ``plugin_sha256``,
        ``update_kernel``)."""
        return {
            "version": self.version,
            "commit": self.commit,
            "plugin_sha256": dict(self.plugins or {}),
            "update_kernel": self.update_kernel,
        }

    def changes_since(self, recorded: CodeFingerprint) -> tuple[list[str], list[str]]:
        """What differs between ``recorded`` (a result file's) and this (the current code), and
        what cannot be told, each as reasons for a message."""
        changed: list[str] = []
        unknown: list[str] = []
        if recorded.version is None:
            unknown.append("the result file records no empathy-zoo version")
        elif recorded.version != self.version:
            changed.append(f"made by empathy-zoo {recorded.version}, this is {self.version}")
        if None not in (recorded.update_kernel, self.update_kernel) and recorded.update_kernel != self.update_kernel:
            changed.append(
                f"made with the {recorded.update_kernel} update kernel, this would use {self.update_kernel} "
                f"(--update-kernel {recorded.update_kernel} goes on with it)"
            )
        for module, digest in sorted((self.plugins or {}).items()):
            if recorded.plugins is None:
                unknown.append(
                    f"made before result files recorded plug-in source hashes: whether plug-in module "
                    f"{module} changed cannot be told"
                )
                continue
            before = recorded.plugins.get(module)
            if digest is None or before is None:
                unknown.append(
                    f"plug-in module {module} {'has' if digest is None else 'had'} no source file to hash: "
                    "whether it changed cannot be told"
                )
            elif digest != before:
                changed.append(
                    f"plug-in module {module} changed since these results were made (source hash "
                    f"{before[:_SHOWN_HASH]}… → {digest[:_SHOWN_HASH]}…)"
                )
        return changed, unknown


def plugin_names(spec: RunSpec) -> dict[str, tuple[str, str]]:
    """The plug-ins ``spec`` names by module path, by module: ``(plug-in name, kind)`` (its method
    and its fixed policies, each a name or a table with a ``"policy"`` key)."""
    named = [(spec.method, "method")]
    for entry in map(policy_entry, spec.fixed_policies().values()):
        named.append((entry if isinstance(entry, str) else entry["policy"], "fixed policy"))
    return {name.partition(":")[0]: (name, kind) for name, kind in named if PLUGIN_NAME.fullmatch(name)}


def kernel_argument(learner: Any, update_kernel: str) -> dict[str, str]:
    """The keyword that asks ``learner`` (a learner class or factory) for ``update_kernel``: empty
    for ``"auto"`` (the learner's own default: a subclass may pin its kernel) and for a learner
    without a choice of kernels (it has no ``resolved_update_kernel``)."""
    return {"update_kernel": update_kernel} if update_kernel != "auto" and hasattr(learner, "resolved_update_kernel") else {}


def update_kernel_of(learner: Any) -> str | None:
    """The update kernel a built learner uses (``"numba"`` or ``"torch"``), ``None`` for a learner
    without a choice of kernels."""
    kernel = getattr(learner, "update_kernel", None) if hasattr(learner, "resolved_update_kernel") else None
    return kernel if isinstance(kernel, str) else None


def expected_update_kernel(spec: RunSpec, update_kernel: str, device: str) -> str | None:
    """The update kernel ``spec``'s learner would use here with ``update_kernel`` on ``device``
    (``None``: its learner has no choice)."""
    learner = spec.method_object().learner
    resolve = getattr(learner, "resolved_update_kernel", None)
    return None if resolve is None else str(resolve(**kernel_argument(learner, update_kernel), device=device))


def run_fingerprint(spec: RunSpec, update_kernel: str | None = None) -> CodeFingerprint:
    """The fingerprint of the code that trains ``spec`` here, now (its plug-ins are imported),
    with the update kernel it trains with (``None``: none to choose)."""
    plugins = {}
    for module, (name, kind) in plugin_names(spec).items():
        resolve_name(name, {}, kind)  # imports the module (or says why it cannot)
        plugins[module] = module_sha256(sys.modules[module])
    return CodeFingerprint(package_version(), git_commit(), plugins, update_kernel)


def recorded_fingerprint(result: RunResult) -> CodeFingerprint:
    """The fingerprint a result file records (``plugins`` is ``None`` in files older than it,
    ``update_kernel`` in files older than that field)."""
    plugins = None if result.plugin_sha256 is None else dict(result.plugin_sha256)
    return CodeFingerprint(result.version, result.commit, plugins, result.update_kernel)


@cache
def module_sha256(module: ModuleType) -> str | None:
    """SHA-256 (hex) of the file ``module`` was loaded from: its source file, else the file itself
    (a compiled extension, a sourceless ``.pyc``); ``None`` for a module without a file. Once per
    loaded module: a module imported again is a new module, hashed again."""
    try:
        path = inspect.getsourcefile(module)
    except TypeError:  # a built-in module
        path = None
    path = path or getattr(module, "__file__", None)
    if path is None or not Path(path).is_file():
        return None
    return hashlib.sha256(Path(path).read_bytes()).hexdigest()


def code_changes(
    specs: Iterable[RunSpec],
    results: Mapping[str, RunResult],
    update_kernel: str = "auto",
    device: str = "cpu",
) -> tuple[dict[str, list[str]], dict[str, list[str]]]:
    """Fingerprint every run of ``specs`` (so its plug-ins are hashed before it trains), as trained
    with ``update_kernel`` on ``device``, and compare it with the one recorded by its result file
    in ``results`` (by run id; runs without one are not finished): the run ids made by other code
    than this, and those whose code cannot be told, each by reason (see the module documentation)."""
    changed: dict[str, list[str]] = {}
    unknown: dict[str, list[str]] = {}
    for spec in specs:
        current = run_fingerprint(spec, expected_update_kernel(spec, update_kernel, device))
        if spec.run_id not in results:
            continue
        differs, untold = current.changes_since(recorded_fingerprint(results[spec.run_id]))
        for groups, reasons in ((changed, differs), (unknown, untold)):
            for reason in reasons:
                groups.setdefault(reason, []).append(spec.run_id)
    return changed, unknown


def listing(groups: Mapping[str, list[str]]) -> str:
    """``reason (runs a, b, c and 4 more); reason (run d)``: each reason with the runs it holds for."""
    parts = []
    for reason, run_ids in groups.items():
        shown = ", ".join(run_ids[:SHOWN_RUNS]) + (f" and {len(run_ids) - SHOWN_RUNS} more" if len(run_ids) > SHOWN_RUNS else "")
        parts.append(f"{reason} ({'runs' if len(run_ids) > 1 else 'run'} {shown})")
    return "; ".join(parts)
