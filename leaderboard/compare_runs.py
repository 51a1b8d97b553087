"""Which runs of two results directories computed the same thing: each run of one is matched with
the run of the other of the same variant, method, β, aggregation of the others, reward transform,
world, partners and seed, and the pair is *same* when their training and evaluation columns are
equal value for value (what a version that changed nothing a run computes must give).
Two directories of which no run has a partner in the other are refused: nothing is compared.

    python -m leaderboard.compare_runs OLD_DIR NEW_DIR

prints one line per matched pair and the counts; runs without a partner are counted apart. Two
runs of one directory that match the same key are refused (:func:`runs_by_key`), and so are two
runs of one key but of two experiments (:func:`check_one_experiment_per_key`). A matched pair
must agree on every setting both files record (a version may add or drop a setting, never change
one's value), its reward transform's fields and its budget (steps, evaluation schedule); a pair
that differs in one is refused naming it (:func:`setting_differences`).
"""

from __future__ import annotations

import sys
from collections.abc import Callable, Sequence

from empathy_zoo.experiment.records import RunResult
from empathy_zoo.names import positional_tool, tool_help
from empathy_zoo.result_file import read_folder
from leaderboard.aggregate import load_results
from leaderboard.run_facts import description_of

PROG = "python -m leaderboard.compare_runs"

__all__ = [
    "check_one_experiment_per_key",
    "check_same_settings",
    "check_something_matched",
    "compare_runs",
    "run_key",
    "runs_by_key",
    "setting_differences",
]


def run_key(run: RunResult) -> tuple:
    """What two versions' runs must share to be the same experiment: variant, method, β, the
    aggregation of the others, reward transform, world (environment arguments) and partners (fixed
    agents), and seed (last)."""
    return (
        run.config.variant or run.env,
        run.method,
        description_of(run)["selfishness"],
        run.config.settings.get("others", "closest"),
        run.config.reward_name,
        tuple(sorted((name, repr(value)) for name, value in run.config.env_kwargs.items())),
        tuple(sorted(run.config.fixed.items())),
        run.seed,
    )


def runs_by_key(runs: Sequence[RunResult], key: Callable[[RunResult], tuple] = run_key) -> dict[tuple, RunResult]:
    """``runs`` by their ``key``; two runs of one key (two experiments that differ only in what
    the key leaves out: a γ, a label) raise ``ValueError`` naming both, since neither could be
    matched, nor pooled, without dropping the other."""
    keyed: dict[tuple, RunResult] = {}
    for run in runs:
        other = keyed.setdefault(key(run), run)
        if other is not run:
            raise ValueError(
                f"runs {other.run_id} and {run.run_id} are one experiment's seed {run.seed} to this tool (same variant, "
                "method, β, aggregation of the others, reward transform, world, partners and seed) but two runs: it would "
                "match or pool "
                "one and drop the other; compare directories that hold one of them each"
            )
    return keyed


def check_one_experiment_per_key(runs: Sequence[RunResult], key: Callable[[RunResult], tuple] | None = None) -> None:
    """Refuse (``ValueError`` naming two runs) runs of one directory that ``key`` (by default
    :func:`run_key` less the seed) takes for one experiment but whose run ids say are two (another
    learning rate, γ, budget, reward field, label: what the key leaves out); they would be matched
    or pooled as one."""
    first: dict[tuple, RunResult] = {}
    for run in runs:
        other = first.setdefault(run_key(run)[:-1] if key is None else key(run), run)
        if other.experiment != run.experiment:
            raise ValueError(
                f"runs {other.run_id} and {run.run_id} share variant, method, β, aggregation of the others, reward "
                "transform, world and partners but are two experiments (another setting, budget or label): this tool "
                "would match or pool them as one; compare directories that hold one of them each"
            )


def setting_differences(a: RunResult, b: RunResult) -> list[str]:
    """What ``a`` and ``b`` (runs of one :func:`run_key`, from two directories) record differently:
    a setting both record (a version may add or drop one), a field of the reward transform both
    record, the steps or the evaluation schedule; each ``name: A against B``."""
    found = []
    shared = sorted(set(a.config.settings) & set(b.config.settings))
    found += [
        f"{n}: {a.config.settings[n]!r} against {b.config.settings[n]!r}"
        for n in shared
        if a.config.settings[n] != b.config.settings[n]
    ]
    ra, rb = a.config.reward or {}, b.config.reward or {}
    found += [f"reward {n}: {ra[n]!r} against {rb[n]!r}" for n in sorted(set(ra) & set(rb)) if ra[n] != rb[n]]
    if a.steps != b.steps:
        found.append(f"steps: {a.steps!r} against {b.steps!r}")
    for name in ("eval_interval", "eval_episodes"):
        va, vb = getattr(a.config, name), getattr(b.config, name)
        if va is not None and vb is not None and va != vb:
            found.append(f"{name}: {va!r} against {vb!r}")
    return found


