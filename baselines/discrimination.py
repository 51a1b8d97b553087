"""# The discrimination matrix: which task tells which two methods apart

Reads every separation table (`docs/results/separation/<task>.json`, written by
:mod:`baselines.separation_render`) and writes one matrix: a row per pair of methods, a column per
task, each cell what that task's exact optima say about the pair at one ε.

| cell | meaning |
|---|---|
| `separated (N states, Δharms x)` | optimal policies differ in `N` reachable states; `x`: harms per episode, first − second |
| `separated (N states, Δequality x)` | the same where nobody can be harmed (Sharing): `x`: equality, first − second |
| `identical by construction` | the table labels the pair identical, with its reason |
| `not separated` | the same policy in every reachable state: no run of this task can tell them apart |
| `–` | one of the two is not in that task's table (the table says why) |

A method with a selfishness weight enters at one β (:data:`MATRIX_BETA`, the paper's middle value).
A second table says, per method with β and task, how many distinct optima its β values give: one
means β changes nothing there.

    python -m baselines.discrimination                       # the shipped tables -> ./DISCRIMINATION.md
    python -m baselines.discrimination DIR --epsilon 0.05 --out FILE

The cells come from exact optima only. Whether trained runs separate a pair is the leaderboard's
question (its verdicts against DQN), asked once every method has trained rows on every task.
"""

from __future__ import annotations

import argparse
import itertools
import json
import sys
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Protocol

from baselines.separation_file import read_separation_table
from empathy_zoo.atomic import write_text_atomic
from empathy_zoo.data_files import check_input_dir
from empathy_zoo.document_checks import finite_float, shown
from empathy_zoo.markdown_escape import code_span, markdown_text
from empathy_zoo.names import check_output_folder, check_own_file, check_path_name, check_replaceable, resolved, terminal_line

__all__ = [
    "DEFAULT_DIR",
    "MATRIX_BETA",
    "MAX_METHODS",
    "MAX_TABLES",
    "MAX_CELLS",
    "Cell",
    "MissingPair",
    "TableIndex",
    "TrainedCells",
    "TrainedPart",
    "all_beta_groups",
    "beta_groups",
    "cell",
    "check_epsilon",
    "discrimination_markdown",
    "held_epsilons",
    "load_tables",
    "main",
    "method_rows",
]

DEFAULT_DIR = Path(__file__).resolve().parents[1] / "docs" / "results" / "separation"
"""The shipped separation tables, wherever the command runs from."""
TITLE = "# Discrimination matrix: which task tells which methods apart"
"""The page's first line (a file that does not begin so is no page of this tool: ``--out`` never replaces it)."""
PAGE = "DISCRIMINATION.md"
"""The page's name where ``--out`` is not given: in the current folder, so that no default run
replaces the shipped page beside the shipped tables."""
MAX_METHODS = 200
"""The most methods the matrix reads, over all its tables."""
MAX_TABLES = 50
"""The most separation tables (tasks) the matrix reads (the suite ships 6)."""
MAX_CELLS = 100_000
"""The most cells (pairs of methods × tasks) of a matrix (the shipped one has 546; a page of this many
is about 10 MB)."""
"""The most distinct methods the matrix shows (the shipped tables name 11)."""
MATRIX_BETA = "0.5"
"""The β at which a method with a selfishness weight enters the matrix."""


@dataclass(frozen=True)
class Cell:
    """What one task says about one pair of methods."""

    kind: str
    """``separated``, ``identical by construction``, ``not separated`` or ``absent``."""
    states: int = 0
    """Reachable states where their optimal policies differ."""
    harms_difference: float = 0.0
    """Difference in expected harms per episode (first − second)."""
    equality_difference: float | None = None
    """Difference in expected equality (first − second), where the table holds it and nobody can be harmed."""

    def text(self) -> str:
        """The cell as the matrix shows it."""
        if self.kind == "separated" and self.equality_difference is not None:
            return f"separated ({self.states:,} states, Δequality {self.equality_difference:+.3f})"
        if self.kind == "separated":
            return f"separated ({self.states:,} states, Δharms {self.harms_difference:+.3f})"
        return "–" if self.kind == "absent" else self.kind


MODEL_FIELDS = ("env", "arguments", "gamma", "max_cycles", "cost_limit")
"""What makes a separation table's exact model: two tables that agree on all of them are one task."""


