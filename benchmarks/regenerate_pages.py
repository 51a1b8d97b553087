"""Regenerate every shipped page made from files into one folder, to compare two versions of the code.

``python benchmarks/regenerate_pages.py OUT [--only NAME ...]`` writes, under ``OUT``:

* ``<name>/`` — the leaderboard (``LEADERBOARD.md``, ``leaderboard.csv``, ``leaderboard.html``,
  ``figures/``) of each shipped results directory ``docs/results/<name>`` that holds its runs
  (quick, methods, paper, sb3_transforms, sharing_sensitivity, coexistence_sensitivity; medium and
  methods/tuned ship no runs, so they cannot be made again);
* ``sharing_sensitivity/SENSITIVITY.md``, ``coexistence_sensitivity/SENSITIVITY.md`` and
  ``REPRODUCTION.md``, by the commands their headers name (the second printed, not written with
  ``--out``, so that its header names no output path);
* ``separation/`` — the exact separation tables (``empathy-zoo analyse separation ENV``) and
  ``DISCRIMINATION.md`` (``empathy-zoo analyse discrimination``);
* ``stdout/`` — what the printing readers print of the shipped results (``analyse versus-dqn``,
  ``heldout-verdicts``, ``compare-runs``, ``equivalence``), a marl-eval export, and a leaderboard of
  two directories read into one (labels prefixed, budgets in the labels).

Each leaderboard is written as its page's header says it was made: the page's command and commit
are the shipped page's (the code's own commit and ``--out`` would change the header line, and only
it), so a page made again by unchanged code equals the shipped one byte for byte, and two versions
of the code are compared with ``diff -r OUT_BEFORE OUT_AFTER`` (PNG and GIF bytes included).
The reproduction report is written as the shipped command writes it, into the tree the script lies
in (``REPRODUCTION.md``, its held-out figures into ``docs/results/paper/figures``: its links are
relative to it), then copied to ``OUT`` (``REPRODUCTION.md``, ``reproduction_figures/``). So run the
script from a copy of the tree (``git archive COMMIT | tar -x -C DIR``; one per commit compared):
it reads the code and the results of the tree it lies in, and writes nothing else there. Run it
under ``nice``: it takes about half an hour on two busy cores.
"""

from __future__ import annotations

import argparse
import os
import re
import shutil
import subprocess
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
RESULTS = "docs/results"
LEADERBOARDS = ("quick", "methods", "paper", "sb3_transforms", "sharing_sensitivity", "coexistence_sensitivity")
"""The shipped leaderboards whose runs ship too (``medium`` and ``methods/tuned`` ship none)."""
SEPARATION = (
    ("coexistence_v0",),
    ("coexistence_v0", "max_cycles=501", "rules=authors"),
    ("sharing_v0", "size=5", "view=3"),
    ("charger_v0",),
    ("vase_v0",),
    ("helping_v0",),
)
"""The arguments of every shipped separation table (their pages name them)."""
SHIPPED_HEADER = re.compile(r"^Produced by `(?P<command>[^`]+)` with empathy-zoo [^,]+, commit `(?P<commit>[^`]+)`\.$")


def pinned(commit: str, command: str, argv: list[str]) -> int:
    """Run the command line ``argv`` as ``command`` with the code's commit read as ``commit``."""
    sys.path.insert(0, str(ROOT))  # (this tree's code, not another checkout the environment names)
    import empathy_zoo.provenance as provenance

    provenance.git_commit = lambda: commit  # type: ignore[assignment]  # (before anything imports it by name)
    from empathy_zoo.cli import parse_args

    args = parse_args(argv)
    return int(args.handler(args, command))


def shipped_header(page: Path) -> tuple[str, str]:
    """The command and commit a shipped leaderboard page names in its header."""
    for line in page.read_text(encoding="utf-8").splitlines()[:6]:
        found = SHIPPED_HEADER.match(line)
        if found:
            return found["command"], found["commit"]
    raise SystemExit(f"{page}: no 'Produced by ... commit ...' header line")


