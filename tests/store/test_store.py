"""Tests of stiffknots.store: keys and settings hash, round trip, idempotency, uniqueness,
validation, states and ground states, schema versioning, concurrent writers and atomicity under
kill -9."""

from __future__ import annotations

import csv
import hashlib
import os
import pickle
import random
import signal
import sqlite3
import subprocess
import sys
import time
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pytest

from stiffknots._json import to_plain
from stiffknots._version import __version__
from stiffknots.store import (
    KEY_FIELDS,
    SCHEMA_VERSION,
    KeyCollisionError,
    ReplicaKey,
    SchemaVersionError,
    Store,
    StoreError,
    canonical_json,
    describe_knot,
    ground_table,
    knot_sort_key,
    row_from_replica,
    settings_hash,
    to_csv,
)
from stiffknots.store.rows import SHAPES
from stiffknots.store.schema import COLUMNS
from stiffknots.width import Width

WRITER = Path(__file__).with_name("writer.py")
SETTINGS = {"problem": "anneal", "moves": 30_000_000, "start": "all",
            "params": {"exclusion": "bead", "d": 2 ** -0.5, "delta": np.pi / 100}}
D = 2 ** -0.5


def make_row(**over):
    row = {"knot": "5_2", "exclusion": "bead", "beads": 150, "thickness": D, "seed": 0,
           "replica": 0, "settings": SETTINGS, "epsilon": 128.4, "min_segment_distance": 0.72,
           "wall_seconds": 12.5}
    row.update(over)
    return row


def chain(beads=150, seed=0):
    return np.random.default_rng(seed).normal(size=(beads, 3))


@pytest.fixture
def store(tmp_path):
    with Store(tmp_path / "db" / "results.db") as s:
        yield s


def writer(*args, **kw):
    return subprocess.Popen([sys.executable, str(WRITER), *map(str, args)],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, **kw)


def wait_for(proc, word, timeout=30.0):
    """Read the writer's stdout until a line starting with ``word``; return the lines."""
    lines, end = [], time.monotonic() + timeout
    while time.monotonic() < end:
        line = proc.stdout.readline()
        if not line:
            raise AssertionError(f"writer ended before {word!r}: {proc.stderr.read()}")
        lines.append(line.split())
        if lines[-1][0] == word:
            return lines
    raise AssertionError(f"writer did not say {word!r} in {timeout} s")


# ---- keys and hashes ---------------------------------------------------------------------------

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


# ---- the database -----------------------------------------------------------------------------

def test_new_database_is_wal_and_versioned(tmp_path):
    path = tmp_path / "a" / "b" / "x.db"
    with Store(path) as s:
        assert s.meta()["schema_version"] == str(SCHEMA_VERSION)
        assert s.meta()["created_by"] == f"stiffknots {__version__}"
        assert len(s) == 0 and s.knots() == []
    con = sqlite3.connect(path)
    assert con.execute("PRAGMA journal_mode").fetchone()[0] == "wal"
    cols = [r[1] for r in con.execute("PRAGMA table_info(replicas)")]
    assert tuple(cols) == COLUMNS
    con.close()
    Store(path).close()  # reopening an existing database works


def test_schema_version_mismatch_is_a_clear_error(tmp_path):
    path = tmp_path / "x.db"
    Store(path).close()
    con = sqlite3.connect(path)
    con.execute("UPDATE meta SET value = '99' WHERE key = 'schema_version'")
    con.commit()
    con.close()
    with pytest.raises(SchemaVersionError, match=r"schema version 99.*reads version 1.*Upgrade"):
        Store(path)
    con = sqlite3.connect(path)
    con.execute("UPDATE meta SET value = '0' WHERE key = 'schema_version'")
    con.commit()
    con.close()
    with pytest.raises(SchemaVersionError, match="No migration"):
        Store(path)


