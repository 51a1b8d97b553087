"""Which ensembles a run of ``train_runs`` trains: checkpointed ones first, as they were, then new ones.

An ensemble's checkpoint (``checkpoints/<env>-<digest>.pt``) holds the state of its runs in
lockstep, so it can only continue as that same ensemble. Beside it, ``<env>-<digest>.runs.json``
lists the specs of those runs. Before any training, :func:`plan_ensembles` looks at every
checkpoint of the output directory:

* one that holds a run still to do resumes **as it was checkpointed** (said when that is not how
  this invocation would have grouped its runs), whatever the grouping of
  this invocation would be (another ``--max-parallel-runs``, other ``--seeds``, some of its
  results written already): its runs already finished are recomputed but not written again, and
  its runs not asked for this time are finished and written too (nothing is lost);
* one whose runs are all finished is removed;
* one that holds only runs not asked for here (another sweep's) is kept;
* one that holds runs asked for here beside runs that cannot be rebuilt from those asked for is
  kept (it resumes when they are asked for too), and its runs asked for start again from scratch;
  where those runs, grouped as asked, would train under its very name (its list of runs was
  edited), it is set aside as ``<name>.disowned`` instead, so that nothing resumes from it or
  deletes it;
* one that cannot be resumed (the code that defines its runs changed, or it overlaps a newer one)
  is removed, and its runs still to do start again from scratch;
* one that holds other runs than its name says (a renamed or copied file) is set aside as
  ``<name>.misnamed`` (said, with the name that would resume it): under its name it would be
  taken for the checkpoint of other runs.

A file set aside takes the first of ``.misnamed`` (``.unreadable``), ``.misnamed.2``, … that names
nothing yet: nothing is ever renamed over a file, a link or a folder, a user's or one set aside
before.

The list of runs beside a checkpoint is data, never code: it is read as JSON and each record is
compared with the :meth:`~empathy_zoo.experiment.model.RunSpec.request` of the runs asked for
here (and its run id with theirs); a record is never resolved, so it can name no method or
policy to import. A record that equals a run asked for but for its seed is that run with the
record's seed (another ``--seeds``); any other record cannot be rebuilt here. A list that cannot
be read is set aside (``<name>.runs.json.unreadable``, or ``.unreadable.2``, …, said), and the checkpoint's own run ids
are used instead.

Every decision but a plain resume is reported through ``on_note``, one line each.

Nothing is changed while the checkpoints are looked at: :func:`survey_ensembles` reads them (and
loads each checkpoint that resumes, or whose list of runs cannot be read, with the checks of
:func:`~empathy_zoo.training.checkpoint.load_checkpoint`) and raises any refusal (a damaged
checkpoint, a checkpoint that holds other runs than its list of runs) before a file is removed or
set aside; :meth:`EnsemblePlan.apply` then makes those changes, in order, and says each. So a
refused command leaves ``checkpoints/`` as it was, an unreadable list of runs included.
"""

from __future__ import annotations

import hashlib
import inspect
import json
import os
import re
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any

from empathy_zoo.atomic import read_json, write_json_atomic
from empathy_zoo.data_files import data_files
from empathy_zoo.experiment.model import RunSpec, group_specs
from empathy_zoo.names import check_path_name
from empathy_zoo.result_file import result_path
from empathy_zoo.training.checkpoint import RUNS_LIST_SUFFIX, CheckpointError, load_checkpoint, runs_list_path

__all__ = [
    "CHECKPOINT_DIR",
    "EnsemblePlan",
    "checkpoint_path",
    "manifest_path",
    "write_manifest",
    "remove_checkpoint",
    "plan_ensembles",
    "survey_ensembles",
]

CHECKPOINT_DIR = "checkpoints"
MANIFEST_SUFFIX = RUNS_LIST_SUFFIX
"""Suffix of the file beside a checkpoint that lists its runs' specs."""
MANIFEST_FORMAT = 2
"""Format of that list: 2, each record a run's ``request()`` with its ``run_id``; 1 (read too): without it."""
UNREADABLE_SUFFIX = ".unreadable"
"""Suffix a list of runs that cannot be read is set aside with."""
MISNAMED_SUFFIX = ".misnamed"
"""Suffix a checkpoint is set aside with when it holds other runs than its name says (renamed or copied)."""
DISOWNED_SUFFIX = ".disowned"
"""Suffix a checkpoint is set aside with when its list of runs cannot be rebuilt from the runs asked
for, yet those runs, grouped as this invocation groups them, would train under its very name."""
REQUEST_KEYS = frozenset(inspect.signature(RunSpec.of).parameters)
"""The keys a record of a list of runs may hold (those of :meth:`RunSpec.request`), besides ``run_id``."""


