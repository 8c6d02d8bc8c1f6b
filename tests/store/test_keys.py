"""The store's keys (store/keys): the settings hash, the thickness in the key, the order of knot
names."""

from __future__ import annotations

import hashlib

import numpy as np
import pytest

from stiffknots.store import (
    ReplicaKey,
    canonical_json,
    knot_sort_key,
    settings_hash,
)
from store_support import (
    D,
)


def test_settings_hash_is_canonical():
    s = {"b": [0.1, 2.5, (1, 2)], "a": 1, "c": {"y": None, "x": True}}
    text = canonical_json(s)
    assert text == '{"a":1,"b":[0.1,2.5,[1,2]],"c":{"x":true,"y":null}}'
    h = settings_hash(s)
    assert h == hashlib.sha256(text.encode()).hexdigest()[:16]
    assert len(h) == 16 and int(h, 16) >= 0
    # key order and numpy types do not matter; values do
    same = {"c": {"x": np.bool_(True), "y": None}, "a": np.int64(1),
            "b": np.array([0.1, 2.5]).tolist() + [np.array([1, 2])]}
    assert settings_hash(same) == h
    assert settings_hash({**s, "a": 2}) != h
    assert settings_hash({**s, "b": [0.1 + 1e-16 * 2, 2.5, (1, 2)]}) != h  # floats by repr
    with pytest.raises(ValueError, match="NaN or infinite"):
        settings_hash({"a": float("nan")})
    with pytest.raises(ValueError, match="mapping"):
        settings_hash([1, 2])


def test_thickness_in_the_key_absorbs_round_off_only():
    a = ReplicaKey("3_1", "bead", 150, D, 0, 0, "0" * 16)
    b = ReplicaKey("3_1", "bead", 150, np.nextafter(D, 1.0), 0, 0, "0" * 16)
    c = ReplicaKey("3_1", "bead", 150, 0.7071, 0, 0, "0" * 16)
    assert a == b and hash(a) == hash(b) and a.thickness_key == "0.707106781187"
    assert a != c
    assert {a, b, c} == {a, c}
    with pytest.raises(ValueError, match="exclusion"):
        ReplicaKey("3_1", "rod", 150, D, 0, 0, "0" * 16)
    with pytest.raises(ValueError, match="settings_hash"):
        ReplicaKey("3_1", "bead", 150, D, 0, 0, "xyz")
    with pytest.raises(ValueError, match="seed"):
        ReplicaKey("3_1", "bead", 150, D, 2**63, 0, "0" * 16)


def test_knot_sort_key_orders_like_the_tables():
    names = ["10_1", "3_1", "K11a10", "5_2", "K11a2", "4_1"]
    assert sorted(names, key=knot_sort_key) == ["3_1", "4_1", "5_2", "10_1", "K11a2", "K11a10"]
