"""# Verdicts against DQN, one page beside another

Reads the "P(improves on DQN)" tables of two leaderboard pages (``LEADERBOARD.md``: say the same
profile at 5 seeds and at 10) and lists every cell, variant × phase × method × metric, whose mark
differs: ▲ (better than DQN), ▼ (worse) or none. A mark that appears on the new page only reads
as power; one that changes sign is a finding.

    python -m leaderboard.verdict_changes OLD/LEADERBOARD.md NEW/LEADERBOARD.md

A page of no such table (a README, an empty file, a leaderboard of runs with no DQN row) is
refused in one line naming it, status 2: its "0 marks differ" would read as "no verdict moved".
So is one file given twice (a copy of a page is compared), and two pages that share no cell.

Pure text: the pages are read as Markdown, nothing is recomputed. A page may come from anyone:
each name copied from it (variant, phase, method, metric) is shown as text, its Markdown escapes
undone and escaped again, and any control or format character shown as its code (``\\x1b``), so
no page opens HTML, a link or emphasis in the list, or sends a terminal escape to the screen.
"""

from __future__ import annotations

import argparse
import os
import re
import sys
from pathlib import Path

from empathy_zoo.markdown_escape import markdown_text
from empathy_zoo.names import terminal_line

__all__ = ["Cell", "changes", "changes_markdown", "main", "shown_text", "verdicts"]

Cell = tuple[str, str, str, str]
"""(variant, phase, method row, metric); a page whose tables name each row's DQN row (an
``Against`` column) names the row ``METHOD, against DQN ROW`` (its seed count left out, so a row
of 5 seeds and one of 10 are one row)."""

_TABLE = "### P(improves on DQN): "
_SEEDS_SUFFIX = re.compile(r" \([0-9,]+ seeds?\)$")
"""The seed count an ``Against`` cell ends with (``DQN (5 seeds)``)."""
_MARK = re.compile(r"^\s*([▲▼]?)")
_ESCAPED = re.compile(r"\\(.)")
_CELL_BAR = re.compile(r"(?<!\\)\|")
"""A bar that ends a table cell: one no backslash escapes (a label's own ``|`` is written ``\\|``)."""
MAX_SHOWN = 200
MAX_COLUMNS = 1_000
"""The most cells a table row of a page may hold (the shipped ones hold at most 12)."""
MAX_CELLS = 100_000
"""The most cells of "P(improves on DQN)" tables a page may hold (the shipped ones hold at most 240);
a page past it is refused before its cells fill memory."""
"""Characters of a name shown (a page's names are a few dozen; a longer one is cut, with ``…``)."""


def shown_text(cell: str) -> str:
    """A name read from a page (Markdown: data), as one Markdown text that reads as itself: its
    backslash escapes undone, cut to :data:`MAX_SHOWN` characters, each control or format
    character written as its code, then :func:`~empathy_zoo.markdown_escape.markdown_text`."""
    plain = _ESCAPED.sub(lambda found: found.group(1), cell[: 2 * MAX_SHOWN + 2])
    if len(plain) > MAX_SHOWN:
        plain = plain[: MAX_SHOWN - 1] + "…"
    visible = terminal_line(plain)
    return markdown_text(visible)