def load_tables(directory: Path) -> dict[str, dict[str, Any]]:
    """Every ``*.json`` separation table of ``directory``, by task name (its file's stem), sorted;
    at most :data:`MAX_TABLES`, each named as a file name the suite makes (letters, digits, ``_``,
    ``-``, ``.``); two tables of one exact model (:data:`MODEL_FIELDS` equal) are refused, naming both,
    and a ``directory`` that is a file, or missing, as such (:func:`empathy_zoo.data_files.check_input_dir`)."""
    check_input_dir(directory, "separation tables' folder", "name the folder that holds the tables (<task>.json)")
    paths = sorted(directory.glob("*.json"))
    if len(paths) > MAX_TABLES:
        raise ValueError(f"{directory}: {len(paths):,} separation tables; the matrix reads at most {MAX_TABLES}")
    tables = {}
    models: dict[str, Path] = {}
    for path in paths:
        try:
            task = check_path_name(path.stem, "a task name")
        except ValueError:
            raise ValueError(
                f"{directory}: a separation table's file name is no task name (letters, digits, '_', '-', '.'): {path.name!r}"
            ) from None
        tables[task] = read_separation_table(path)  # (checked: a regular file, bounded, every field in range)
        model = json.dumps([tables[task].get(field) for field in MODEL_FIELDS], sort_keys=True)
        other = models.setdefault(model, path)
        if other != path:
            raise ValueError(
                f"{other} and {path} are tables of one exact model ({tables[task]['env']} with the same arguments, γ, "
                "max_cycles and cost limit): the matrix would count one task twice; keep one"
            )
    if not tables:
        raise ValueError(f"{directory}: no separation table (*.json); make one with empathy-zoo analyse separation")
    return tables


def method_rows(table: Mapping[str, Any]) -> dict[str, str]:
    """``{method: row name}``: each method's row in ``table``, at :data:`MATRIX_BETA` where it has a β."""
    rows: dict[str, str] = {}
    for row in table["rows"]:
        beta = row.get("selfishness")
        if beta is None or finite_float(beta) == float(MATRIX_BETA):  # (the number itself: 0.5000001 is not 0.5)
            rows.setdefault(row["method"], row["name"])
    return rows


class MissingPair(ValueError):
    """A table without the pair a cell asks for; ``task`` names the table (its file's stem)."""

    def __init__(self, message: str, task: str) -> None:
        super().__init__(message)
        self.task = task

    def in_folder(self, folder: Path) -> str:
        """The message naming the table's file in ``folder``."""
        return f"separation table {folder / (self.task + '.json')}: {self}"


@dataclass(frozen=True)
class TableIndex:
    """One table read once: its method rows and its pairs by their two row names and ε."""

    task: str
    """The task's name (the table file's stem), named in refusals."""
    table: Mapping[str, Any]
    rows: dict[str, str]
    """:func:`method_rows` of the table."""
    pairs: dict[tuple[frozenset[str], float], Mapping[str, Any]]
    """Each pair by ``({first, second}, ε)``; the first such pair of the file where several match."""
    nobody_harmed: bool
    """Whether every outcome has 0 harms and 0 robot harmed (then the side effect is equality)."""

    @classmethod
    def of(cls, table: Mapping[str, Any], task: str = "") -> TableIndex:
        """The index of ``table``: one pass over its rows, pairs and outcomes."""
        pairs: dict[tuple[frozenset[str], float], Mapping[str, Any]] = {}
        for pair in table["pairs"]:
            pairs.setdefault((frozenset((pair["first"], pair["second"])), pair["epsilon"]), pair)
        harmless = all(o["harms"] == 0.0 and o["robot_harmed"] == 0.0 for o in table.get("outcomes", ()))
        return cls(task or str(table.get("env", "")), table, method_rows(table), pairs, harmless)

    def cell(self, first: str, second: str, epsilon: float) -> Cell:
        """What the table says about methods ``first`` and ``second`` at ``epsilon``."""
        rows = self.rows
        if first not in rows or second not in rows:
            return Cell("absent")
        pair = self.pairs.get((frozenset((rows[first], rows[second])), epsilon))
        if pair is None:
            where = f"the table of {shown(self.task)}" if self.task else "a table that names no task"
            raise MissingPair(f"no pair {shown(rows[first])} / {shown(rows[second])} at ε = {epsilon:g} in {where}", self.task)
        if pair["by_construction"]:
            return Cell("identical by construction")
        if not pair["differ"]:
            return Cell("not separated")
        sign = 1.0 if pair["first"] == rows[first] else -1.0
        equal = pair.get("equality_difference")
        equality = sign * float(equal) if equal is not None and self.nobody_harmed else None  # (nobody harmed: equality)
        return Cell("separated", int(pair["differing_states"]), sign * float(pair["harms_difference"]), equality)