def checkpoint_path(out_dir: Path, specs: Sequence[RunSpec]) -> Path:
    """The checkpoint of the ensemble ``specs`` (in this order)."""
    return _checkpoint_file(out_dir, specs[0].env, [s.run_id for s in specs])


def _checkpoint_file(out_dir: Path, env: str, run_ids: Sequence[str]) -> Path:
    digest = hashlib.sha256("|".join(run_ids).encode()).hexdigest()[:16]
    return Path(out_dir) / CHECKPOINT_DIR / f"{env}-{digest}.pt"


def manifest_path(checkpoint: Path) -> Path:
    return runs_list_path(checkpoint)


def write_manifest(checkpoint: Path, specs: Sequence[RunSpec]) -> None:
    """Write the specs of ``checkpoint``'s runs beside it (once: they never change)."""
    manifest = manifest_path(checkpoint)
    if not manifest.exists():
        records = [{"run_id": spec.run_id, **spec.request()} for spec in specs]
        write_json_atomic(manifest, {"format": MANIFEST_FORMAT, "runs": records})


def remove_checkpoint(checkpoint: Path) -> None:
    checkpoint.unlink(missing_ok=True)
    manifest_path(checkpoint).unlink(missing_ok=True)


def _free_suffix(suffix: str, *paths: Path) -> str:
    """The first of ``suffix``, ``suffix.2``, ``suffix.3``, … that, after the name of each of
    ``paths``, names nothing yet (no file, directory or link, not even a dangling one): a file set
    aside under it replaces nothing, a user's or one set aside before."""
    number = 1
    while True:
        tail = suffix if number == 1 else f"{suffix}.{number}"
        if not any(os.path.lexists(path.with_name(path.name + tail)) for path in paths):
            return tail
        number += 1


_OWN_MANIFEST = re.compile(r"(?P<env>[A-Za-z0-9_.-]+)-[0-9a-f]{16}" + re.escape(MANIFEST_SUFFIX))
"""The name the suite gives a list of runs: ``<environment>-<16 hex digits>.runs.json``."""
_MANIFEST_OPENING = b'{\n "format": '
"""How a list of runs the suite wrote begins (:func:`write_manifest`)."""


def _own_orphan(manifest: Path) -> bool:
    """Whether ``manifest`` (a list of runs without its checkpoint) is one the suite wrote and may
    remove: a regular file of the suite's own name (:data:`_OWN_MANIFEST`, of a registered
    environment) that begins as :func:`write_manifest` writes one. Any other file is left alone."""
    from empathy_zoo.environments import ENGINES

    found = _OWN_MANIFEST.fullmatch(manifest.name)
    if found is None or found["env"] not in ENGINES or manifest.is_symlink() or not manifest.is_file():
        return False
    with manifest.open("rb") as handle:
        return handle.read(len(_MANIFEST_OPENING)) == _MANIFEST_OPENING


def _env_of(ids: Sequence[str], runs_asked: _AskedRuns, checkpoint: Path) -> str:
    """The environment a checkpoint of the runs ``ids`` is named for: that of its first run where it
    is asked for here, else the prefix of the name it was given (``<environment>-<digest>.pt``) or
    of its first run id (``<variant>__…``) where either is a registered environment, else a placeholder."""
    from empathy_zoo.environments import ENGINES

    spec = runs_asked.known.get(ids[0]) if ids else None
    if spec is not None:
        return spec.env
    guesses = [checkpoint.stem.rpartition("-")[0], ids[0].partition("__")[0] if ids else ""]
    return next((guess for guess in guesses if guess in ENGINES), "<environment>")


