"""Fixtures of the tests of the structures solved at w = 0."""

import numpy as np
import pytest


def _top_order_diffs(res: dict) -> tuple[float, float]:
    """Differences of the best extrapolation to the one a level coarser / an order lower."""
    R = np.array([[np.nan if v is None else v for v in row]
                  for row in res["details"]["richardson_table"]])
    k = R.shape[1] - 1
    return abs(R[-1, k] - R[-2, k]), abs(R[-1, k] - R[-1, k - 1])


@pytest.fixture(scope="session")
def top_order_diffs():
    """Differences of a result's best extrapolation to the one a level coarser and to the one
    an order lower."""
    return _top_order_diffs
