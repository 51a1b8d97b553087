"""A fixed policy's saved random stream, read back from a checkpoint: only its own fields, a key
that is a 64-bit unsigned int, a count in range, arrays of the dtype it writes; else one
``ValueError``, never a wrong resumed run or an OverflowError."""

from __future__ import annotations

import numpy as np
import pytest

from empathy_zoo.builtin_policies import RandomWalk
from empathy_zoo.partner_policies import Population
from empathy_zoo.policies import batched


@pytest.mark.parametrize(
    "change, says",
    [
        ({"evil": 1}, "holds key and count"),
        ({"key": -1}, "64-bit unsigned"),
        ({"key": 2**64}, "64-bit unsigned"),
        ({"count": 10**400}, r"count is an int in \[0, 2\*\*63\)"),
        ({"count": 1.5}, "count is an int"),
    ],
)
def test_a_walks_forged_stream_is_refused(change: dict, says: str) -> None:
    walk = RandomWalk()
    walk.reset(3)
    with pytest.raises(ValueError, match=says):
        RandomWalk().load_state({**walk.state(), **change})


def test_a_batched_walks_forged_arrays_are_refused() -> None:
    fast = batched(RandomWalk(), 2)
    state = fast.state()
    with pytest.raises(ValueError, match="expected uint64"):
        batched(RandomWalk(), 2).load_state({**state, "counts": state["counts"].astype(np.int64)})
    with pytest.raises(ValueError, match="holds keys and counts"):
        batched(RandomWalk(), 2).load_state({**state, "evil": 0})


def test_a_populations_forged_state_is_refused() -> None:
    population = Population(["random_walk", "chase"])
    population.reset(1)
    state = population.state()
    with pytest.raises(ValueError, match="holds key, count, member and members"):
        Population(["random_walk", "chase"]).load_state({**state, "evil": 0})
    with pytest.raises(ValueError, match="64-bit unsigned"):
        Population(["random_walk", "chase"]).load_state({**state, "members": [{"key": -5, "count": 0}, {}]})
