"""The SQLite store (store/sqlite): round trip, idempotency, uniqueness, states, concurrent writers,
atomicity under kill -9, read-only media, full disks."""

from __future__ import annotations

import os
import pickle
import random
import signal
import sqlite3
import time

import numpy as np
import pytest

from stiffknots._json import to_plain
from stiffknots._version import __version__
from stiffknots.store import (
    KEY_FIELDS,
    ReplicaKey,
    Store,
    StoreError,
    settings_hash,
)
from store_support import (
    SETTINGS,
    D,
    chain,
    fill_5_2,
    make_row,
    wait_for,
    writer,
)


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


def test_put_many_is_all_or_nothing(store):
    items = [(make_row(replica=r), chain()) for r in range(3)] + [
        (make_row(replica=3, epsilon=float("nan")), chain())]
    with pytest.raises(ValueError, match="finite"):
        store.put_many(items)
    assert len(store) == 0


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