def verdicts(page: str) -> dict[Cell, str]:
    """Every cell of the page's "P(improves on DQN)" tables and its mark (``▲``, ``▼`` or ``""``):
    the metrics are the columns after ``Seeds``, a row is named by its ``Method`` and, where the
    table has one, its ``Against`` cell (:data:`Cell`). A ``ValueError`` where one cell is read twice
    (two rows of one name in a table): one would hide the other's mark."""
    cells: dict[Cell, str] = {}
    variant = phase = ""
    header: list[str] = []
    first = 2
    for line in page.splitlines():
        if line.startswith("## "):
            variant, phase, header = line[3:].strip(), "", []
        elif line.startswith("### "):
            phase = line[len(_TABLE) :].strip() if line.startswith(_TABLE) else ""
            header = []
        elif phase and line.startswith("|"):
            if line.count("|") > MAX_COLUMNS + 1:
                raise ValueError(f"a table row holds more than {MAX_COLUMNS:,} cells, the most one may (docs/limits.md)")
            parts = [part.strip().replace("\\|", "|") for part in _CELL_BAR.split(line.strip().strip("|"))]
            if not header:
                header = parts
                first = header.index("Seeds") + 1 if "Seeds" in header else 2
                _check_columns(header[first:], variant, phase)
            elif not set(parts[0]) <= set(":-"):
                # (strict=False: the page is read as text, as written; a row with more or fewer cells than its
                # header is read as far as both go, as before)
                row = parts[0]
                if first > 2 and len(parts) > 1:  # (an Against column: the DQN row is part of the row's name)
                    row = f"{parts[0]}, against {_SEEDS_SUFFIX.sub('', parts[1])}"
                for metric, value in zip(header[first:], parts[first:], strict=False):
                    match = _MARK.match(value)
                    cell = (variant, phase, row, metric)
                    if cell in cells:
                        raise ValueError(
                            f"two rows {shown_text(row)!r} in {shown_text(variant)!r}, {shown_text(phase)!r}: one would hide "
                            "the other's mark; give pages the leaderboard wrote"
                        )
                    cells[cell] = match.group(1) if match else ""
                if len(cells) > MAX_CELLS:
                    raise ValueError(f"the page holds more than {MAX_CELLS:,} verdict cells, the most it may (docs/limits.md)")
    return cells


def _check_columns(metrics: list[str], variant: str, phase: str) -> None:
    """Refuse (``ValueError``, naming it) a metric column a table's header names twice: its cells would
    be one cell of each row, one hiding the other's mark."""
    seen: set[str] = set()
    for metric in metrics:
        if metric in seen:
            raise ValueError(
                f"two columns {shown_text(metric)!r} in {shown_text(variant)!r}, {shown_text(phase)!r}: one would hide "
                "the other's marks; give pages the leaderboard wrote"
            )
        seen.add(metric)


def changes(old: dict[Cell, str], new: dict[Cell, str]) -> list[tuple[Cell, str, str]]:
    """The cells of both pages whose marks differ: ``(cell, old mark, new mark)``, in the new page's order."""
    return [(cell, old[cell], mark) for cell, mark in new.items() if cell in old and old[cell] != mark]


def _kind(before: str, after: str) -> str:
    if before and after:
        return "sign changed"
    return "new mark" if after else "mark gone"


def changes_markdown(old_page: str, new_page: str) -> str:
    """A Markdown table of the marks that differ, with a count of the cells compared and, where a
    cell is on one page only (a row gone, a column renamed), a line per page counting and naming
    those cells (:func:`_one_page`); pages of the same cells have no such lines."""
    old, new = verdicts(old_page), verdicts(new_page)
    changed = changes(old, new)
    common = sum(1 for cell in new if cell in old)
    old_only = {cell: mark for cell, mark in old.items() if cell not in new}
    new_only = {cell: mark for cell, mark in new.items() if cell not in old}
    lines = [
        f"{common} cells on both pages; {len(changed)} marks differ ({sum(1 for _, b, a in changed if b and a)} change sign).",
    ]
    if old_only or new_only:  # (a row or a column on one page only: its cells are named, not compared)
        lines += [_one_page(old_only, "old"), _one_page(new_only, "new")]
    lines += [
        "",
        "| variant | phase | method | metric | old | new | change |",
        "|---|---|---|---|:-:|:-:|---|",
    ]
    for names, before, after in changed:
        variant, phase, method, metric = (shown_text(name) for name in names)  # (from the pages: data)
        lines.append(f"| {variant} | {phase} | {method} | {metric} | {before or '–'} | {after or '–'} | {_kind(before, after)} |")
    return "\n".join(lines) + "\n"


MAX_NAMED = 10
"""The most cells of one page only that the summary names one by one; past it, the rest are counted."""