def _set_aside_misnamed(checkpoint: Path, suffix: str = MISNAMED_SUFFIX) -> Path:
    """Rename ``checkpoint`` (and its list of runs) to ``<name><suffix>`` (``.misnamed``, or
    ``.misnamed.2``, … where that name is taken: never over anything)."""
    manifest = manifest_path(checkpoint)
    tail = _free_suffix(suffix, checkpoint, manifest)
    aside = checkpoint.with_name(checkpoint.name + tail)
    checkpoint.replace(aside)
    if manifest.exists():
        manifest.replace(manifest.with_name(manifest.name + tail))
    return aside


def _set_aside_unreadable(manifest: Path) -> Path:
    """Rename the list of runs ``manifest`` to ``<name>.unreadable`` (``.unreadable.2``, … where that
    name is taken: never over a user's file or one set aside before)."""
    return manifest.replace(manifest.with_name(manifest.name + _free_suffix(UNREADABLE_SUFFIX, manifest)))


def read_manifest(manifest: Path, checkpoint: Path) -> list[dict[str, Any]]:
    """The records of the list of runs ``manifest`` beside ``checkpoint``, checked as data (a
    ``ValueError`` saying what is wrong): a table per run of the keys :meth:`RunSpec.request` gives
    and, in format 2, the run's id, the ids those of ``checkpoint``'s name."""
    data = read_json(manifest, "list of runs")  # (bounded: a regular file of at most MAX_RUNS_LIST_BYTES)
    if not isinstance(data, dict) or data.get("format") not in (1, MANIFEST_FORMAT):
        raise ValueError(f"not a list of runs of format 1 or {MANIFEST_FORMAT}")
    unknown_top = sorted(str(key) for key in data if key not in ("format", "runs"))
    if unknown_top:
        raise ValueError(f"it has unknown key(s) {unknown_top} (a list of runs holds format and runs)")
    runs = data.get("runs")
    if not isinstance(runs, list) or not runs or not all(isinstance(record, dict) for record in runs):
        raise ValueError("'runs' must be a non-empty list of tables")
    with_ids = data["format"] == MANIFEST_FORMAT
    for number, record in enumerate(runs):
        unknown = sorted(str(key) for key in record if key not in REQUEST_KEYS and not (with_ids and key == "run_id"))
        if unknown:
            raise ValueError(f"run {number} has unknown key(s) {unknown}")
        if with_ids:
            check_path_name(record.get("run_id"), f"run {number}'s run_id")
    if with_ids:
        ids = [record["run_id"] for record in runs]
        env = runs[0].get("env")
        if not isinstance(env, str) or _checkpoint_file(checkpoint.parent.parent, env, ids) != checkpoint:
            raise ValueError(f"its run ids are not those of {checkpoint.name}")
    return runs


def _canonical(request: Mapping[str, Any]) -> str:
    """``request`` as the text its record in a list of runs compares by (tuples are lists there)."""
    return json.dumps(request, sort_keys=True, default=repr)


class _AskedRuns:
    """The runs asked for here, by what a record of a list of runs is compared with: their
    ``request()``, and their ``request()`` without the seed."""

    def __init__(self, known: Mapping[str, RunSpec]) -> None:
        self.known = known
        """The runs asked for (finished ones too), by run id."""
        self._exact: dict[str, RunSpec] | None = None
        self._seedless: dict[str, RunSpec] = {}

    def _index(self) -> dict[str, RunSpec]:
        if self._exact is None:  # (only when a directory has checkpoints)
            self._exact = {}
            for spec in self.known.values():
                request = spec.request()
                self._exact[_canonical(request)] = spec
                self._seedless.setdefault(_canonical({**request, "seed": None}), spec)
        return self._exact

    def spec_of(self, record: Mapping[str, Any]) -> RunSpec | None:
        """The run ``record`` describes, if it is a run asked for here or one of them with another
        seed; ``None`` otherwise (nothing of ``record`` is resolved)."""
        plain = {key: value for key, value in record.items() if key != "run_id"}
        exact = self._index().get(_canonical(plain))
        if exact is not None:
            return exact
        template = self._seedless.get(_canonical({**plain, "seed": None}))
        seed = plain.get("seed")
        if template is None or isinstance(seed, bool) or not isinstance(seed, int) or seed < 0:
            return None
        return replace(template, seed=seed)


