"""# Separation table files: JSON, Markdown and the command that writes them

:func:`to_json` and :func:`from_json` store a :class:`baselines.separation.SeparationTable`
losslessly; :func:`to_markdown` renders it for the docs. The command

    python -m baselines.separation_render [ENV] [ARG=VALUE ...] [--out DIR]

builds the table of ``ENV`` (default ``coexistence_v0``) with the engine arguments given and writes
``DIR/<name>.json`` and ``DIR/<name>.md`` (``DIR`` default the current folder; the shipped tables
were written with ``--out docs/results/separation``, which no default touches). ``<name>`` is
the environment's name, followed by ``_<rules>`` when a ``rules`` argument is given. The returns of
an outcome appear where the table holds them (the environment's task is the robot's return).
"""

from __future__ import annotations

import json
from collections.abc import Callable
from dataclasses import asdict
from pathlib import Path
from typing import Any

from baselines.separation import Omission, Pair, Row, RowOutcome, SeparationTable, separation_table
from baselines.separation_bounds import check_bounds
from empathy_zoo.environments import DEFAULT_ENVIRONMENT, ENGINES, ENVIRONMENT_TABLE
from empathy_zoo.exact_solver import command_line_arguments, tabular_model

__all__ = ["to_json", "from_json", "to_markdown", "equivalence_classes", "file_name", "main"]

OUT = Path(".")
"""Where the command writes by default: the current folder (never the shipped tables' folder)."""
RETURNS = ("robot_return", "other_return", "changed", "batteries", "other_batteries", "equality")
"""The outcome fields a table holds only where the environment's task is the robot's return (the
returns), where it has a state beyond the cells (``changed``: the vase broken) or where its layers
hold the batteries collected (the battery figures)."""
RANDOM_PARTNER = "random_walk"
"""The fixed policy the exact model's other agent follows (uniformly random moves)."""
OPTIONAL_PAIR_FIELDS = ("equality_difference",)
"""The pair fields a table holds only where its outcomes hold equality."""


def to_json(table: SeparationTable) -> str:
    """The table as JSON (every field, floats exact)."""
    data = asdict(table)
    data["arguments"] = [list(item) for item in table.arguments]
    for item in data["outcomes"]:  # (returns only where the table holds them)
        for key in RETURNS:
            if item[key] is None:
                del item[key]
    for item in data["pairs"]:
        for key in OPTIONAL_PAIR_FIELDS:
            if item[key] is None:
                del item[key]
    return json.dumps(data, ensure_ascii=False, indent=1) + "\n"


def from_json(text: str) -> SeparationTable:
    """The table :func:`to_json` wrote."""
    data: dict[str, Any] = json.loads(text)
    return SeparationTable(
        env=str(data["env"]),
        arguments=tuple((str(key), value) for key, value in data["arguments"]),
        gamma=float(data["gamma"]),
        max_cycles=int(data["max_cycles"]),
        cost_limit=float(data["cost_limit"]),
        rows=tuple(Row(**row) for row in data["rows"]),
        outcomes=tuple(RowOutcome(**item) for item in data["outcomes"]),
        pairs=tuple(Pair(**item) for item in data["pairs"]),
        omitted=tuple(Omission(**item) for item in data["omitted"]),
    )


def equivalence_classes(table: SeparationTable, epsilon: float) -> tuple[tuple[str, ...], ...]:
    """The rows at ``epsilon`` grouped by the same optimum (no pair of a group differs), in row order."""
    names = [o.row for o in table.outcomes if o.epsilon == epsilon]
    classes: list[list[str]] = []
    for name in names:
        home = next((c for c in classes if not table.differ(c[0], name, epsilon)), None)
        if home is None:
            classes.append([name])
        else:
            home.append(name)
    return tuple(tuple(c) for c in classes)


def file_name(env: str, arguments: dict[str, int | str]) -> str:
    """``<env>`` or ``<env>_<rules>`` (the name of the files the command writes)."""
    return f"{env}_{arguments['rules']}" if "rules" in arguments and arguments["rules"] != "paper" else env


def _letter(index: int) -> str:
    return chr(ord("A") + index)


Column = tuple[str, Callable[[RowOutcome], str]]
"""A column of the outcomes: its header and how it shows an outcome."""


