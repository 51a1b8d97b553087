"""The exact solver built from the engine (empathy_zoo.exact_solver): it gives the reference
module's figures for the paper's Coexistence at every β, ε and tie rule tried; the authors' rules
are modelled as the engine plays them (contact not wrapped, a fixed start, the harmed step paid);
and under them β moves the optimum within (0, 1), where under the paper's rules it does not."""

from __future__ import annotations

import numpy as np
import pytest

from empathy_zoo.exact_solver import MAX_STATES, optimum, tabular_model
from empathy_zoo.reference import coexistence_optimum


@pytest.fixture(scope="module")
def paper():
    return tabular_model("coexistence_v0")


@pytest.fixture(scope="module")
def authors():
    return tabular_model("coexistence_v0", rules="authors", max_cycles=501)


@pytest.mark.parametrize("ties", ["uniform", "first"])
@pytest.mark.parametrize("epsilon", [0.0, 0.01, 0.05])
@pytest.mark.parametrize("beta", [1.0, 0.5, 0.0])
def test_the_paper_optimum_is_the_reference_modules(paper, beta, epsilon, ties) -> None:
    solved, reference = optimum(paper, beta, epsilon, ties=ties), coexistence_optimum(beta, epsilon, ties=ties)
    assert solved.harms == pytest.approx(reference.harms, abs=1e-9)
    assert solved.survival == pytest.approx(reference.survival, abs=1e-6)


def test_the_model_is_the_engines_step(paper, authors) -> None:
    cells = paper.cells
    robot, other = 24, 26  # (3, 3) and (3, 5): the cat steps left next to the robot, which stays
    index = robot * cells + other
    assert paper.robot_harmed[index, 4, 2] and not authors.robot_harmed[index, 4, 2]
    assert authors.other_harmed[index, 4, 2] and not paper.other_harmed[index, 4, 2]
    assert paper.reward[index, 4, 2] == 0.0 and authors.reward[index, 4, 4] == 1.0
    # the authors' start: the robot in the centre, the cat in the corner
    assert np.flatnonzero(authors.start).tolist() == [24 * cells + 0] and authors.start.sum() == 1.0
    assert paper.start.sum() == pytest.approx(1.0) and np.count_nonzero(paper.start) == 49 * 44


def test_under_the_authors_rules_selfishness_moves_the_optimum_within_zero_and_one(paper, authors) -> None:
    betas = (0.75, 0.5, 0.25)
    paper_outcomes = {optimum(paper, beta, 0.01) for beta in betas}
    assert len({(round(o.harms, 9), round(o.survival, 6)) for o in paper_outcomes}) == 1
    harms = [optimum(authors, beta, 0.01).harms for beta in betas]
    survival = [optimum(authors, beta, 0.01).survival for beta in betas]
    assert harms[0] > harms[1] > harms[2] and survival[0] > survival[1] > survival[2]


def test_a_grid_too_large_to_enumerate_is_refused() -> None:
    size = int(MAX_STATES**0.25) + 2
    with pytest.raises(ValueError, match="joint states"):
        tabular_model("coexistence_v0", size=size, view=3)
