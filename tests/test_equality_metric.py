"""The equality metric (SPEC §5): its values, symmetric, on numbers and arrays, and its refusal of
negative battery rewards."""

from __future__ import annotations

import numpy as np
import pytest

from empathy_zoo.metrics import equality


@pytest.mark.parametrize(
    "robot, other, expected",
    [
        (0.0, 0.0, 1.0),
        (1.0, 1.0, 1.0),
        (1.0, 0.0, 0.0),
        (0.0, 2.5, 0.0),
        (3.0, 1.0, 0.5),  # 2·1 / 4
        (1.9, 1.0, 2.0 / 2.9),  # robot 1.0 + 0.9, other 1.0
        (4.5, 0.9 + 1.0 + 0.8, 2 * 2.7 / 7.2),
    ],
)
def test_equality_values(robot, other, expected):
    assert float(equality(robot, other)) == pytest.approx(expected)
    assert float(equality(other, robot)) == pytest.approx(expected)  # symmetric


def test_equality_on_arrays_and_negative_rewards():
    np.testing.assert_allclose(equality(np.array([0.0, 1.0, 3.0]), np.array([0.0, 1.0, 1.0])), [1.0, 1.0, 0.5])
    with pytest.raises(ValueError, match="non-negative"):
        equality(-0.1, 1.0)
    with pytest.raises(ValueError, match="non-negative"):
        equality(np.array([1.0, 2.0]), np.array([1.0, -2.0]))
