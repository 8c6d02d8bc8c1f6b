"""The strand-passage guard of straight-line motions (:mod:`stiffknots.engine.guard`, §II):
a step that passes a strand through another is refused even when its end state looks
harmless; rigid motions and sliding pass; a bead swept across its neighbours' bond is refused.
"""

from __future__ import annotations

import numpy as np

from stiffknots.engine import kernel as K
from stiffknots.engine.guard import passage_guard


def crossing_loop():
    """A closed 8-bead loop whose segment (0, 1) passes 0.2 above segment (4, 5)."""
    return np.array([
        [-0.5, 0.0, 0.1], [0.5, 0.0, 0.1], [1.5, 0.5, 0.1], [1.5, 1.5, 0.0],
        [0.0, 0.5, -0.1], [0.0, -0.5, -0.1], [-1.5, -1.5, 0.0], [-1.5, -0.5, 0.1],
    ])


def test_guard_rejects_a_step_that_passes_a_strand_through_another():
    old = crossing_loop()
    push = np.zeros_like(old)
    push[[0, 1], 2] = -0.4  # segment (0, 1) dives through segment (4, 5)
    # the end state alone looks harmless: the segments are again 0.2 apart
    assert K.min_nonadjacent_segment_distance(old + push) > 0.1
    assert not passage_guard(old, old + push)
    # shortened, the same motion stops short of the other strand and is accepted
    assert passage_guard(old, old + 0.25 * push)
    # a step that touches the other strand is rejected too
    assert not passage_guard(old, old + 0.5 * push)


def test_guard_accepts_rigid_motions_and_sliding():
    old = crossing_loop()
    # a rigid translation of the whole loop, far larger than the gap
    assert passage_guard(old, old + np.array([3.0, -2.0, 7.0]))
    # the upper strand slides along x, parallel to the lower one, without closing the gap
    slide = np.zeros_like(old)
    slide[[0, 1, 7], 0] = 0.3
    assert passage_guard(old, old + slide)


def test_guard_rejects_a_bead_swept_across_its_neighbours_bond():
    old = crossing_loop()
    mid = 0.5 * (old[7] + old[0])  # middle of the bond (7, 0)
    new = old.copy()
    new[1] = mid + 0.5 * (mid - old[1])  # bead 1's straight path crosses that bond
    assert not passage_guard(old, new)
    assert passage_guard(old, old + 0.25 * (new - old))