@dataclass
class _Ensemble:
    """What the run of ``train_runs`` knows of a checkpoint's ensemble."""

    ids: list[str]
    """Its run ids (of the runs asked for, as they are now; of the others, as the checkpoint has them)."""
    specs: list[RunSpec] | None
    """Its runs, in order, when every one can be rebuilt here, else ``None``."""
    problem: str = ""
    """Why it cannot resume (``""`` when it can)."""
    dead: bool = False
    """It can never resume (the code that defines its runs changed): remove it."""
    misnamed: bool = False
    """It holds other runs than its name says (a renamed or copied file): set it aside, as it
    would be taken for the checkpoint of the runs its name is for."""
    loaded: bool = False
    """Its run ids were read from the checkpoint itself (loaded and checked already)."""


Change = Callable[[], str]
"""A change :meth:`EnsemblePlan.apply` makes (or only a note it says): it returns the line said."""


@dataclass
class EnsemblePlan:
    """What :func:`survey_ensembles` found, nothing changed yet: the ensembles that train, and the
    changes to ``checkpoints/`` (removals, files set aside) with their notes, in order."""

    todo: list[RunSpec]
    """The runs to do."""
    chunks: list[list[RunSpec]]
    """The ensembles that train them: checkpointed ones first, as they were, then new ones."""
    changes: list[Change]
    """The changes and notes, in the order they are made and said."""

    def apply(self, on_note: Callable[[str], None]) -> list[list[RunSpec]]:
        """Make every change of the plan (each under a name nothing holds then: nothing is
        replaced), saying each through ``on_note``; returns :attr:`chunks`."""
        for change in self.changes:
            on_note(change())
        return self.chunks


def _said(text: str) -> Change:
    """A note alone, said when the plan is applied."""
    return lambda: text


def _set_aside_unreadable_change(manifest: Path, checkpoint: Path, error: ValueError) -> Change:
    """Setting aside the list of runs ``manifest`` of ``checkpoint`` that cannot be read (``error``)."""

    def change() -> str:
        aside = _set_aside_unreadable(manifest)  # (under a name nothing holds yet: nothing is replaced)
        return (
            f"set aside {manifest} as {aside.name}: it cannot be read as the list of runs of checkpoint "
            f"{checkpoint.name} ({error}); that checkpoint's own run ids are read instead"
        )

    return change


def _ensemble_of(checkpoint: Path, asked: _AskedRuns, changes: list[Change]) -> _Ensemble:
    """``checkpoint``'s ensemble, from its list of runs (or, without a readable one, from its own run
    ids: the list is then set aside, a change added to ``changes``)."""
    manifest = manifest_path(checkpoint)
    if manifest.exists():
        try:
            records = read_manifest(manifest, checkpoint)
        except ValueError as error:
            changes.append(_set_aside_unreadable_change(manifest, checkpoint, error))
        else:
            return _ensemble_of_records(checkpoint, records, asked)
    ids = _checkpoint_run_ids(checkpoint)  # (written before checkpoints had a list of runs, or it was unreadable)
    if _checkpoint_file(checkpoint.parent.parent, checkpoint.stem.rpartition("-")[0], ids) != checkpoint:
        return _Ensemble(ids, None, "misnamed", misnamed=True, loaded=True)
    if all(run_id in asked.known for run_id in ids):
        return _Ensemble(ids, [asked.known[run_id] for run_id in ids], loaded=True)
    return _Ensemble(ids, None, "it holds runs not asked for here, and has no list of runs to rebuild them from", loaded=True)


def _check_resumable(checkpoint: Path, ids: Sequence[str]) -> None:
    """Load ``checkpoint`` (an ensemble that resumes) with :func:`load_checkpoint`'s checks and
    refuse it where it is damaged or holds other runs than ``ids`` (its list of runs), as resuming
    from it would: before anything is changed, not once training starts."""
    if _checkpoint_run_ids(checkpoint) != list(ids):
        raise ValueError(f"checkpoint {checkpoint} belongs to other runs; move it away")