def test_foreign_files_are_refused(tmp_path):
    text = tmp_path / "notes.db"
    text.write_text("not a database at all, just some text that is long enough")
    with pytest.raises(StoreError, match="not an SQLite database"):
        Store(text)
    other = tmp_path / "other.db"
    con = sqlite3.connect(other)
    con.execute("CREATE TABLE t (x)")
    con.commit()
    con.close()
    with pytest.raises(StoreError, match="not a stiffknots results database"):
        Store(other)
    with pytest.raises(StoreError, match="no results database"):
        Store(tmp_path / "missing.db", create=False)
    assert not (tmp_path / "missing.db").exists()
    with pytest.raises(StoreError, match="folder"):
        Store(tmp_path)


def test_round_trip_is_bit_exact(store):
    x = chain()
    x[0] = [-0.0, 5e-324, 1e300]  # signed zero, subnormal, huge
    x[1] = [np.nextafter(1.0, 2.0), -np.pi, 1 / 3]
    row = make_row(replica_seed=2**62 + 5, shape="CB", multiplicity=3, converged=True,
                   start="braid", cpu_seconds=11.25, knot_verified=False,
                   extra={"energy": np.float64(2.5), "acceptance": {"single": 0.5},
                          "trace": np.arange(3)}, version="9.9.9")
    assert store.put(row, x) is True
    (r,) = store.replicas()
    got = store.coords(r["id"])
    assert got.dtype == np.float64 and got.shape == (150, 3)
    assert got.tobytes() == x.tobytes()  # bit-exact, -0.0 included
    assert got.flags.writeable
    assert r["settings"] == to_plain(SETTINGS)
    assert r["settings_hash"] == settings_hash(SETTINGS)
    for name in ("knot", "exclusion", "beads", "thickness", "seed", "replica", "replica_seed",
                 "epsilon", "shape", "multiplicity", "min_segment_distance", "converged",
                 "start", "wall_seconds", "cpu_seconds", "knot_verified", "version"):
        assert r[name] == row[name], name
    assert r["problem"] == "anneal"
    assert r["w_over_L"] == D / 150
    assert r["extra"] == {"energy": 2.5, "acceptance": {"single": 0.5}, "trace": [0, 1, 2]}
    assert r["created"].endswith("+00:00")
    assert "coords" not in r
    assert store.get(r["id"]) == r
    assert store.check()["ok"]
    # defaults: version of this code, optional fields NULL
    store.put(make_row(replica=1), x)
    r1 = store.replicas(replica=1)[0]
    assert r1["version"] == __version__
    assert r1["shape"] is None and r1["converged"] is None and r1["cpu_seconds"] is None


def test_put_twice_is_a_no_op(store):
    assert store.put(make_row(), chain()) is True
    assert store.put(make_row(epsilon=999.0), chain(seed=1)) is False  # the first write wins
    assert len(store) == 1
    (r,) = store.replicas()
    assert r["epsilon"] == 128.4
    assert store.coords(r["id"]).tobytes() == chain().tobytes()
    assert store.put_many([(make_row(), chain()), (make_row(replica=1), chain())]) == 1
    assert len(store) == 2


CHANGES = {"knot": "4_1", "exclusion": "tube", "beads": 151, "thickness": 0.5, "seed": 1,
           "replica": 1, "settings_hash": {**SETTINGS, "moves": 1_000_000}}


@pytest.mark.parametrize("field", KEY_FIELDS)
def test_every_key_field_makes_a_new_row(store, field):
    assert set(CHANGES) == set(KEY_FIELDS)
    store.put(make_row(), chain())
    new = make_row(**({"settings": CHANGES[field]} if field == "settings_hash"
                      else {field: CHANGES[field]}))
    assert store.put(new, chain(new["beads"])) is True
    assert len(store) == 2
    keys = store.keys()
    assert len(keys) == 2
    new_key = ReplicaKey.from_row(new)
    assert new_key in keys and store.has(new_key)
    # a thickness that differs by round-off only is the same key
    assert store.put(make_row(thickness=np.nextafter(D, 0.0)), chain()) is False