def check_same_settings(a: RunResult, b: RunResult) -> None:
    """Refuse (``ValueError`` naming both runs and the first difference) a matched pair of two
    experiments (:func:`setting_differences`)."""
    differences = setting_differences(a, b)
    if differences:
        raise ValueError(
            f"runs {a.run_id} and {b.run_id} match as one experiment (same variant, method, β, aggregation of the "
            f"others, reward transform, world and partners) but differ in {differences[0]}"
            f"{f' (and {len(differences) - 1} more)' if len(differences) > 1 else ''}: they are two experiments; "
            "compare directories of the same experiments"
        )


def compare_runs(old: Sequence[RunResult], new: Sequence[RunResult]) -> dict[str, list[tuple]]:
    """``{"same": [...], "different": [...], "only_old": [...], "only_new": [...]}``: the keys
    (:func:`run_key`) of the matched pairs by outcome, and of the runs without a partner. Two
    experiments taken for one, in a directory or across them, raise ``ValueError`` (see the module page)."""
    by_key_old, by_key_new = runs_by_key(old), runs_by_key(new)
    check_one_experiment_per_key(old)
    check_one_experiment_per_key(new)
    outcome: dict[str, list[tuple]] = {"same": [], "different": [], "only_old": [], "only_new": []}
    for key in sorted(by_key_new, key=repr):
        if key not in by_key_old:
            outcome["only_new"].append(key)
            continue
        a, b = by_key_old[key], by_key_new[key]
        check_same_settings(a, b)
        outcome["same" if a.train == b.train and a.eval == b.eval else "different"].append(key)
    outcome["only_old"] = sorted((key for key in by_key_old if key not in by_key_new), key=repr)
    return outcome


def check_something_matched(
    first: str, second: str, only_first: Sequence[tuple], only_second: Sequence[tuple], what: str
) -> None:
    """Refuse (``ValueError`` naming one unmatched ``what`` of each side) two directories ``first``
    and ``second`` of which no ``what`` (run, experiment) has a partner in the other: nothing
    would be compared, and counts of zero would read as a finding."""
    if only_first or only_second:
        sides = [(first, only_first), (second, only_second)]
        examples = "; ".join(f"{len(keys)} only in {path}, e.g. {_shown_key(keys[0])}" for path, keys in sides if keys)
        raise ValueError(f"{first} and {second} hold no {what} in common ({examples}): nothing would be compared")
    raise ValueError(f"{first} and {second} hold no runs: nothing would be compared")


def _shown_key(key: tuple) -> str:
    """A key's parts that are set, comma-separated (its env, method, β, ...), a part of
    ``(name, value)`` pairs (world, partners) as ``name=value``."""
    return ", ".join(
        " ".join(f"{name}={value}" for name, value in part) if isinstance(part, tuple) else str(part)
        for part in key
        if part not in (None, (), "closest")
    )


def main(argv: Sequence[str] | None = None) -> int:
    """``python -m leaderboard.compare_runs OLD_DIR NEW_DIR``: one line per matched pair, then the counts."""
    args = list(sys.argv[1:] if argv is None else argv)
    usage = f"usage: {PROG} OLD_DIR NEW_DIR"
    if args in (["-h"], ["--help"]):
        print(tool_help(usage, __doc__))
        return 0
    return positional_tool(PROG, usage, args, 2, _print_comparison)


def _print_comparison(paths: list[str]) -> int:
    if read_folder(paths[0]) == read_folder(paths[1]):  # (DIR and DIR/runs are one directory)
        raise ValueError(f"{paths[1]} is given twice (as {paths[0]} too): its runs would be compared with themselves")
    result = compare_runs(load_results(paths[0]), load_results(paths[1]))
    if not result["same"] and not result["different"]:
        check_something_matched(paths[0], paths[1], result["only_old"], result["only_new"], "run")
    for verdict in ("same", "different"):
        for key in result[verdict]:
            print(f"{verdict:9s} {key}")
    print(", ".join(f"{name}: {len(keys)}" for name, keys in result.items()))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
