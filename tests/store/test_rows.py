"""Rows of the store (store/rows): bad rows and chains refused clearly, an engine result
mapped to a row."""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np
import pytest

from stiffknots.store import (
    row_from_replica,
)
from stiffknots.width import Width
from store_support import (
    SETTINGS,
    D,
    chain,
    make_row,
)

BAD = [
    ({"epsilon": None}, "required field.*epsilon"),
    ({"knot": None}, "required field.*knot"),
    ({"epsilon": float("nan")}, "'epsilon' must be finite"),
    ({"wall_seconds": float("inf")}, "'wall_seconds' must be finite"),
    ({"epsilon": "128"}, "'epsilon' must be a number"),
    ({"beads": 150.0}, "'beads' must be an integer"),
    ({"beads": True}, "'beads' must be an integer"),
    ({"seed": -1}, "'seed' must be in"),
    ({"thickness": 0.0}, "'thickness' must be >"),
    ({"exclusion": "rod"}, "'exclusion' must be one of"),
    ({"shape": "cage"}, "'shape' must be one of"),
    ({"shape": "CB"}, "'multiplicity' must be an integer"),
    ({"shape": "4C", "multiplicity": 2}, "only a 'CB' shape"),
    ({"converged": 2}, "'converged' must be True, False or None"),
    ({"energy": 1.0}, "unknown row field.*energy.*extra"),
    ({"settings": {"moves": 10}}, "settings must name the problem"),
    ({"settings_hash": "0123456789abcdef"}, "does not match the settings"),
    ({"min_segment_distance": -0.1}, "'min_segment_distance' must be ≥ 0"),
]


@pytest.mark.parametrize(("over", "message"), BAD)
def test_bad_rows_are_refused_clearly(store, over, message):
    with pytest.raises(ValueError, match=message):
        store.put(make_row(**over), chain())
    assert len(store) == 0


@pytest.mark.parametrize(("coords", "message"), [
    (chain(149), r"shape \(beads, 3\) = \(150, 3\), got \(149, 3\)"),
    (chain()[:, :2], r"got \(150, 2\)"),
    (chain().ravel(), r"got \(450,\)"),
    (np.where(np.arange(450).reshape(150, 3) == 7, np.nan, 1.0), "finite"),
    (np.full((150, 3), "a"), "real numbers"),
])
def test_bad_coords_are_refused_clearly(store, coords, message):
    with pytest.raises(ValueError, match=message):
        store.put(make_row(), coords)
    assert len(store) == 0


def test_row_from_replica_maps_an_engine_result(store):
    x = chain()

    class Result(SimpleNamespace):
        def summary(self):
            d = dict(vars(self))
            d.pop("coords")
            return d

    res = Result(replica=3, seed=123456789, epsilon=129.6, energy=0.864, coords=x,
                 wall_time=40.0, cpu_time=39.5, min_segment_distance=0.71, knot="5_2",
                 knot_verified=True, version="0.1.0", start="cage", stage_epsilon={"a": 130.0},
                 acceptance={"single": 0.4}, seconds_to_target=None)
    row, coords = row_from_replica(res, knot="5_2", width=Width.bead(150, d=D), seed=0,
                                   settings=SETTINGS, shape="4C", converged=True)
    assert coords is not None and row["beads"] == 150 and row["w_over_L"] == D / 150
    assert store.put(row, coords)
    (r,) = store.replicas()
    assert (r["seed"], r["replica"], r["replica_seed"]) == (0, 3, 123456789)
    assert (r["wall_seconds"], r["cpu_seconds"], r["start"]) == (40.0, 39.5, "cage")
    assert r["extra"] == {"energy": 0.864, "stage_epsilon": {"a": 130.0},
                          "acceptance": {"single": 0.4}, "seconds_to_target": None}