def run(argv: list[str], log: Path, stdout: Path | None = None, cwd: Path = ROOT) -> None:
    """Run ``argv`` in ``cwd`` (this tree's code imported wherever it runs); its output goes to
    ``stdout`` (else the log)."""
    started = time.monotonic()
    with log.open("a", encoding="utf-8") as sink:
        sink.write(f"$ {' '.join(argv)}\n")
        sink.flush()
        out = stdout.open("w", encoding="utf-8") if stdout is not None else sink
        try:
            environment = {**os.environ, "PYTHONPATH": os.pathsep.join(filter(None, [str(ROOT), os.environ.get("PYTHONPATH")]))}
            status = subprocess.run(argv, cwd=cwd, env=environment, stdout=out, stderr=sink, check=False).returncode
        finally:
            if stdout is not None:
                out.close()
        sink.write(f"# exit {status}, {time.monotonic() - started:.0f} s\n")
    print(f"exit {status} in {time.monotonic() - started:5.0f} s: {' '.join(argv[-6:])}", flush=True)
    if status != 0:
        raise SystemExit(f"failed: {' '.join(argv)} (see {log})")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("out", type=Path)
    parser.add_argument("--only", nargs="*", help="only these parts (leaderboard names, reports, separation, stdout)")
    parser.add_argument("--pinned", nargs=argparse.REMAINDER, help=argparse.SUPPRESS)
    options = parser.parse_args()
    if options.pinned:
        commit, command, *argv = options.pinned
        raise SystemExit(pinned(commit, command, argv))
    out = options.out.resolve()
    out.mkdir(parents=True, exist_ok=True)
    (out / "stdout").mkdir(exist_ok=True)
    log = out / "regenerate.log"
    wanted = set(options.only or ())

    def chosen(part: str) -> bool:
        return not wanted or part in wanted

    python, cli = sys.executable, [sys.executable, "-m", "empathy_zoo.cli"]
    this = [python, str(Path(__file__).resolve()), str(out), "--pinned"]
    for name in LEADERBOARDS:
        if chosen(name):
            command, commit = shipped_header(ROOT / RESULTS / name / "LEADERBOARD.md")
            run([*this, commit, command, "leaderboard", f"{RESULTS}/{name}", "--out", str(out / name)], log)
    if chosen("reports"):
        sharing, coexistence = f"{RESULTS}/sharing_sensitivity", f"{RESULTS}/coexistence_sensitivity"
        paper = f"{RESULTS}/paper"
        (out / "sharing_sensitivity").mkdir(exist_ok=True)
        (out / "coexistence_sensitivity").mkdir(exist_ok=True)
        made_by = "empathy-zoo reproduce --profile sharing_sensitivity --out results/sharing_sensitivity"
        page = str(out / "sharing_sensitivity" / "SENSITIVITY.md")
        run([*cli, "sensitivity", sharing, "--note", f"{sharing}/NOTE.md", "--produced-by", made_by, "--out", page], log)
        page = out / "coexistence_sensitivity" / "SENSITIVITY.md"  # (printed: the page names no --out)
        run([*cli, "analyse", "coexistence-sensitivity", coexistence], log, page)
        appendices = ["--sensitivity", sharing, "--coexistence-sensitivity", coexistence, "--note", f"{paper}/NOTE.md"]
        run([*cli, "reproduction", paper, *appendices, "--out", "REPRODUCTION.md"], log)  # (its links: from the root)
        shutil.copyfile(ROOT / "REPRODUCTION.md", out / "REPRODUCTION.md")
        shutil.copytree(ROOT / paper / "figures", out / "reproduction_figures", dirs_exist_ok=True)
    if chosen("separation"):
        for arguments in SEPARATION:
            run([*cli, "analyse", "separation", *arguments, "--out", str(out / "separation")], log)
        run([*cli, "analyse", "discrimination", "separation"], log, cwd=out)  # (its page names the folder as given)
    if chosen("stdout"):
        printed = out / "stdout"
        for name in ("paper", "methods"):
            run([*cli, "analyse", "versus-dqn", f"{RESULTS}/{name}"], log, printed / f"versus_dqn_{name}.txt")
        for name in ("quick", "paper", "methods"):
            run([*cli, "analyse", "heldout-verdicts", f"{RESULTS}/{name}"], log, printed / f"heldout_verdicts_{name}.txt")
        run([*cli, "analyse", "compare-runs", f"{RESULTS}/quick", f"{RESULTS}/paper"], log, printed / "compare_runs.txt")
        sharing = f"{RESULTS}/sharing_sensitivity"
        run([*cli, "analyse", "equivalence", sharing, sharing, "--all", "--tost"], log, printed / "equivalence.txt")
        run([*cli, "export", "--format", "marl-eval", "--out", str(printed / "marl_eval_quick.json"), f"{RESULTS}/quick"], log)
        quick, sb3 = f"{RESULTS}/quick", f"{RESULTS}/sb3_transforms"
        two = [quick, sb3, "--label", f"{quick}=Q", "--out", str(out / "two_dirs")]
        run([*this, "none", f"empathy-zoo leaderboard {quick} {sb3}", "leaderboard", *two], log)


if __name__ == "__main__":
    main()