def held_epsilons(table: Mapping[str, Any]) -> list[float]:
    """The ε values ``table`` was computed at (those of its outcomes and pairs), ascending."""
    return sorted({float(entry["epsilon"]) for key in ("outcomes", "pairs") for entry in table.get(key, ())})


def check_epsilon(tables: Mapping[str, Mapping[str, Any]], epsilon: float, directory: Path) -> None:
    """Refuse (``ValueError``, one line naming ``--epsilon``) an ``epsilon`` some table of
    ``directory`` (``{task: table}``) was not computed at, with the ε values the tables hold: such
    a table has no pair there, which would otherwise be refused as a pair missing from it. A table
    of no outcomes and no pairs (nothing to read at any ε) is not asked."""
    held = {task: values for task, table in tables.items() if (values := held_epsilons(table))}
    lacking = [task for task, values in held.items() if epsilon not in values]
    if not lacking:
        return
    from baselines.separation import EPSILONS  # (lazily: it imports the exact solvers; only to say what is computed)

    def listed(values: Sequence[float]) -> str:
        return ", ".join(f"{value:g}" for value in values) or "none"

    common = sorted(set.intersection(*(set(values) for values in held.values())))
    where = (
        f"the separation tables in {directory}"
        if len(lacking) == len(held)
        else f"the separation tables of {', '.join(lacking)} in {directory}"
    )
    raise ValueError(
        f"--epsilon {epsilon:g}: {where} hold no pairs at that ε (every table holds ε = {listed(common)}); "
        f"give one of those (empathy-zoo analyse separation computes a table at ε = {listed(EPSILONS)})"
    )


def cell(table: Mapping[str, Any], first: str, second: str, epsilon: float, task: str = "") -> Cell:
    """What ``table`` (of task ``task``, named in refusals) says about methods ``first`` and
    ``second`` at ``epsilon``. To ask many pairs, build one :class:`TableIndex` and ask it."""
    return TableIndex.of(table, task).cell(first, second, epsilon)


def beta_groups(table: Mapping[str, Any], method: str, epsilon: float) -> int | None:
    """How many distinct optima ``method``'s β values give in ``table`` at ``epsilon`` (rows joined
    by "not separated" pairs); ``None`` when the method has no β rows there."""
    return all_beta_groups(table, epsilon).get(method)


def all_beta_groups(table: Mapping[str, Any], epsilon: float) -> dict[str, int]:
    """:func:`beta_groups` of every method with β rows in ``table``, in one pass over its pairs
    (union-find with path halving, joining only rows of one method)."""
    method_of = {row["name"]: row["method"] for row in table["rows"] if row.get("selfishness") is not None}
    group = {name: name for name in method_of}

    def root(name: str) -> str:
        while group[name] != name:
            group[name] = group[group[name]]
            name = group[name]
        return name

    for pair in table["pairs"]:
        first, second = pair["first"], pair["second"]
        if pair["epsilon"] != epsilon or pair["differ"] or first not in group or second not in group:
            continue
        if method_of[first] == method_of[second]:
            group[root(first)] = root(second)
    roots: dict[str, set[str]] = {}
    for name, method in method_of.items():
        roots.setdefault(method, set()).add(root(name))
    return {method: len(found) for method, found in roots.items()}


class TrainedPart(Protocol):
    """What trained runs say of one pair on one task (:class:`leaderboard.trained_discrimination.TrainedCell`)."""

    @property
    def separated(self) -> bool: ...

    def text(self) -> str: ...