def _columns(table: SeparationTable) -> list[Column]:
    """The outcome columns the Markdown shows: harms and the robot harmed where someone can be
    harmed, survival, the battery figures and both returns where the table holds them, and the
    vase broken where it holds that."""
    entry = ENVIRONMENT_TABLE.get(table.env)
    harmless = entry is not None and not entry.can_harm
    batteries = any(o.batteries is not None for o in table.outcomes)
    columns: list[Column] = []
    if not harmless:
        columns += [("harms", lambda o: f"{o.harms:.4f}"), ("robot harmed", lambda o: f"{o.robot_harmed:.4f}")]
    columns.append(("survival (episode length)" if harmless else "survival", lambda o: f"{o.survival:.1f}"))
    if batteries:
        columns += [
            ("batteries", lambda o: f"{o.batteries or 0.0:.3f}"),
            ("other batteries", lambda o: f"{o.other_batteries or 0.0:.3f}"),
            ("equality", lambda o: f"{o.equality or 0.0:.4f}"),
        ]
    if any(o.robot_return is not None for o in table.outcomes):
        digits = 3 if batteries else 1
        columns += [
            ("robot return", lambda o: f"{o.robot_return or 0.0:.{digits}f}"),
            ("other return", lambda o: f"{o.other_return or 0.0:.{digits}f}"),
        ]
    if any(o.changed is not None for o in table.outcomes):
        columns.append(("vase broken", lambda o: f"{o.changed or 0.0:.4f}"))
    return columns


def _notes(table: SeparationTable) -> list[str]:
    """What the table's figures mean where its environment needs saying: nobody harmed, a partner
    in training other than the model's random one, a step that draws."""
    entry = ENVIRONMENT_TABLE.get(table.env)
    if entry is None:
        return []
    lines = []
    if not entry.can_harm:
        lines.append(
            f"Nobody can be harmed in {entry.title} (its environment entry says `can_harm = False`): every row's harms and "
            "chance of the robot harmed are 0, and the table leaves them out. Survival is the episode's length, as the "
            "engine counts it: the episode ends when the last battery is taken (or at the time limit)."
        )
    partners = sorted(set(entry.fixed.values()) - {RANDOM_PARTNER})
    if partners:
        other = next(iter(entry.fixed))
        lines.append(
            f"The exact model's `{other}` acts uniformly at random, as it does in every table; in training its default "
            f"partner is `{'`, `'.join(partners)}`."
        )
    draws = int(getattr(ENGINES[table.env], "tabular_draws", 1))
    if draws > 1:
        lines.append(
            f"Its step draws from the environment's generator (a battery both agents reach goes to either): the model "
            f"steps every state once for each of the {draws} equally likely draws."
        )
    return lines


def to_markdown(table: SeparationTable) -> str:
    """The table for the docs: rows, outcomes, the groups of rows with one optimum, and the pairs of groups."""
    arguments = " ".join(f"{key}={value}" for key, value in table.arguments)
    command = f"empathy-zoo analyse separation {table.env} {arguments}".rstrip()
    lines = [
        f"# Separation table: {table.env}" + (f" ({arguments})" if arguments else ""),
        "",
        f"Exact optima under full observability; γ = {table.gamma:g}, {table.max_cycles} steps an episode,",
        f"the Lagrangian's limit d = {table.cost_limit:g} harms per episode. Made by `{command}`.",
        "",
        "## Rows",
        "",
        "| row | method | β | identical by construction |",
        "|---|---|---:|---|",
    ]
    for row in table.rows:
        beta = "" if row.selfishness is None else f"{row.selfishness:g}"
        same = f"to `{row.identical_to}`: {row.reason}" if row.identical_to else ""
        lines.append(f"| `{row.name}` | `{row.method}` | {beta} | {same} |")
    epsilons = table.epsilons
    columns = _columns(table)
    notes = _notes(table)
    if notes:
        lines[5:5] = [*notes, ""]
    figures = ", ".join(header for header, _ in columns)
    lines += ["", f"## Outcomes ({figures} per episode)", ""]
    lines.append("| row | " + " | ".join(f"ε = {e:g}" for e in epsilons) + " |")
    lines.append("|---|" + "---:|" * len(epsilons))
    for row in table.rows:
        cells = []
        for epsilon in epsilons:
            found = [o for o in table.outcomes if o.row == row.name and o.epsilon == epsilon]
            cells.append(", ".join(show(found[0]) for _, show in columns) if found else "—")
        lines.append(f"| `{row.name}` | " + " | ".join(cells) + " |")
    lagrangian = [o for o in table.outcomes if o.row == "dqn_lagrangian" and not _identical(table, o.row)]
    if lagrangian:
        lines += ["", "The Lagrangian's multiplier:", ""]
        for o in lagrangian:
            value = "none" if o.multiplier is None else f"{o.multiplier:.4g}"
            lines.append(f"* ε = {o.epsilon:g}: λ = {value} ({o.note}).")
    for epsilon in epsilons:
        classes = equivalence_classes(table, epsilon)
        lines += ["", f"## Groups with one optimum at ε = {epsilon:g}", ""]
        headers = [header for header, _ in columns]
        lines += ["| group | rows | " + " | ".join(headers) + " |", "|---|---|" + "---:|" * len(headers)]
        for index, members in enumerate(classes):
            o = table.outcome(members[0], epsilon)
            names = ", ".join(f"`{m}`" for m in members)
            lines.append(f"| {_letter(index)} | {names} | " + " | ".join(show(o) for _, show in columns) + " |")
        if len(classes) > 1:
            lines += ["", "States where two groups' greedy policies differ, of those reachable under either:", ""]
            lines.append("| | " + " | ".join(_letter(j) for j in range(1, len(classes))) + " |")
            lines.append("|---|" + "---:|" * (len(classes) - 1))
            for i in range(len(classes) - 1):
                cells = []
                for j in range(1, len(classes)):
                    pair = table.pair(classes[i][0], classes[j][0], epsilon)
                    cells.append(f"{pair.differing_states} / {pair.reachable_states}" if pair is not None and j > i else "")
                lines.append(f"| {_letter(i)} | " + " | ".join(cells) + " |")
    if table.omitted:
        lines += ["", "## Not in the table", ""]
        lines += [f"* `{o.method}`: {o.reason}." for o in table.omitted]
    return "\n".join(lines) + "\n"


