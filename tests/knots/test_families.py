"""The tabulated 80 family (knots.families.EIGHTY_FAMILY) is what the 80 embeddings give."""

from __future__ import annotations

import pytest

from stiffknots.knots.catalogue import catalogue
from stiffknots.knots.families import EIGHTY_FAMILY, EIGHTY_FAMILY_MAX_CROSSINGS


@pytest.mark.slow
def test_eighty_family_is_recomputed_from_the_embeddings():
    """Every spec of eighty_specs(10) built as an N = 150 chain and identified (≈ 45 s):
    the prime two-bridge knots through 10 crossings among them are the table."""
    from stiffknots.knots.eighty_embedding import eighty_table

    two_bridge = {k.name for k in catalogue(EIGHTY_FAMILY_MAX_CROSSINGS)
                  if k.crossing_number >= 3 and k.bridge_number == 2}
    found = {name for _, knot in eighty_table(EIGHTY_FAMILY_MAX_CROSSINGS, 150, free=False)
             for name in knot.split("|")}
    assert found & two_bridge == EIGHTY_FAMILY
