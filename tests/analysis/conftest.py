"""Fixtures of the tests of stiffknots.analysis: the annealed chains of ``tests/data/analysis``
and an open hairpin."""

import json
import math

import numpy as np
import pytest

from helpers import DATA

ANNEALED = DATA / "analysis"


@pytest.fixture(scope="session")
def annealed():
    """The annealed chain of a file of ``tests/data/analysis`` (its ``fixtures.json`` lists
    them with their ε and shape class)."""
    def load(name):
        return np.load(ANNEALED / name)
    return load


@pytest.fixture(scope="session")
def manifest():
    """The entries of ``tests/data/analysis/fixtures.json``: file, knot, epsilon, label,
    multiplicity."""
    return json.loads((ANNEALED / "fixtures.json").read_text())["fixtures"]


def _hairpin(arm=40, tail=10, gap=1.0):
    """Open chain: a straight arm, a half-circle turn of diameter `gap`, a straight arm back
    that goes on for `tail` more bonds."""
    k = 3
    a = np.column_stack([np.arange(arm, 0, -1.0), np.zeros(arm), np.zeros(arm)])
    th = np.linspace(-math.pi / 2, math.pi / 2, k + 2)[1:-1]
    c = np.column_stack([-gap * np.cos(th), 0.5 * gap * np.sin(th) + 0.5 * gap, np.zeros(k)])
    b = np.column_stack([np.arange(1, arm + tail + 1.0), np.full(arm + tail, gap),
                         np.zeros(arm + tail)])
    return np.vstack([a, c, b])


@pytest.fixture(scope="session")
def hairpin():
    """An open chain folded back on itself: a line-braid of two strands with a free tail."""
    return _hairpin