def _ensemble_of_records(checkpoint: Path, records: list[dict[str, Any]], asked: _AskedRuns) -> _Ensemble:
    found = [asked.spec_of(record) for record in records]
    if None in found:
        stored: list[Any] = [record.get("run_id") for record in records]
        if None in stored:  # (format 1: the checkpoint has them)
            stored = _checkpoint_run_ids(checkpoint)
            if len(stored) != len(records):
                raise CheckpointError(f"checkpoint {checkpoint} holds {len(stored)} runs, its list of runs {len(records)}")
        ids = [str(run_id) if spec is None else spec.run_id for spec, run_id in zip(found, stored, strict=True)]
        foreign = [str(run_id) for spec, run_id in zip(found, stored, strict=True) if spec is None]
        why = f"it also holds runs that cannot be rebuilt from the runs asked for here ({', '.join(foreign)})"
        return _Ensemble(ids, None, why)
    specs = [spec for spec in found if spec is not None]
    ids = [spec.run_id for spec in specs]
    if checkpoint_path(checkpoint.parent.parent, specs) != checkpoint:
        return _Ensemble(ids, None, "its runs are no longer the same runs (the code that defines them changed)", dead=True)
    return _Ensemble(ids, specs)


def _checkpoint_run_ids(checkpoint: Path) -> list[str]:
    """The run ids ``checkpoint`` itself holds (a damaged one raises :class:`CheckpointError`)."""
    run_ids = load_checkpoint(checkpoint).get("run_ids")
    if not isinstance(run_ids, list) or not run_ids or not all(isinstance(run_id, str) for run_id in run_ids):
        raise CheckpointError(
            f"checkpoint {checkpoint} is corrupted or incomplete (no list of run ids); it was left untouched: "
            "delete or move it to restart those runs from scratch"
        )
    return run_ids


def plan_ensembles(
    todo: Sequence[RunSpec],
    out_dir: Path,
    max_parallel_runs: int,
    on_note: Callable[[str], None],
    every_run: Sequence[RunSpec] | None = None,
) -> list[list[RunSpec]]:
    """The ensembles that train the runs ``todo``: :func:`survey_ensembles`, then its plan applied
    (the changes to ``checkpoints/`` made and said through ``on_note``)."""
    return survey_ensembles(todo, out_dir, max_parallel_runs, every_run).apply(on_note)