def test_keys_and_filters(store):
    for seed in range(2):
        for r in range(3):
            store.put(make_row(seed=seed, replica=r, start=["braid", "cage", "80"][r]), chain())
    store.put(make_row(knot="3_1", shape="CB", multiplicity=2, epsilon=79.5), chain())
    assert len(store.keys(knot="5_2")) == 6
    assert len(store.keys(knot="5_2", seed=1)) == 3
    assert len(store.keys(thickness=np.sqrt(0.5))) == 7  # another spelling of 1/√2
    assert store.keys(thickness=0.5) == set()
    assert store.count(start=["braid", "cage"]) == 4
    assert store.count(settings_hash=settings_hash(SETTINGS)) == 7
    key = ReplicaKey("5_2", "bead", 150, D, 1, 2, settings_hash(SETTINGS))
    assert store.has(key) and not store.has(ReplicaKey("5_2", "bead", 150, D, 2, 2, key
                                                       .settings_hash))
    assert store.knots() == ["3_1", "5_2"]
    with pytest.raises(ValueError, match="unknown filter"):
        store.replicas(colour="red")
    with pytest.raises(ValueError, match="ReplicaKey"):
        store.has(("5_2",))


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


def test_put_many_is_all_or_nothing(store):
    items = [(make_row(replica=r), chain()) for r in range(3)] + [
        (make_row(replica=3, epsilon=float("nan")), chain())]
    with pytest.raises(ValueError, match="finite"):
        store.put_many(items)
    assert len(store) == 0


def test_same_key_from_another_start_is_a_collision(store):
    store.put(make_row(start="braid", replica_seed=11), chain())
    assert store.put(make_row(start="braid", replica_seed=11), chain()) is False
    with pytest.raises(KeyCollisionError, match="start 'braid'.*'cage'"):
        store.put(make_row(start="cage"), chain())
    with pytest.raises(KeyCollisionError, match="replica_seed"):
        store.put(make_row(replica_seed=12), chain())
    assert len(store) == 1


def test_damaged_chain_is_detected(store):
    store.put(make_row(), chain())
    con = sqlite3.connect(store.path)
    blob = bytearray(con.execute("SELECT coords FROM replicas").fetchone()[0])
    blob[100] ^= 1
    con.execute("UPDATE replicas SET coords = ?", (bytes(blob),))
    con.commit()
    con.close()
    with pytest.raises(StoreError, match="damaged"):
        store.coords(1)
    assert store.coords(1, verify=False).tobytes() == bytes(blob)
    report = store.check()
    assert not report["ok"] and report["bad_coords"] == [1] and report["integrity"] == ["ok"]


def test_schema_refuses_a_short_blob_even_behind_the_api(store):
    store.put(make_row(), chain())
    con = sqlite3.connect(store.path)
    with pytest.raises(sqlite3.IntegrityError, match="CHECK"):
        con.execute("UPDATE replicas SET coords = zeroblob(100)")
    con.close()


def test_store_pickles_as_its_path_and_survives_fork(store):
    store.put(make_row(), chain())
    other = pickle.loads(pickle.dumps(store))
    assert other.path == store.path and len(other) == 1
    other.close()
    pid = os.fork()
    if pid == 0:  # child: write through the inherited Store (it must open its own connection)
        ok = store.put(make_row(replica=5), chain())
        os._exit(0 if ok else 1)
    _, status = os.waitpid(pid, 0)
    assert os.waitstatus_to_exitcode(status) == 0
    assert len(store) == 2 and store.check()["ok"]