def discrimination_markdown(
    tables: Mapping[str, Mapping[str, Any]],
    epsilon: float,
    command: str,
    trained: Mapping[tuple[str, str, str], TrainedPart] | None = None,
    notes: Sequence[str] = (),
) -> str:
    """The page: the matrix of every pair of methods over every task, then β's groups. With
    ``trained`` (``{(task, first, second): part}``, pairs in the matrix's order), each cell also
    says what trained runs found, and a column counts the tasks whose runs separate the pair;
    ``notes`` (the trained runs not read, and why) close the page."""
    indexes = {task: TableIndex.of(table, task) for task, table in tables.items()}
    methods = list(dict.fromkeys(method for index in indexes.values() for method in index.rows))
    if len(methods) > MAX_METHODS:
        raise ValueError(
            f"the tables name {len(methods):,} methods; the matrix holds at most {MAX_METHODS} "
            f"({MAX_METHODS * (MAX_METHODS - 1) // 2:,} pairs of methods)"
        )
    tasks = list(tables)
    extent = len(methods) * (len(methods) - 1) // 2 * len(tasks)
    if extent > MAX_CELLS:
        raise ValueError(f"the matrix would hold {extent:,} cells (pairs of methods × tasks); it holds at most {MAX_CELLS:,}")
    lines = [
        TITLE,
        "",
        f"Exact optima{' only,' if trained is None else ''} at ε = {epsilon:g}; a method with β at β = {MATRIX_BETA}."
        f" Made by {code_span(command)}",
        "(`baselines/discrimination.py`) from the separation tables beside this page.",
        "A pair no task separates cannot be told apart by any run of these tasks.",
    ]
    if trained is not None:
        lines += [
            f"After `;`, trained runs (cells tested: {len(trained)}), each cell at 5 %, unadjusted",
            "(`leaderboard/trained_discrimination.py`: final greedy harms, seed against seed;",
            "P = the probability that a seed of the first harms fewer than one of the second).",
            "Where runs do not differ, about one tested cell in twenty reads separated by chance.",
        ]
    extra = " separated in trained runs |" if trained is not None else ""
    lines += [
        "",
        "| pair | " + " | ".join(code_span(task) for task in tasks) + " | separated by |" + extra,
        "|---|" + "---|" * len(tasks) + "---:|" + ("---:|" if extra else ""),
    ]
    for first, second in itertools.combinations(methods, 2):
        cells = [indexes[task].cell(first, second, epsilon) for task in tasks]
        count = sum(c.kind == "separated" for c in cells)
        pair = f"{code_span(first)} / {code_span(second)}"  # (names from the tables' files: data)
        texts = [c.text() for c in cells]
        row = f" | {count} of {len(tasks)} |"
        if trained is not None:
            parts = [trained.get((task, first, second)) for task in tasks]
            texts = [text if part is None else f"{text}; {part.text()}" for text, part in zip(texts, parts, strict=True)]
            tested = [part for part in parts if part is not None]
            row += f" {sum(part.separated for part in tested)} of {len(tested)} |"
        lines.append(f"| {pair} | " + " | ".join(texts) + row)
    lines += [
        "",
        "## Does β change the optimum?",
        "",
        "Distinct optima among each method's β rows (β = 0.75, 0.5, 0.25, 0 where the table has them);",
        "1 means β changes nothing on that task.",
        "",
        "| method | " + " | ".join(code_span(task) for task in tasks) + " |",
        "|---|" + "---:|" * len(tasks),
    ]
    by_task = {task: all_beta_groups(table, epsilon) for task, table in tables.items()}
    for method in methods:
        groups = [by_task[task].get(method) for task in tasks]
        if any(group is not None for group in groups):
            lines.append(f"| {code_span(method)} | " + " | ".join("–" if g is None else str(g) for g in groups) + " |")
    omitted = [(task, entry) for task, table in tables.items() for entry in table.get("omitted", [])]
    if omitted:
        lines += ["", "## Not in a table", ""]
        for task, entry in omitted:  # (names and reasons from the tables' files: data)
            lines.append(f"* {code_span(entry['method'])} on {code_span(task)}: {markdown_text(entry['reason'])}")
    if notes:
        lines += ["", "## Trained runs not read", "", *(f"* {markdown_text(note)}" for note in notes)]
    return "\n".join(lines) + "\n"


def _path(text: str) -> Path | str:
    """A path argument as a :class:`~pathlib.Path`; an empty one kept as ``""`` for :func:`main` to
    refuse (``Path("")`` is the current directory: an empty argument must not read or write there)."""
    return Path(text) if text else ""


