"""Which runs of two results directories computed the same thing: each run of one is matched with
the run of the other of the same variant, method, β, aggregation of the others, reward transform,
world, partners and seed, and the pair is *same* when their training and evaluation columns are
equal value for value (what a version that changed nothing a run computes must give).

    python -m leaderboard.compare_runs OLD_DIR NEW_DIR

prints one line per matched pair and the counts; runs without a partner are counted apart. Two
runs of one directory that match the same key are refused (:func:`runs_by_key`).
"""

from __future__ import annotations

import sys
from collections.abc import Callable, Sequence

from empathy_zoo.experiment.records import RunResult
from empathy_zoo.names import positional_tool
from leaderboard.aggregate import load_results
from leaderboard.run_facts import description_of

PROG = "python -m leaderboard.compare_runs"

__all__ = ["run_key", "runs_by_key", "compare_runs"]


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


def compare_runs(old: Sequence[RunResult], new: Sequence[RunResult]) -> dict[str, list[tuple]]:
    """``{"same": [...], "different": [...], "only_old": [...], "only_new": [...]}``: the keys
    (:func:`run_key`) of the matched pairs by outcome, and of the runs without a partner."""
    by_key_old, by_key_new = runs_by_key(old), runs_by_key(new)
    outcome: dict[str, list[tuple]] = {"same": [], "different": [], "only_old": [], "only_new": []}
    for key in sorted(by_key_new, key=repr):
        if key not in by_key_old:
            outcome["only_new"].append(key)
            continue
        a, b = by_key_old[key], by_key_new[key]
        outcome["same" if a.train == b.train and a.eval == b.eval else "different"].append(key)
    outcome["only_old"] = sorted((key for key in by_key_old if key not in by_key_new), key=repr)
    return outcome


def main(argv: Sequence[str] | None = None) -> int:
    """``python -m leaderboard.compare_runs OLD_DIR NEW_DIR``: one line per matched pair, then the counts."""
    args = list(sys.argv[1:] if argv is None else argv)
    if args in (["-h"], ["--help"]):
        print(main.__doc__)
        return 0
    return positional_tool(PROG, f"usage: {PROG} OLD_DIR NEW_DIR", args, 2, _print_comparison)


def _print_comparison(paths: list[str]) -> int:
    result = compare_runs(load_results(paths[0]), load_results(paths[1]))
    for verdict in ("same", "different"):
        for key in result[verdict]:
            print(f"{verdict:9s} {key}")
    print(", ".join(f"{name}: {len(keys)}" for name, keys in result.items()))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
