"""Result files in marl-eval's exchange format (``empathy-zoo export --format marl-eval``).

`marl-eval <https://github.com/instadeepai/marl-eval>`_ (Gorsane et al. 2022; the format BenchMARL
writes) reads one JSON document nested five deep, environment → task → algorithm → run → step,
each step ``{"step_count": <int>, "<metric>": [one value per evaluation episode], ...}``, and each
run ends with ``absolute_metrics`` (the same metric lists, no ``step_count``). A run of this suite
maps onto it as follows (:func:`marl_eval_layout`, a pure function of the runs read):

* environment: ``env``, the engine's name (``coexistence_v0``);
* task: the variant, the env key of its sweep (``coexistence_3cats``; the env name where it has
  none), the row's environment in the leaderboard;
* algorithm: the leaderboard row's label (``method_label``, with its ``--label`` prefix, and ending
  with its budget where the runs have several: :func:`leaderboard.sources.load_results_dirs`),
  commas dropped (:func:`algorithm_name`: marl-eval refuses a comma in an algorithm name);
* run: ``seed_<seed>``, as marl-eval's own ``JsonLogger`` and BenchMARL name runs;
* ``step_<i>``: the ``i``-th greedy evaluation (``eval`` in step order, from 0): ``step_count`` its
  training step, and every metric of :data:`empathy_zoo.metrics.METRIC_NAMES` as the list of its
  episodes' values;
* ``absolute_metrics``: the last greedy evaluation's lists (the policy at the end of its budget).

Two choices differ from marl-eval's own logger. ``absolute_metrics`` is the final evaluation, not
the best policy re-evaluated on ten times the episodes (Gorsane et al. 2022): a run keeps only its
final agent, and picking the best of its evaluations would choose on the numbers it reports. No
``elapsed_time`` is written: a result file records the run's total wall time only, not when each
evaluation was made, and an invented time would be no measurement.

Every metric is written as recorded, whichever way it is better
(:data:`empathy_zoo.metrics.HIGHER_IS_BETTER`: fewer ``harms`` are better, every other
metric is better higher); marl-eval's aggregates and probability of improvement take higher as
better, so negate ``harms`` before handing it to them. marl-eval lower-cases every key and
aggregates across the tasks of an environment only when they hold the same algorithms, runs and
evaluation steps; its ``DiagnoseData`` names what differs.
"""

from __future__ import annotations

import json
import os
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from empathy_zoo.atomic import write_text_atomic
from empathy_zoo.evaluation_file import check_not_read_folder
from empathy_zoo.experiment.records import RunResult
from empathy_zoo.metrics import METRIC_NAMES
from empathy_zoo.names import check_output_file, resolved
from empathy_zoo.result_file import RUNS_DIR
from leaderboard.aggregate import group_runs
from leaderboard.sources import load_results_dirs

__all__ = [
    "ABSOLUTE_METRICS",
    "STEP_COUNT",
    "MarlEvalExport",
    "algorithm_name",
    "check_export_path",
    "marl_eval_layout",
    "run_key",
    "step_key",
    "write_marl_eval",
]

ABSOLUTE_METRICS = "absolute_metrics"
"""The key of a run's absolute metrics (marl-eval finds it by the word ``absolute``)."""
STEP_COUNT = "step_count"
"""The key of an evaluation's training step in a marl-eval step."""


def algorithm_name(label: str) -> str:
    """The marl-eval algorithm name of a leaderboard label: the label without its commas (marl-eval
    refuses a comma in an algorithm name: ``Empathic DQN, mean (β=0.5)`` → ``Empathic DQN mean
    (β=0.5)``, ``DQN · 30,000 steps`` → ``DQN · 30000 steps``)."""
    return label.replace(",", "")


def run_key(seed: int) -> str:
    """The marl-eval run of a seed: ``seed_<seed>``."""
    return f"seed_{seed}"


def step_key(index: int) -> str:
    """The marl-eval step of a run's ``index``-th greedy evaluation (from 0): ``step_<index>``."""
    return f"step_{index}"


def _run_layout(run: RunResult) -> dict[str, Any]:
    """One run as marl-eval's ``{step_<i>: {...}, ..., absolute_metrics: {...}}`` (each value as
    its result file records it)."""
    evaluations = sorted(run.eval, key=lambda entry: entry.step)
    if not evaluations:
        raise ValueError(
            f"run {run.run_id} has no greedy evaluation (its eval is empty): marl-eval's steps and absolute "
            "metrics are evaluations; train it with an evaluation interval within its budget, or move it away"
        )
    steps: dict[str, Any] = {
        step_key(i): {STEP_COUNT: entry.step, **{metric: entry.metrics[metric].tolist() for metric in METRIC_NAMES}}
        for i, entry in enumerate(evaluations)
    }
    steps[ABSOLUTE_METRICS] = {metric: evaluations[-1].metrics[metric].tolist() for metric in METRIC_NAMES}
    return steps