def _identical(table: SeparationTable, row: str) -> bool:
    """Whether ``row`` is identical to another by construction in ``table``."""
    return any(r.name == row and r.identical_to for r in table.rows)


def main(argv: list[str] | None = None) -> None:
    """``python -m baselines.separation_render [ENV] [ARG=VALUE ...] [--out DIR]``: write the table's
    files, both or neither (:func:`empathy_zoo.atomic.write_all_atomic`); anything but a regular
    file in either's place (a link, a directory, a FIFO) is refused before the table is computed,
    and nothing else in ``DIR`` is touched. A write that fails (a full disk) is an ``OSError``
    naming the file, and leaves both files as they were."""
    import argparse

    from empathy_zoo.atomic import write_all_atomic
    from empathy_zoo.evaluation_file import check_not_read_folder
    from empathy_zoo.names import check_output_folder, check_own_file, check_replaceable

    parser = argparse.ArgumentParser(prog="python -m baselines.separation_render", description=main.__doc__)
    parser.add_argument("env", nargs="?", default=DEFAULT_ENVIRONMENT)
    parser.add_argument("arguments", nargs="*", metavar="ARG=VALUE", help="environment arguments (ints or strings)")
    parser.add_argument("--out", default=str(OUT), help="folder of the files (default: the current folder)")
    args = parser.parse_args(argv)
    if args.out == "":  # (Path("") is the working directory: never taken for an empty argument)
        raise ValueError("argument --out: an empty path; give a folder")
    kwargs = command_line_arguments(args.arguments)  # (a ValueError: one line, as the environment's own)
    name = file_name(args.env, kwargs)
    check_output_folder(args.out)  # (a file in the folder's place: refused before the long part, not after it)
    paths = [check_replaceable(Path(args.out) / f"{name}{suffix}") for suffix in (".json", ".md")]  # (before the long part)
    check_not_read_folder(args.out, f"--out {args.out} (its separation tables)")
    check_own_file(paths[0], "separation table", b'{\n "env": ')
    check_own_file(paths[1], "separation page", b"# Separation table: ")
    check_bounds(args.env, kwargs)  # (a row's bound that follows from the arguments: before any model is built)
    model = tabular_model(args.env, **kwargs)
    table = separation_table(model)
    texts = (to_json(table), to_markdown(table))
    try:
        written = write_all_atomic([(path, text.encode("utf-8")) for path, text in zip(paths, texts, strict=True)])
    except OSError as error:  # (a full disk): the pair is written whole or not at all
        raise OSError(
            f"cannot write {error.filename or paths[0]} ({error.strerror or error}): {paths[0].name} and "
            f"{paths[1].name} in {args.out} are as they were; free space or give another --out"
        ) from None
    for path in written:
        print(path)


def module_main(argv: list[str] | None = None) -> int:
    """:func:`main` as ``python -m`` runs it: a refusal (``ValueError``) is one line on stderr and
    exit status 2, a write that failed (``OSError``: a full disk) one line and exit status 1, as
    through ``empathy-zoo analyse separation``."""
    import sys

    from empathy_zoo.names import terminal_line

    try:
        main(argv)
    except ValueError as error:
        print(f"python -m baselines.separation_render: error: {terminal_line(error)}", file=sys.stderr)
        return 2
    except OSError as error:
        print(f"python -m baselines.separation_render: error: {terminal_line(error)}", file=sys.stderr)
        return 1
    return 0


if __name__ == "__main__":
    raise SystemExit(module_main())
