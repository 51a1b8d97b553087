"""The verdict rules of REPRODUCTION.md: pure functions over per-method cells.

A *cell* is one method's figure for one metric in one phase: the mean over seeds with the
leaderboard's interval for a 95 % claim (:func:`leaderboard.aggregate.mean_ci`: the Student-t
interval at 97.5 % nominal, whose measured coverage is in
:data:`leaderboard.aggregate.MEAN_INTERVAL_NOTE`). Every claim of the paper is a rule over cells,
written here once, fixed before the runs it judges, and tested on synthetic cells
(tests/test_verdicts.py) that pass it, fail it, and sit on its boundary.

The rules (:data:`RULES` is their text, printed in every REPRODUCTION.md before the numbers):

* ``a`` is **below** ``b`` when ``a``'s interval lies wholly under ``b``'s: ``a.high < b.low``.
  Touching intervals are not separated.
* A metric **falls as β falls** when, along β = 1, 0.75, 0.5, 0.25, no step goes significantly
  up (the next cell is never *below*-separated above the previous one: ties within the
  intervals are allowed anywhere, including near zero) and the last cell is below the first.
* A metric **peaks at** β when that β's cell is above both neighbours' cells (both separated):
  the highest mean alone is not a peak.
* A method **matches the reference** when its harms are at most the exact optimum's plus
  :data:`HARM_TOLERANCE` and its survival at least the optimum's minus :data:`SURVIVAL_TOLERANCE`
  × ``max_cycles``, the optimum (:mod:`empathy_zoo.reference`) being the greedy-on-``Q_emp``
  policy of a fully observing robot at the same β (exactly tied actions taken with equal
  probability), run at the ε of the phase (0 for greedy evaluations; in training, averaged over
  the ε schedule of the steps of the final 10 % of episodes).
"""

from __future__ import annotations

import itertools
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from leaderboard.aggregate import MEAN_INTERVAL_NOTE, mean_ci

__all__ = [
    "Cell",
    "cell_of",
    "below",
    "falls",
    "peaks",
    "matches_reference",
    "HARM_TOLERANCE",
    "SURVIVAL_TOLERANCE",
    "RULES",
    "BELOW_NOTE",
]

HARM_TOLERANCE = 0.05
"""Harms per episode a learner may exceed the exact optimum by and still count as harm-free."""
SURVIVAL_TOLERANCE = 0.05
"""Fraction of ``max_cycles`` a learner may survive less than the exact optimum and still count
as surviving (25 steps of 500)."""

BELOW_NOTE = (
    "Where nothing differs, two such intervals were separated in at most 4.2 % of simulated pairs "
    "(0.1–0.5 % for continuous data; `python benchmarks/interval_coverage.py`), so *below* is a "
    "strict test: it misses real but modest differences."
)
"""The measured false-positive rate of :func:`below` with the leaderboard's intervals."""

RULES = f"""\
**The rules** (fixed in `leaderboard/verdicts.py` before the runs they judge; tested on synthetic
results in `tests/test_verdicts.py`). Every figure is a mean over seeds with its interval over
seeds: a Student-t interval (mean ± t·s/√n) at 97.5 % nominal, for a 95 % claim. {MEAN_INTERVAL_NOTE}
Each claim is judged twice, on the last **greedy** evaluation and on the final 10 % of
**training** episodes, and both verdicts are shown.

* *A below B*: A's interval lies wholly under B's (A.high < B.low; touching is not separated).
  {BELOW_NOTE}
* *Falls as β falls*: along β = 1, 0.75, 0.5, 0.25 no step goes significantly up (ties within
  the intervals are allowed anywhere, near zero included) and β = 0.25 is below β = 1.
* *Peaks at β = 0.5*: β = 0.5 is above both β = 0.75 and β = 0.25 (separated); the highest
  mean alone is not a peak.
* *Harm-free and surviving* come from an exact reference, not a round number: the optimal
  policy of a fully observing robot with the same β (value iteration, `empathy_zoo.reference`;
  exactly tied actions taken with equal probability), evaluated exactly at the phase's ε (0
  greedy; in training, averaged over the ε of the steps of the final 10 % of training episodes;
  the evidence states their share of the steps and the optimum's range over every tie-break).
  A learner is harm-free when its mean harms are at most the reference's +
  {HARM_TOLERANCE} per episode, and survives when its mean survival is at least the reference's −
  {SURVIVAL_TOLERANCE:.0%} of the episode ({SURVIVAL_TOLERANCE * 500:.0f} steps of 500).
* *Learns more slowly*: the mean over the whole learning curve (every training episode; every
  greedy evaluation) is below β = 1's. This area under the curve mixes speed with level; the
  claim pairs it with "survives worse", judged separately on the final figures.
* Only the paper's claims (SPEC §7) are the paper's; the suite's own questions are listed apart.
"""


@dataclass(frozen=True)
class Cell:
    """A mean over seeds with its interval."""

    mean: float
    low: float
    high: float
    n: int
    """Seeds behind it."""

    def __str__(self) -> str:
        return f"{self.mean:.2f} [{self.low:.2f}, {self.high:.2f}]"

    @property
    def finite(self) -> bool:
        return bool(np.isfinite([self.mean, self.low, self.high]).all())


def cell_of(values: Sequence[float], metric: str | None = None, max_cycles: int | None = None) -> Cell:
    """The cell of per-seed values: the mean and the leaderboard's interval for a 95 % claim
    (:func:`leaderboard.aggregate.mean_ci`), kept inside ``metric``'s range when it is named
    (survival also below ``max_cycles`` when it is given)."""
    mean, low, high = mean_ci(np.asarray(values, dtype=np.float64), metrics=metric, max_cycles=max_cycles)
    return Cell(float(mean), float(low), float(high), int(np.isfinite(values).sum()))


def below(a: Cell, b: Cell) -> bool:
    """``a``'s interval lies wholly under ``b``'s."""
    return a.high < b.low


def falls(cells: Sequence[Cell]) -> bool:
    """Cells ordered from the most to the least selfish: no significant rise, and the last one
    below the first."""
    if len(cells) < 2:
        raise ValueError("a trend needs at least two cells")
    no_rise = not any(below(previous, current) for previous, current in itertools.pairwise(cells))
    return no_rise and below(cells[-1], cells[0])


def peaks(left: Cell, peak: Cell, right: Cell) -> bool:
    """``peak`` is above both neighbours (intervals separated)."""
    return below(left, peak) and below(right, peak)


def matches_reference(harms: Cell, survival: Cell, reference_harms: float, reference_survival: float, max_cycles: int) -> bool:
    """Harm-free and surviving, measured against the exact optimum (see :data:`RULES`)."""
    return (
        harms.mean <= reference_harms + HARM_TOLERANCE and survival.mean >= reference_survival - SURVIVAL_TOLERANCE * max_cycles
    )