def test_threads_may_share_a_store(store):
    import threading

    def work(t):
        for r in range(25):
            assert store.put(make_row(seed=t, replica=r), chain())

    threads = [threading.Thread(target=work, args=(t,)) for t in range(4)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    assert len(store) == 100 and store.check()["ok"]


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


# ---- states -------------------------------------------------------------------------------------

def fill_5_2(store):
    """A 5_2 ensemble with a known grouping (1 % rule) and rows that must stay apart."""
    data = [  # (epsilon, shape, multiplicity, start)
        (128.9, "4C", None, "braid"), (128.4, "4C", None, "cage"), (129.5, "4C", None, "cage"),
        (147.3, "80", None, "80"), (148.1, "80", None, "braid"),
        (152.0, "80", None, "80"),  # > 1 % above 147.3: a state of its own
        (181.2, "CB", 3, "braid"), (150.0, "other", None, "braid"),
    ]
    ids = {}
    for r, (eps, shape, mult, start) in enumerate(data):
        store.put(make_row(replica=r, epsilon=eps, shape=shape, multiplicity=mult, start=start,
                           converged=r != 1), chain())
        ids[eps] = store.replicas(replica=r, beads=150, exclusion="bead")[0]["id"]
    # never mixed in: other N, other model, other width, other settings (all with lower ε)
    store.put(make_row(beads=100, epsilon=100.0, shape="4C"), chain(100))
    store.put(make_row(exclusion="tube", epsilon=101.0, shape="4C"), chain())
    store.put(make_row(thickness=0.5, epsilon=102.0, shape="4C"), chain())
    store.put(make_row(settings={**SETTINGS, "moves": 10}, epsilon=103.0, shape="80"),
              chain())
    return ids


def test_states_group_one_ensemble_only(store):
    ids = fill_5_2(store)
    with pytest.raises(ValueError, match="5 ensembles of 5_2 match.*beads=100"):
        store.states("5_2")
    st = store.states("5_2", exclusion="bead", beads=150, thickness=D,
                      settings_hash=settings_hash(SETTINGS))
    assert st["replicas"] == 8 and st["classified"] == 0 and st["rel_tol"] == 0.01
    g = st["ground"]
    assert (g["name"], g["count"], g["epsilon"]) == ("4C", 3, 128.4)
    assert g["eps_mean"] == pytest.approx((128.4 + 128.9 + 129.5) / 3)
    assert g["eps_max"] == 129.5
    assert g["representative"] == ids[128.4] and g["start"] == "cage" and g["replica"] == 1
    assert g["starts"] == {"cage": 2, "braid": 1}
    assert g["converged"] is False and g["converged_count"] == 2
    assert sorted(g["ids"]) == sorted([ids[128.4], ids[128.9], ids[129.5]])
    meta = [(s["name"], s["count"], s["epsilon"]) for s in st["metastable"]]
    assert meta == [("80", 2, 147.3), ("other", 1, 150.0), ("80", 1, 152.0),
                    ("CB(i=3)", 1, 181.2)]
    assert st["metastable"][-1]["multiplicity"] == 3
    # a wider tolerance merges the two 80 states
    wide = store.states("5_2", beads=150, exclusion="bead", thickness=D,
                        settings_hash=settings_hash(SETTINGS), rel_tol=0.05)
    assert [(s["name"], s["count"]) for s in wide["metastable"]] == [
        ("80", 3), ("other", 1), ("CB(i=3)", 1)]
    with pytest.raises(ValueError, match="stored knots: 5_2"):
        store.states("3_1")


def test_rows_without_a_shape_are_classified_from_their_chain(store):
    from stiffknots.analysis.synthetic import torus_braid

    x = torus_braid(2, 150)
    for r in range(2):
        store.put(make_row(knot="3_1", replica=r, epsilon=79.5 + r * 0.1), x)
    st = store.states("3_1")
    assert st["classified"] == 2
    assert (st["ground"]["name"], st["ground"]["count"]) == ("CB(i=2)", 2)
    assert store.replicas()[0]["shape"] is None  # nothing written back


def test_every_state_names_its_contact_structure(store):
    """``structure``: the §V B name of the state's lowest chain at the ensemble's thickness;
    None when not asked (a sweep's convergence checks) and for a stored chain the analysis
    cannot read (not unit bonds, or beads closer than d)."""
    from stiffknots.analysis import analyse_structure
    from stiffknots.analysis.synthetic import four_cage, torus_braid

    store.put(make_row(knot="3_1", replica=0, epsilon=79.5, shape="CB", multiplicity=2),
              torus_braid(2, 150, separation=0.9))
    store.put(make_row(knot="3_1", replica=1, epsilon=90.0, shape="4C"), four_cage())
    store.put(make_row(knot="3_1", replica=2, epsilon=95.0, shape="other"), chain())
    st = store.states("3_1")
    names = [s["structure"] for s in (st["ground"], *st["metastable"])]
    assert names == ["circular line-braid (m = 2)", "2 point-braids", None]
    assert names[1] == analyse_structure(store.coords(st["metastable"][0]["representative"]),
                                         d=D).name
    assert all(s["structure"] is None for s in (
        lambda x: (x["ground"], *x["metastable"]))(store.states("3_1", structure=False)))
    (row,) = store.ground_states()
    assert row["structure"] == "circular line-braid (m = 2)"
    assert store.ground_states(structure=False)[0]["structure"] is None


def test_ground_table_one_row_per_model_and_csv(store, tmp_path):
    fill_5_2(store)
    # a second settings for the 150-bead bead model with a higher ground: not chosen
    store.put(make_row(settings={**SETTINGS, "moves": 20}, epsilon=140.0, shape="4C"),
              chain())
    store.put(make_row(knot="3_1", shape="CB", multiplicity=2, epsilon=79.5, start="braid"),
              chain())
    table = ground_table(store)
    models = [(t["knot"], t["exclusion"], t["beads"], t["thickness"]) for t in table]
    assert models == [("3_1", "bead", 150, D), ("5_2", "bead", 100, D), ("5_2", "bead", 150, 0.5),
                      ("5_2", "bead", 150, D), ("5_2", "tube", 150, D)]
    row = table[3]
    assert (row["state"], row["epsilon"], row["n_settings"]) == ("80", 103.0, 3)
    assert row["settings_hash"] == settings_hash({**SETTINGS, "moves": 10})
    assert table[0]["state"] == "CB(i=2)" and table[0]["multiplicity"] == 2
    only = store.ground_states(knot="5_2", beads=150, exclusion="bead", thickness=D)
    assert len(only) == 1 and only[0]["epsilon"] == 103.0
    full = store.states("5_2", beads=150, exclusion="bead", thickness=D,
                        settings_hash=settings_hash(SETTINGS))
    assert full["ground"]["epsilon"] == 128.4
    path = to_csv(tmp_path / "out" / "ground.csv", table)
    with open(path, newline="") as f:
        back = list(csv.DictReader(f))
    assert len(back) == 5 and list(back[0]) == list(table[0])
    assert float(back[0]["thickness"]) == D and back[0]["converged"] == ""
    assert back[0]["knot_verified"] == "" and back[0]["metastable"] == ""
    assert (back[3]["state"], back[3]["epsilon"], back[3]["n_settings"]) == ("80", "103.0", "3")
    # one settings only: its ground and, in order, its metastable states
    (one,) = store.ground_states(knot="5_2", exclusion="bead", beads=150, thickness=D,
                                 settings_hash=settings_hash(SETTINGS))
    assert (one["state"], one["count"], one["replicas"], one["n_states"]) == ("4C", 3, 8, 5)
    assert one["metastable"] == "80 147.30 ×2; other 150.00 ×1; 80 152.00 ×1; CB(i=3) 181.20 ×1"


def test_describe_knot_lists_every_ensemble(store):
    fill_5_2(store)
    d = describe_knot(store, "5_2")
    assert d["knot"] == "5_2" and len(d["ensembles"]) == 5 and d["replicas"] == 12
    (main,) = [e for e in d["ensembles"] if e["replicas"] == 8]
    assert main["ground"]["name"] == "4C"
    assert len(describe_knot(store, "5_2", beads=150, exclusion="bead")["ensembles"]) == 3
    with pytest.raises(ValueError, match="no stored replicas of knot '9_9'.*stored knots: 5_2"):
        describe_knot(store, "9_9")


def test_shape_labels_match_the_classifier():
    from stiffknots.analysis.shapes import LABELS

    assert tuple(SHAPES) == tuple(LABELS)


# ---- several processes, kill -9 ----------------------------------------------------------------

def test_concurrent_writers_lose_nothing(tmp_path):
    db, barrier = tmp_path / "c.db", tmp_path / "go"  # both writers create the database
    procs = [writer(db, "loop", seed, 200, 150, "--shared", 50, "--barrier", barrier)
             for seed in (1, 2)]
    for p in procs:
        wait_for(p, "ready")
    barrier.touch()
    inserted = []
    for p in procs:
        lines = wait_for(p, "inserted", timeout=120)
        assert p.wait(30) == 0, p.stderr.read()
        inserted.append(int(lines[-1][1]))
        assert sum(1 for ln in lines if ln[0] == "done") == 250
    with Store(db) as s:
        assert len(s) == 450  # 2 × 200 own rows + 50 shared keys stored once
        assert s.count(seed=1) == s.count(seed=2) == 200 and s.count(seed=999) == 50
        assert s.check()["ok"]
    assert sum(inserted) == 450  # each shared key written by exactly one of them


def test_a_writer_killed_inside_its_transaction_leaves_nothing(tmp_path):
    db = tmp_path / "k.db"
    Store(db).close()
    p = writer(db, "hang", 20_000)
    wait_for(p, "in-transaction")  # the row is INSERTed, the COMMIT not yet run
    os.kill(p.pid, signal.SIGKILL)
    p.wait(30)
    assert p.returncode == -signal.SIGKILL
    with Store(db) as s:
        assert len(s) == 0
        assert s.check() == {"ok": True, "integrity": ["ok"], "rows": 0, "bad_coords": [],
                             "bad_settings": []}
        assert s.put(make_row(), chain()) is True  # and the database is writable


def test_kill_9_at_random_moments_leaves_no_half_row(tmp_path):
    """Writers of 480 kB chains killed with SIGKILL at random moments (5 kills, up to 10 until
    one has landed inside a put; a put spends ~85 % of its time in its SQLite transaction).
    After each kill: SQLite's integrity check passes, every row's chain has 24·N bytes and its
    SHA-256, every row a writer reported written is there, no row is there that no writer
    began, and the next writer resumes by skipping the stored keys."""
    db, beads = tmp_path / "kill.db", 20_000
    Store(db).close()
    rng = random.Random(20240611)
    written, begun, where, stored = set(), set(), [], set()
    while len(where) < 5 or (len(where) < 10 and not any(w[0] == "begin" for w in where)):
        p = writer(db, "loop", 3, 100_000, beads, "--skip-stored")
        wait_for(p, "ready")
        time.sleep(rng.uniform(0.02, 0.3))
        os.kill(p.pid, signal.SIGKILL)
        p.wait(30)
        assert p.returncode == -signal.SIGKILL
        out = p.stdout.read()  # (not communicate(): it would skip what readline buffered)
        p.stdout.close()
        p.stderr.close()
        # a kill between the writes of one line would leave it cut: read whole lines only
        lines = [ln.split() for ln in out.splitlines(keepends=True) if ln.endswith("\n")]
        begun |= {int(ln[1]) for ln in lines if ln[0] == "begin"}
        now_written = {int(ln[1]) for ln in lines if ln[0] == "done" and ln[2] == "1"}
        last = next((ln for ln in reversed(lines) if ln[0] in ("begin", "done")), ["ready"])
        where.append(last)
        with Store(db) as s:
            report = s.check()  # integrity_check, every blob's length and SHA-256
            assert report["ok"], report
            before, stored = stored, {k.replica for k in s.keys()}
            assert written | now_written <= stored, "a row reported written is missing"
            assert stored <= begun, "a row appeared that no writer began"
            # unreported: at most the one put killed after its COMMIT, before it printed
            unreported = stored - before - now_written
            assert len(unreported) <= 1 and (not unreported or last[0] == "begin")
            written |= now_written | unreported
            assert all(s.coords(r["id"]).shape == (beads, 3) for r in s.replicas())
    assert any(w[0] == "begin" for w in where), f"no kill landed inside a put: {where}"
    print(f"\n{len(where)} kills, last words: {[' '.join(w) for w in where]}; "
          f"{len(written)} rows stored")
    for f in tmp_path.glob("kill.db*"):  # ~100 MB: do not keep it among pytest's last runs
        f.unlink()


# ---- read-only media, immutable files, full disks (#40 rows 2, 3, 4, 14) -------------------------


def test_a_query_reads_a_database_on_read_only_media(small_fs):
    """Row 3: a good database on a read-only mount was 'not a usable SQLite database'."""
    fs = small_fs("4m")
    with Store(fs / "r.db") as s:
        fill_5_2(s)
    small_fs.readonly(fs)
    with Store(fs / "r.db", readonly=True) as s:
        assert len(s.replicas(knot="5_2")) == 12
    with pytest.raises(StoreError, match=r"r\.db: cannot open the results database for "
                                         r"writing \(Read-only file system"):
        Store(fs / "r.db")


def test_an_immutable_database_is_refused_when_opened_not_at_its_first_row(tmp_path,
                                                                           immutable):
    """Row 2: an immutable file opened (SQLite falls back to reading) and the first replica
    of the sweep was lost with 'attempt to write a readonly database'."""
    with Store(tmp_path / "r.db") as s:
        s.put(make_row(), chain())
    immutable(tmp_path / "r.db")
    with pytest.raises(StoreError, match=r"cannot open the results database for writing "
                                         r"\(Operation not permitted"):
        Store(tmp_path / "r.db")
    with Store(tmp_path / "r.db", readonly=True) as s:
        assert len(s.replicas()) == 1


def test_a_query_writes_nothing_into_an_empty_file(tmp_path):
    """Row 14: `db states` on a 0-byte --db wrote the schema into it."""
    (tmp_path / "empty.db").write_bytes(b"")
    for kw in ({"readonly": True}, {"create": False}):
        with pytest.raises(StoreError, match=r"empty\.db is empty: no results database yet"):
            Store(tmp_path / "empty.db", **kw)
    assert (tmp_path / "empty.db").read_bytes() == b""
    assert sorted(p.name for p in tmp_path.iterdir()) == ["empty.db"]


def test_a_full_disk_stores_nothing_half_and_keeps_every_stored_row(small_fs):
    """Row 4: 'database or disk is full' was a traceback; now one StoreError naming the file
    and the full disk, and the rows stored before stay, whole."""
    from helpers import fill_up

    fs = small_fs("2m")
    s = Store(fs / "r.db")
    s.put(make_row(replica=0), chain())
    fill_up(fs, leave=0)
    with pytest.raises(StoreError, match=r"r\.db: cannot write the results database \(no "
                                         r"space left on the device.*rows stored before are "
                                         r"kept"):
        for r in range(1, 200):
            s.put(make_row(replica=r), chain(seed=r))
    s.close()
    (fs / "filler").unlink()
    with Store(fs / "r.db") as s:
        assert s._query("PRAGMA integrity_check") == [("ok",)]
        rows = s.replicas()
        assert rows[0]["replica"] == 0 and len(rows) >= 1


def test_a_database_that_does_not_fit_leaves_no_file(small_fs):
    """Row 4: a new database on a full disk left a 0-byte file and 0-byte -wal and -shm."""
    from helpers import fill_up

    fs = small_fs("1m")
    fill_up(fs, leave=0)
    with pytest.raises(StoreError, match=r"new\.db: cannot open the results database for "
                                         r"writing.*(No space left|disk is full)"):
        Store(fs / "new.db")
    assert sorted(p.name for p in fs.iterdir()) == ["filler"]
