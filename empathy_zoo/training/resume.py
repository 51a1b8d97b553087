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
* one that cannot be resumed (its runs can no longer be rebuilt, or it overlaps a newer one) is
  removed, and its runs still to do start again from scratch.

Every decision but a plain resume is reported through ``on_note``, one line each.
"""

from __future__ import annotations

import hashlib
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Any

from empathy_zoo.atomic import read_json, write_json_atomic
from empathy_zoo.experiment.model import RunSpec, group_specs
from empathy_zoo.result_file import result_path
from empathy_zoo.training.checkpoint import load_checkpoint

__all__ = ["CHECKPOINT_DIR", "checkpoint_path", "manifest_path", "write_manifest", "remove_checkpoint", "plan_ensembles"]

CHECKPOINT_DIR = "checkpoints"
MANIFEST_SUFFIX = ".runs.json"
"""Suffix of the file beside a checkpoint that lists its runs' specs."""


def checkpoint_path(out_dir: Path, specs: Sequence[RunSpec]) -> Path:
    """The checkpoint of the ensemble ``specs`` (in this order)."""
    digest = hashlib.sha256("|".join(s.run_id for s in specs).encode()).hexdigest()[:16]
    return Path(out_dir) / CHECKPOINT_DIR / f"{specs[0].env}-{digest}.pt"


def manifest_path(checkpoint: Path) -> Path:
    return checkpoint.with_name(checkpoint.stem + MANIFEST_SUFFIX)


def write_manifest(checkpoint: Path, specs: Sequence[RunSpec]) -> None:
    """Write the specs of ``checkpoint``'s runs beside it (once: they never change)."""
    manifest = manifest_path(checkpoint)
    if not manifest.exists():
        write_json_atomic(manifest, {"format": 1, "runs": [_record(spec) for spec in specs]})


def remove_checkpoint(checkpoint: Path) -> None:
    checkpoint.unlink(missing_ok=True)
    manifest_path(checkpoint).unlink(missing_ok=True)


def _record(spec: RunSpec) -> dict[str, Any]:
    return spec.request()


def _ensemble_of(checkpoint: Path, known: dict[str, RunSpec]) -> tuple[list[str], list[RunSpec] | None, str]:
    """The run ids of ``checkpoint``'s ensemble, their specs (``None`` when they cannot be rebuilt),
    and why not."""
    manifest = manifest_path(checkpoint)
    if manifest.exists():
        try:
            specs = [RunSpec.of(**record) for record in read_json(manifest)["runs"]]
        except (KeyError, TypeError, ValueError) as error:
            return [], None, f"its list of runs {manifest.name} cannot be read ({error})"
        ids = [spec.run_id for spec in specs]
        if checkpoint_path(checkpoint.parent.parent, specs) != checkpoint:
            return ids, None, "its runs are no longer the same runs (the code that defines them changed)"
        return ids, specs, ""
    ids = list(load_checkpoint(checkpoint)["run_ids"])  # written before checkpoints had a list of runs
    if all(run_id in known for run_id in ids):
        return ids, [known[run_id] for run_id in ids], ""
    return ids, None, "it was written by an earlier version and holds runs not asked for here"


def plan_ensembles(
    todo: Sequence[RunSpec], out_dir: Path, max_parallel_runs: int, on_note: Callable[[str], None]
) -> list[list[RunSpec]]:
    """The ensembles that train the runs ``todo`` (see the module documentation)."""
    directory = Path(out_dir) / CHECKPOINT_DIR
    pending = {spec.run_id: spec for spec in todo}
    claimed: dict[str, Path] = {}
    chunks: list[list[RunSpec]] = []
    usual = [[spec.run_id for spec in chunk] for chunk in group_specs(todo, max_parallel_runs)]
    for manifest in directory.glob(f"*{MANIFEST_SUFFIX}"):  # a manifest written just before a kill
        if not manifest.with_name(manifest.name.removesuffix(MANIFEST_SUFFIX) + ".pt").exists():
            manifest.unlink()
    checkpoints = sorted(directory.glob("*.pt"), key=lambda p: (-p.stat().st_mtime_ns, p.name)) if directory.is_dir() else []
    for checkpoint in checkpoints:  # the most recent first: it wins an overlap
        ids, specs, reason = _ensemble_of(checkpoint, pending)
        asked = [run_id for run_id in ids if run_id in pending]
        finished = [run_id for run_id in ids if run_id not in pending and result_path(out_dir, run_id).exists()]
        overlap = [run_id for run_id in ids if run_id in claimed]
        if specs is not None and asked and not overlap:
            chunks.append(specs)
            claimed.update({run_id: checkpoint for run_id in ids})
            others = [run_id for run_id in ids if run_id not in pending and run_id not in finished]
            if ids not in usual:  # a plain resume goes without saying
                on_note(
                    f"resuming {len(ids)} run(s) together from checkpoint {checkpoint}, as they were checkpointed"
                    + (f"; {len(finished)} of them already finished are recomputed, not written again" if finished else "")
                    + (f"; not asked for here, but finished and written too: {', '.join(others)}" if others else "")
                )
            continue
        if not asked and len(finished) == len(ids):
            remove_checkpoint(checkpoint)
            on_note(f"removed checkpoint {checkpoint}: all its runs are finished")
        elif not asked:
            on_note(f"kept checkpoint {checkpoint}: it holds unfinished runs not asked for here ({', '.join(ids)})")
        else:
            why = f"it overlaps the newer checkpoint {claimed[overlap[0]]}" if overlap else reason
            remove_checkpoint(checkpoint)
            restart = [run_id for run_id in asked if run_id not in claimed]
            on_note(
                f"removed checkpoint {checkpoint}: {why}"
                + (f"; these runs start again from scratch: {', '.join(restart)}" if restart else "")
            )
    rest = [spec for spec in todo if spec.run_id not in claimed]
    return chunks + group_specs(rest, max_parallel_runs)