def marl_eval_layout(results: Iterable[RunResult]) -> dict[str, dict[str, dict[str, dict[str, Any]]]]:
    """``results`` (runs as :func:`leaderboard.aggregate.load_results` or
    :func:`leaderboard.sources.load_results_dirs` read them) in marl-eval's layout,
    ``{environment: {task: {algorithm: {run: {step_<i>: ..., "absolute_metrics": ...}}}}}`` (the
    mapping is in this module's docstring). Environments and tasks are sorted; algorithms come in
    the leaderboard's row order (:func:`leaderboard.aggregate.group_runs`), runs by seed, steps by
    training step with ``absolute_metrics`` last (marl-eval reads steps in this order).

    ``ValueError`` for a run without a greedy evaluation, for two labels of one task whose
    algorithm names are one to marl-eval (equal once commas are dropped and letters lower-cased):
    give one its own label (``--label DIR=PREFIX`` where they come from two directories), and for
    two variants whose names are one once lower-cased (``Coex`` and ``coex``).
    """
    layout: dict[str, dict[str, dict[str, dict[str, Any]]]] = {}
    labels: dict[tuple[str, str, str], str] = {}
    tasks: dict[tuple[str, str], str] = {}
    for (task, label), runs in group_runs(results).items():
        environment = runs[0].env
        named = tasks.setdefault((environment.lower(), task.lower()), task)
        if named != task:
            raise ValueError(
                f"variants {named!r} and {task!r} of {environment} are one task to marl-eval, which lower-cases names: "
                "their runs would land in one cell; give one variant another name"
            )
        algorithm = algorithm_name(label)
        first = labels.setdefault((environment, task, algorithm.lower()), label)
        if first != label:
            raise ValueError(
                f"labels {first!r} and {label!r} of {environment}/{task} are one algorithm to marl-eval, which drops "
                f"commas and lower-cases names ({algorithm.lower()!r}); give one its own label (train --label, label in "
                "its sweep entry, or --label DIR=PREFIX where they come from two results directories)"
            )
        algorithms = layout.setdefault(environment, {}).setdefault(task, {})
        algorithms[algorithm] = {run_key(run.seed): _run_layout(run) for run in runs}
    return {environment: dict(sorted(layout[environment].items())) for environment in sorted(layout)}


def check_export_path(out: str | os.PathLike[str], results_dirs: Sequence[str | os.PathLike[str]] = ()) -> Path:
    """``out`` as a path if an export can be written there; ``ValueError`` naming it otherwise: a name
    not ending in ``.json``, an existing directory, anything but a regular file in its place (a
    symbolic link, named with its target, a FIFO, a device: :func:`empathy_zoo.names.check_replaceable`),
    a parent that is a file, the folder the result files of one of ``results_dirs`` are read
    from (:func:`leaderboard.aggregate.result_files`), a ``runs`` folder or an evaluation set's
    folder of any results directory, or an existing file that is not an earlier export
    (:func:`_is_export`): an export never replaces a file of another kind."""
    path = check_output_file(out, "JSON", ".json", "marl_eval.json")
    check_not_read_folder(path.parent, str(out))  # (as typed, and where `..` and links lead)
    if path.is_file() and not _is_export(path):
        raise ValueError(
            f"{out} exists and is no marl-eval export of this suite: an export replaces only an earlier export "
            "(move the file away, or name another file)"
        )
    for directory in results_dirs:
        root = Path(directory) / RUNS_DIR if (Path(directory) / RUNS_DIR).is_dir() else Path(directory)
        if root.is_dir() and resolved(path.absolute().parent) == resolved(root):
            raise ValueError(
                f"{out} lies where the result files of {directory} are read ({root}): it would be read as one; write it elsewhere"
            )
    return path


EXPORT_HEAD_BYTES = 4_096
"""The bytes of an existing file read to tell whether it is an earlier export."""


def _is_export(path: Path) -> bool:
    """Whether the regular file ``path`` is empty or begins as :func:`write_marl_eval` writes: ``{``,
    then a registered environment's name as the first key (at most :data:`EXPORT_HEAD_BYTES` are
    read; a result, evaluation, study or other JSON file begins otherwise)."""
    from empathy_zoo.environments import ENGINES

    with path.open("rb") as file:
        head = file.read(EXPORT_HEAD_BYTES)
    if not head:
        return True
    text = head.decode("utf-8", errors="replace")
    return any(text.startswith(f'{{\n "{name}": {{') for name in ENGINES)


@dataclass(frozen=True)
class MarlEvalExport:
    """What :func:`write_marl_eval` wrote."""

    path: Path
    """The JSON file written."""
    environments: int
    """Environments in it."""
    tasks: int
    """Tasks (variants) in it, over all environments."""
    algorithms: int
    """Algorithms (leaderboard rows) in it, over all tasks."""
    runs: int
    """Runs (result files) in it."""


def write_marl_eval(
    results_dirs: Sequence[str | os.PathLike[str]],
    out: str | os.PathLike[str],
    labels: Mapping[str | os.PathLike[str], str] | None = None,
) -> MarlEvalExport:
    """Write the runs of ``results_dirs`` (read as
    :func:`leaderboard.sources.load_results_dirs` reads them, ``labels`` prefixing a directory's
    labels) to ``out`` in marl-eval's layout (:func:`marl_eval_layout`), atomically
    (:func:`empathy_zoo.atomic.write_text_atomic`, strict JSON: no ``NaN``). ``ValueError`` for what those refuse and for an
    ``out`` that is no ``.json`` file name, is a directory, a link, a FIFO or a device, lies in a
    directory that is a file, or lies where result files are read (it would be read as one);
    nothing is written then."""
    check_export_path(out, results_dirs)
    layout = marl_eval_layout(load_results_dirs(results_dirs, labels).results)
    try:
        text = json.dumps(layout, indent=1, allow_nan=False) + "\n"
    except ValueError as error:  # (the result-file checker refuses every value that is no finite number)
        raise ValueError(f"cannot write {out}: a value is no finite number, which JSON cannot hold ({error})") from None
    path = write_text_atomic(out, text)
    tasks = [algorithms for environment in layout.values() for algorithms in environment.values()]
    return MarlEvalExport(
        path=path,
        environments=len(layout),
        tasks=len(tasks),
        algorithms=sum(len(algorithms) for algorithms in tasks),
        runs=sum(len(runs) for algorithms in tasks for runs in algorithms.values()),
    )