def survey_ensembles(
    todo: Sequence[RunSpec],
    out_dir: Path,
    max_parallel_runs: int,
    every_run: Sequence[RunSpec] | None = None,
) -> EnsemblePlan:
    """The ensembles that train the runs ``todo`` and the changes to ``checkpoints/`` that go with
    them (see the module documentation), found without changing anything; ``every_run``: every run
    asked for, those finished too (default ``todo``), what a checkpoint's runs are rebuilt from.
    A checkpoint or list of runs in ``checkpoints/`` that is no regular file (a FIFO, a directory, a
    dangling symbolic link or a loop of links), a checkpoint that resumes or whose list of runs
    cannot be read that is damaged, and one that holds other runs than its list of runs raise
    ``ValueError`` naming it, and nothing is changed."""
    directory = Path(out_dir) / CHECKPOINT_DIR
    data_files(directory, "*.pt", "checkpoint")  # (each a regular file, or refused before anything is changed)
    data_files(directory, f"*{MANIFEST_SUFFIX}", "list of runs")
    pending = {spec.run_id: spec for spec in todo}
    claimed: dict[str, Path] = {}
    chunks: list[list[RunSpec]] = []
    changes: list[Change] = []
    usual = [[spec.run_id for spec in chunk] for chunk in group_specs(todo, max_parallel_runs)]
    for manifest in sorted(directory.glob(f"*{MANIFEST_SUFFIX}")):  # a manifest written just before a kill
        if not manifest.with_name(manifest.name.removesuffix(MANIFEST_SUFFIX) + ".pt").exists() and _own_orphan(manifest):
            changes.append(_removal(manifest))
    checkpoints = sorted(directory.glob("*.pt"), key=lambda p: (-p.stat().st_mtime_ns, p.name)) if directory.is_dir() else []
    kept: list[tuple[Path, str, list[str]]] = []
    runs_asked = _AskedRuns({spec.run_id: spec for spec in (todo if every_run is None else every_run)})
    for checkpoint in checkpoints:  # the most recent first: it wins an overlap
        ensemble = _ensemble_of(checkpoint, runs_asked, changes)
        ids, specs = ensemble.ids, ensemble.specs
        if ensemble.misnamed:
            own_name = _checkpoint_file(out_dir, _env_of(ids, runs_asked, checkpoint), ids).name
            changes.append(_misnamed_aside(checkpoint, ids, own_name))
            continue
        asked = [run_id for run_id in ids if run_id in pending]
        finished = [run_id for run_id in ids if run_id not in pending and result_path(out_dir, run_id).exists()]
        overlap = [run_id for run_id in ids if run_id in claimed]
        if specs is not None and asked and not overlap:
            if not ensemble.loaded:
                _check_resumable(checkpoint, ids)  # (a damaged one is refused here, before any change)
            chunks.append(specs)
            claimed.update(dict.fromkeys(ids, checkpoint))
            others = [run_id for run_id in ids if run_id not in pending and run_id not in finished]
            if ids not in usual:  # a plain resume goes without saying
                changes.append(
                    _said(
                        f"resuming {len(ids)} run(s) together from checkpoint {checkpoint}, as they were checkpointed"
                        + (f"; {len(finished)} of them already finished are recomputed, not written again" if finished else "")
                        + (f"; not asked for here, but finished and written too: {', '.join(others)}" if others else "")
                    )
                )
            continue
        if not asked and len(finished) == len(ids):
            changes.append(_checkpoint_removal(checkpoint, "all its runs are finished"))
        elif not asked:
            changes.append(_said(f"kept checkpoint {checkpoint}: it holds unfinished runs not asked for here ({', '.join(ids)})"))
        elif not overlap and not ensemble.dead:
            kept.append((checkpoint, ensemble.problem, asked))  # (said below, once the fresh ensembles are known)
        else:
            why = f"it overlaps the newer checkpoint {claimed[overlap[0]]}" if overlap else ensemble.problem
            restart = [run_id for run_id in asked if run_id not in claimed]
            changes.append(
                _checkpoint_removal(
                    checkpoint, why + (f"; these runs start again from scratch: {', '.join(restart)}" if restart else "")
                )
            )
    rest = [spec for spec in todo if spec.run_id not in claimed]
    fresh = group_specs(rest, max_parallel_runs)
    taken = {checkpoint_path(out_dir, chunk) for chunk in fresh}
    for checkpoint, problem, asked in kept:
        if checkpoint in taken:  # (a fresh ensemble of these very runs would resume from it, then delete it)
            changes.append(_disowned_aside(checkpoint, problem, asked))
        else:
            changes.append(
                _said(
                    f"kept checkpoint {checkpoint}: {problem}; it resumes when they are asked for too; "
                    f"these runs start again from scratch: {', '.join(asked)}"
                )
            )
    return EnsemblePlan(list(todo), chunks + fresh, changes)


def _removal(manifest: Path) -> Change:
    """Removing ``manifest``, a list of runs the suite wrote whose checkpoint was never written."""

    def change() -> str:
        manifest.unlink()
        return f"removed {manifest}: a list of runs without its checkpoint (a run killed before its first checkpoint)"

    return change


def _checkpoint_removal(checkpoint: Path, why: str) -> Change:
    """Removing ``checkpoint`` and its list of runs, because ``why``."""

    def change() -> str:
        remove_checkpoint(checkpoint)
        return f"removed checkpoint {checkpoint}: {why}"

    return change


def _misnamed_aside(checkpoint: Path, ids: Sequence[str], own_name: str) -> Change:
    """Setting ``checkpoint`` (of the runs ``ids``, whose own name is ``own_name``) aside as misnamed."""

    def change() -> str:
        aside = _set_aside_misnamed(checkpoint)
        return (
            f"set aside checkpoint {checkpoint} as {aside.name}: it holds the runs {', '.join(ids)}, not those its "
            f"name is for (was it renamed or copied?); to resume them, give it back its own name {own_name}"
        )

    return change


def _disowned_aside(checkpoint: Path, problem: str, asked: Sequence[str]) -> Change:
    """Setting ``checkpoint`` aside as disowned: ``problem``, yet the runs ``asked`` train under its name."""

    def change() -> str:
        aside = _set_aside_misnamed(checkpoint, DISOWNED_SUFFIX)
        return (
            f"set aside checkpoint {checkpoint} as {aside.name}: {problem}, yet its name is that of these runs, "
            f"which start again from scratch: {', '.join(asked)}; to resume from it, give it back its name "
            "and its list of runs the specs of its runs"
        )

    return change