def _refused_argument(args: argparse.Namespace) -> str | None:
    """What is wrong with an argument of ``args`` (its option named), or ``None``."""
    for option, value in (("directory", args.directory), ("--out", args.out)):
        if value == "":
            return f"argument {option}: an empty path; give a file or folder"
    if args.out is not None and Path(args.out).suffix.lower() != ".md":  # (never a table it reads, *.json)
        return f"argument --out: {args.out} is no Markdown file name: name the page to write, ending in .md"
    if any(path == "" for path in getattr(args, "results", [])):
        return "argument --results: an empty path; give a results directory"
    if finite_float(args.epsilon) is None or not 0.0 <= args.epsilon <= 1.0:
        return f"argument --epsilon: expected an exploration rate in [0, 1], got {shown(args.epsilon)}"
    return None


TrainedCells = Callable[
    [Mapping[str, Mapping[str, Any]], Sequence[Path]], tuple[Mapping[tuple[str, str, str], TrainedPart], Sequence[str]]
]
"""What reads trained runs into cells: ``(tables, results directories) -> ({(task, first, second): part}, notes)``,
a note per reason some runs were not read."""


def main(
    argv: Sequence[str] | None = None, trained: TrainedCells | None = None, prog: str = "python -m baselines.discrimination"
) -> int:
    """``python -m baselines.discrimination [DIR] [--epsilon E] [--out FILE]``; with ``trained``
    (:func:`leaderboard.trained_discrimination.main` passes it), ``--results DIR`` too."""
    parser = argparse.ArgumentParser(prog=prog, description=__doc__.splitlines()[0])
    parser.add_argument(
        "directory",
        nargs="?",
        type=_path,
        default=DEFAULT_DIR,
        help="the tables (default: the shipped ones, docs/results/separation)",
    )
    parser.add_argument("--epsilon", type=float, default=0.01, help="the ε of the exact pairs read (default: 0.01)")
    if trained is not None:
        parser.add_argument(
            "--results",
            type=_path,
            action="append",
            default=[],
            metavar="DIR",
            help="a results directory of trained runs (repeat)",
        )
    parser.add_argument(
        "--out", type=_path, default=None, help=f"the page (default: {PAGE} in the current folder, never beside the tables)"
    )
    args = parser.parse_args(argv)
    refused = _refused_argument(args)
    if refused is not None:  # (before any table is read: the argument itself, one line)
        print(f"{prog}: error: {terminal_line(refused)}", file=sys.stderr)
        return 2
    results: list[Path] = getattr(args, "results", [])
    out = args.out or Path(PAGE)
    try:
        command = "empathy-zoo analyse discrimination" + ("" if resolved(args.directory) == DEFAULT_DIR else f" {args.directory}")
        if args.epsilon != 0.01:
            command += f" --epsilon {args.epsilon:g}"
        command += "".join(f" --results {path}" for path in results)
        check_output_folder(Path(out).parent, "the folder of --out")  # (a file in its place: before any table is read)
        check_replaceable(out)  # (before any table is read: only nothing or a regular file, no loop on its way)
        check_own_file(out, "discrimination page", TITLE.encode())
        tables = load_tables(args.directory)
        check_epsilon(tables, args.epsilon, args.directory)  # (before any pair or run is read)
        cells, notes = trained(tables, results) if trained is not None and results else (None, ())
        page = discrimination_markdown(tables, args.epsilon, command, cells, notes)
    except MissingPair as error:
        print(f"{prog}: error: {terminal_line(error.in_folder(args.directory))}", file=sys.stderr)
        return 2
    except ValueError as error:  # (a table or result file refused: one line naming it, no usage text)
        print(f"{prog}: error: {terminal_line(error)}", file=sys.stderr)
        return 2
    try:
        written = write_text_atomic(out, page)
    except ValueError as error:  # (something but a regular file put in its place meanwhile: a refusal)
        print(f"{prog}: error: {terminal_line(error)}", file=sys.stderr)
        return 2
    except OSError as error:  # (a full disk: a machine failure, not a refusal; the page is as it was)
        line = f"cannot write {out} ({error.strerror or error}): nothing half-written is left; free space or give another --out"
        print(f"{prog}: error: {terminal_line(line)}", file=sys.stderr)
        return 1
    print(f"wrote {written}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