def _one_page(cells: dict[Cell, str], page: str) -> str:
    """A line counting the cells on the ``page`` (``old`` or ``new``) only, in its order, and naming
    at most :data:`MAX_NAMED` of them (``method · metric (variant, phase) mark``), then ``and N more``."""
    if not cells:
        return f"0 cells on the {page} page only."
    named = [f"{_cell_text(cell)} {mark or '–'}" for cell, mark in list(cells.items())[:MAX_NAMED]]
    more = f"; and {len(cells) - MAX_NAMED:,} more" if len(cells) > MAX_NAMED else ""
    return f"{len(cells)} cells on the {page} page only, not compared: {'; '.join(named)}{more}."


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="python -m leaderboard.verdict_changes", description=__doc__.splitlines()[0])
    parser.add_argument("old", type=Path, help="the older LEADERBOARD.md")
    parser.add_argument("new", type=Path, help="the newer LEADERBOARD.md")
    args = parser.parse_args(argv)
    try:
        old, new = (_read_page(path) for path in (args.old, args.new))
        if os.path.samefile(args.old, args.new):  # (one file, however written: "0 marks differ" would say nothing)
            raise ValueError(f"{args.new} is given twice (as {args.old} too): a page would be compared with itself")
        _check_common_cells(args.old, verdicts(old), args.new, verdicts(new))
    except ValueError as error:
        print(f"{parser.prog}: error: {terminal_line(error)}", file=sys.stderr)
        return 2
    print(changes_markdown(old, new), end="")
    return 0


def _check_common_cells(old_path: Path, old: dict[Cell, str], new_path: Path, new: dict[Cell, str]) -> None:
    """Refuse (``ValueError`` naming both pages and a cell of each) two pages that share no verdict
    cell: nothing would be compared, and "0 marks differ" would read as "no verdict moved"."""
    if any(cell in old for cell in new):
        return
    first = next(iter(old))
    second = next(iter(new))
    raise ValueError(
        f"leaderboard pages {old_path} and {new_path} share no verdict cell (variant, phase, method and metric): "
        f"{len(old)} cells on the first only, e.g. {_cell_text(first)}; {len(new)} on the second only, e.g. "
        f"{_cell_text(second)}: nothing would be compared"
    )


def _cell_text(cell: Cell) -> str:
    """A cell as the summary names it: method · metric (variant, phase), each name shown as text."""
    variant, phase, method, metric = cell
    return f"{shown_text(method)} · {shown_text(metric)} ({shown_text(variant)}, {shown_text(phase)})"


MAX_PAGE_BYTES = 64 * 2**20
"""The largest leaderboard page read (the shipped ones are under 1 MB)."""


def _read_page(path: Path) -> str:
    """A leaderboard page's text: a regular UTF-8 file of at most :data:`MAX_PAGE_BYTES` holding at
    least one and at most :data:`MAX_CELLS` verdict cells, else a ``ValueError`` naming it (a FIFO, a
    device or a directory is refused, never read; a page of no "P(improves on DQN)" table, such as a
    README, an empty file or a leaderboard of runs with no DQN row, is refused: its "0 marks differ"
    would read as "no verdict moved")."""
    from empathy_zoo.limits import read_bounded

    try:
        text = read_bounded(path, MAX_PAGE_BYTES, "leaderboard page").decode("utf-8")
        cells = verdicts(text)  # (its cells within their bound, before two pages' are compared)
    except UnicodeDecodeError as error:
        raise ValueError(f"{path} is not UTF-8 text ({error})") from None
    except OSError as error:
        raise ValueError(f"{path}: {error.strerror or error}") from None
    except ValueError as error:
        raise ValueError(f"leaderboard page {path}: {error}") from None
    if not cells:  # (a README, an empty file, a page of no DQN row: "0 marks differ" would read as "no verdict moved")
        raise ValueError(
            f'leaderboard page {path}: holds no verdict table ("{_TABLE}…" over a table of cells) to compare; '
            "give a LEADERBOARD.md the leaderboard wrote from runs with a DQN row"
        )
    return text


if __name__ == "__main__":
    raise SystemExit(main())
