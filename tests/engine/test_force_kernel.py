"""Open chains at fixed force (paper §VIII): the end moves of the force kernel.

Ends stay on the axis, bonds stay unit, E_d − F·Δz is booked exactly, the knot type and the
exclusion survive hot fuzzing, the moves sample the right ensemble (exact average on a 7-bead
chain), and the annealed chain satisfies force balance μ = E_d/L_e = F (slow).
"""

from __future__ import annotations

import json
import subprocess
import sys

import numpy as np
import pytest
from numba import njit

from helpers import force_state
from stiffknots.engine import kernel as K
from stiffknots.engine.force_kernel import run_end_moves, run_slide_moves
from stiffknots.engine.state import ChainState, MoveParams, check_open_clamping
from stiffknots.geometry import seg_dist2
from stiffknots.knots.identify import close_open_chain_along_z, verify_knot
from stiffknots.problems.open_extension import open_chain


@pytest.fixture(scope="module")
def open31():
    return open_chain("3_1", 30, seed=0)


@pytest.fixture(scope="module")
def open41():
    return open_chain("4_1", 30, seed=0)


def _assert_clamped(pos):
    """End beads exactly on the z axis, end segments along ∓z, free beads inside the slab."""
    assert np.all(pos[[0, 1, -2, -1], :2] == 0.0)
    assert abs(pos[1, 2] - pos[0, 2] - 1.0) < 1e-12
    assert abs(pos[-1, 2] - pos[-2, 2] - 1.0) < 1e-12
    check_open_clamping(pos, tol=0.0)


def _bond_error(pos):
    return float(np.max(np.abs(np.linalg.norm(np.diff(pos, axis=0), axis=1) - 1.0)))


def _run_kind(st, kind, n, temperature):
    return {"pivot": st.run_ends, "slide": st.run_slides, "mixed": st.run}[kind](n, temperature)


# ------------------------------------------------------------------------------------------
# 1. geometry is exact
# ------------------------------------------------------------------------------------------


@pytest.mark.parametrize("exclusion", ["bead", "tube"])
@pytest.mark.parametrize("kind", ["pivot", "slide"])
def test_end_moves_keep_ends_on_axis_and_bonds(open31, kind, exclusion):
    st = force_state(open31, MoveParams(exclusion=exclusion), seed=3, force=0.05)
    counters = st.end_counters if kind == "pivot" else st.slide_counters
    for _ in range(10):
        _run_kind(st, kind, 20_000, 0.05)
        _assert_clamped(st.pos)
        assert _bond_error(st.pos) < 1e-10
        assert st.violation() <= 1e-12
        # the crankshaft kernel's slab follows the moving ends
        assert st.fpar[K.F_ZLO] == st.pos[0, 2] and st.fpar[K.F_ZHI] == st.pos[-1, 2]
    assert counters[K.C_ACCEPTED] > 1000 and counters[K.C_ACCEPTED + 1] > 1000


def test_cell_list_stays_consistent_with_positions(open31):
    st = force_state(open31, MoveParams(), seed=4, force=0.05, end_fraction=0.5)
    st.run(100_000, 0.05)
    head, nxt, prv, bucket = (np.empty_like(a) for a in (st.head, st.nxt, st.prv, st.bucket))
    K.cell_build(st.pos, st.params.cell, head, nxt, prv, bucket, True)
    assert np.array_equal(bucket, st.bucket)  # every segment hashed where its midpoint is
    for h in np.unique(bucket[bucket >= 0]):
        chain, v = set(), st.head[h]
        while v >= 0:
            chain.add(int(v))
            v = st.nxt[v]
        assert chain == set(np.flatnonzero(bucket == h).tolist())


# ------------------------------------------------------------------------------------------
# 2. the moves change the extension, and the force stretches the chain
# ------------------------------------------------------------------------------------------


@pytest.mark.parametrize("kind", ["pivot", "slide"])
def test_end_moves_change_the_extension(open31, kind):
    st = force_state(open31, MoveParams(), seed=5, force=0.05)
    z0 = st.extension
    seen = []
    for _ in range(5):
        _run_kind(st, kind, 20_000, 0.05)
        seen.append(st.extension)
    assert np.ptp(seen + [z0]) > 0.5  # Δz moves by bond lengths, not by round-off


def test_quench_under_force_stretches_the_chain(open31):
    # relax the embedding at fixed extension first (its arm corners alone would pull the
    # tails out when smoothed), then quench at T = 0 under a strong and a negligible force
    # (m_max = 75 as when these numbers were measured: the whole free chain can turn)
    rel = ChainState(open31, MoveParams(m_max=75, m_law="uniform"), seed=1, closed=False)
    for temperature in (1e-3, 1e-4, 0.0):
        rel.run(100_000, temperature)
    le0 = rel.excess_length
    out = {}
    for force in (0.5, 1e-4):
        st = force_state(rel.pos, MoveParams(m_max=75, m_law="uniform"), seed=6, force=force,
                         end_fraction=0.3)
        e0 = st.total_energy
        st.run(300_000, 0.0)
        assert st.total_energy <= e0 + 1e-12  # a quench never goes uphill in E_d − F·Δz
        _assert_clamped(st.pos)
        assert verify_knot(close_open_chain_along_z(st.pos), "3_1")[0]
        out[force] = st.excess_length
    # pulling hard extends the chain (L_e shrinks); a negligible force hardly moves it
    assert out[0.5] < le0 - 3
    assert out[0.5] < out[1e-4] - 3
    assert abs(out[1e-4] - le0) < 1


# ------------------------------------------------------------------------------------------
# 3. energy bookkeeping with the force term
# ------------------------------------------------------------------------------------------


@pytest.mark.parametrize("kind", ["pivot", "slide", "mixed"])
def test_energy_bookkeeping_with_force_term(open31, kind):
    force = 0.05
    st = force_state(open31, MoveParams(), seed=7, force=force, end_fraction=0.5)

    def total():
        return float(K.energy_chain(st.pos, True)) - force * float(st.pos[-1, 2] - st.pos[0, 2])

    before = total()
    returned = sum(_run_kind(st, kind, 10_000, 0.05) for _ in range(10))
    after = total()
    assert abs(returned - (after - before)) < 1e-9
    assert abs(st.total_energy - after) < 1e-9
    assert abs(st.energy - st.recomputed_energy()) < 1e-9
    accepted = st.end_counters[K.C_ACCEPTED:K.C_ACCEPTED + 2].sum() + st.slide_counters[
        K.C_ACCEPTED:K.C_ACCEPTED + 2].sum()
    assert accepted > 10_000
    assert abs(after - before) > 0.1  # the energy did change


# ------------------------------------------------------------------------------------------
# 4. no strand passage, exclusion kept (hot fuzzing)
# ------------------------------------------------------------------------------------------


@pytest.mark.parametrize("exclusion", ["bead", "tube"])
@pytest.mark.parametrize("knot", ["3_1", "4_1"])
def test_hot_fuzz_keeps_knot_and_exclusion(open31, open41, knot, exclusion):
    x = open31 if knot == "3_1" else open41
    st = force_state(x, MoveParams(exclusion=exclusion, m_max=30), seed=11, force=0.02,
                         end_fraction=0.5)
    for _ in range(6):
        st.run(50_000, 0.5)
        assert st.violation() <= 1e-12
        _assert_clamped(st.pos)
        ok, found = verify_knot(close_open_chain_along_z(st.pos), knot)
        assert ok, found
    assert _bond_error(st.pos) < 1e-10
    acc = st.acceptance()
    assert min(acc[k]["accepted"] for k in ("pivot_top", "pivot_bottom", "slide_top",
                                            "slide_bottom")) > 5000


# ------------------------------------------------------------------------------------------
# 5. detailed balance: exact averages on a 7-bead chain (3 free beads, tube model)
# ------------------------------------------------------------------------------------------

T_DB, F_DB, W_DB = 1.0, 0.5, 0.3


@njit(cache=True)
def _exact_averages(u, temperature, force, w):
    """Importance sampling of the fixed-force measure of a 7-bead open chain.

    Bead 1 at the origin, bonds 1→2 and 2→3 uniform on the sphere, z_5 uniform in [−4, 4],
    bead 4 uniform in angle on the circle at distance 1 from beads 3 and 5, whose measure is
    dψ/|r_5 − r_3| (∫d³r δ(|r − a| − 1) δ(|r − b| − 1) = 2π/|a − b|). Weight e^{−E/T}, tube
    rule and slab as indicators; ``u`` holds 6 uniforms per sample. Returns Σw and
    Σw·(Δz, E_d, h_top, h_bottom)."""
    out = np.zeros(5)
    p = np.zeros((7, 3))
    for i in range(u.shape[0]):
        p[:] = 0.0
        p[0, 2] = -1.0
        for b in (2, 3):
            zz = 2.0 * u[i, 2 * b - 4] - 1.0
            a = 2.0 * np.pi * u[i, 2 * b - 3]
            r = np.sqrt(1.0 - zz * zz)
            p[b, 0] = p[b - 1, 0] + r * np.cos(a)
            p[b, 1] = p[b - 1, 1] + r * np.sin(a)
            p[b, 2] = p[b - 1, 2] + zz
        z5 = -4.0 + 8.0 * u[i, 4]
        p[5, 2] = z5
        p[6, 2] = z5 + 1.0
        dx, dy, dz = -p[3, 0], -p[3, 1], z5 - p[3, 2]
        dd = np.sqrt(dx * dx + dy * dy + dz * dz)
        if dd >= 2.0 or dd == 0.0:
            continue
        ex, ey, ez = dx / dd, dy / dd, dz / dd
        if abs(ex) < 0.9:
            ax, ay, az = 1.0, 0.0, 0.0
        else:
            ax, ay, az = 0.0, 1.0, 0.0
        t = ax * ex + ay * ey + az * ez
        ax, ay, az = ax - t * ex, ay - t * ey, az - t * ez
        nn = np.sqrt(ax * ax + ay * ay + az * az)
        ax, ay, az = ax / nn, ay / nn, az / nn
        bx, by, bz = ey * az - ez * ay, ez * ax - ex * az, ex * ay - ey * ax
        rc = np.sqrt(1.0 - dd * dd / 4.0)
        psi = 2.0 * np.pi * u[i, 5]
        cs, sn = np.cos(psi), np.sin(psi)
        p[4, 0] = p[3, 0] + dx / 2 + rc * (cs * ax + sn * bx)
        p[4, 1] = p[3, 1] + dy / 2 + rc * (cs * ay + sn * by)
        p[4, 2] = p[3, 2] + dz / 2 + rc * (cs * az + sn * bz)
        ok = True
        for b in range(1, 6):
            if not p[0, 2] < p[b, 2] < p[6, 2]:
                ok = False
        for a in range(6):
            for b in range(a + 2, 6):
                if seg_dist2(p[a, 0], p[a, 1], p[a, 2], p[a + 1, 0], p[a + 1, 1], p[a + 1, 2],
                             p[b, 0], p[b, 1], p[b, 2], p[b + 1, 0], p[b + 1, 1],
                             p[b + 1, 2]) < w * w:
                    ok = False
        if not ok:
            continue
        e = 0.0
        for v in range(1, 6):
            e += 1.0 - ((p[v, 0] - p[v - 1, 0]) * (p[v + 1, 0] - p[v, 0])
                        + (p[v, 1] - p[v - 1, 1]) * (p[v + 1, 1] - p[v, 1])
                        + (p[v, 2] - p[v - 1, 2]) * (p[v + 1, 2] - p[v, 2]))
        dzz = p[6, 2] - p[0, 2]
        wt = np.exp(-(e - force * dzz) / temperature) / dd
        out[0] += wt
        out[1] += wt * dzz
        out[2] += wt * e
        out[3] += wt * (p[5, 2] - p[4, 2])
        out[4] += wt * (p[2, 2] - p[1, 2])
    return out


@njit(cache=True)
def _mc_samples(pos, n_samples, temperature, force, slide, ipar, fpar, head, nxt, prv,
                bucket, newpos, cnt, rng):
    """Crankshafts alternated with pivot (``slide`` False) or slide end moves; after every
    20 moves record (Δz, E_d, h_top, h_bottom)."""
    out = np.empty((n_samples, 4))
    for s in range(n_samples):
        K.run_moves(pos, 10, temperature, ipar, fpar, head, nxt, prv, bucket, newpos, cnt, rng)
        if slide:
            run_slide_moves(pos, 10, temperature, force, 2, ipar, fpar, head, nxt, prv, bucket,
                            newpos, cnt, rng)
        else:
            run_end_moves(pos, 10, temperature, force, 3, ipar, fpar, head, nxt, prv, bucket,
                          newpos, cnt, rng)
        out[s, 0] = pos[6, 2] - pos[0, 2]
        out[s, 1] = K.energy_chain(pos, True)
        out[s, 2] = pos[5, 2] - pos[4, 2]
        out[s, 3] = pos[2, 2] - pos[1, 2]
    return out


@pytest.fixture(scope="module")
def exact7():
    rng = np.random.default_rng(2024)
    sums = sum(_exact_averages(rng.random((1_000_000, 6)), T_DB, F_DB, W_DB) for _ in range(4))
    return sums[1:] / sums[0]


@pytest.mark.parametrize("slide", [False, True])
def test_detailed_balance_on_a_seven_bead_chain(exact7, slide):
    # The fixed-force measure includes the Jacobian of the re-attachment (h/h' for the pivot
    # move, D/D' for the slide): without it the chain runs stiffer, h_top ≈ 0.78 instead of
    # 0.62 and Δz ≈ 4.92 instead of 4.52 (measured), far outside the tolerances below (≈ 5σ).
    s, c = np.sin(np.pi / 3), np.cos(np.pi / 3)
    pos = np.array([[0, 0, 0], [0, 0, 1], [s, 0, 1 + c], [0, 0, 1 + 2 * c], [s, 0, 1 + 3 * c],
                    [0, 0, 1 + 4 * c], [0, 0, 2 + 4 * c]], dtype=float)
    p = MoveParams(exclusion="tube", w=W_DB, m_max=3)
    ipar, fpar = p.arrays()
    ipar[K.I_OPEN] = 1
    fpar[K.F_ZLO], fpar[K.F_ZHI] = pos[0, 2], pos[-1, 2]
    head = np.empty(1024, dtype=np.int64)
    nxt, prv, bucket = (np.empty(7, dtype=np.int64) for _ in range(3))
    K.cell_build(pos, p.cell, head, nxt, prv, bucket, True)
    cnt = np.zeros(K.C_NCNT, dtype=np.int64)
    out = _mc_samples(pos, 400_000, T_DB, F_DB, slide, ipar, fpar, head, nxt, prv, bucket,
                      np.empty((8, 3)), cnt, K.new_rng_state(21 + slide))[2000:]
    mc = out.mean(axis=0)
    tol = np.array([0.05, 0.06, 0.02, 0.02])  # Δz, E_d, h_top, h_bottom
    assert np.all(np.abs(mc - exact7) < tol), (mc, exact7)
    assert K.check_state(pos, 1, 0.0, W_DB, True) <= 1e-12


# ------------------------------------------------------------------------------------------
# 6. physics: force balance μ = E_d/L_e = F after annealing (slow)
# ------------------------------------------------------------------------------------------


@pytest.mark.slow
def test_annealed_open_trefoil_balances_the_force():
    # Thin-ish tube (w = 0.1), where ε_e(L_e) is nearly constant (README: 21.05, 20.86 at
    # L_e = 40, 60), so −dE_d/dL_e = E_d/L_e and equilibrium at T → 0 means μ = E_d/L_e = F
    # (the thin limit: μ* = 2π²C/L_e², L_e = π(2/F)^½ ≈ 39). Under the paper's bead rule
    # ε_e(L_e) still falls with L_e (23.55 → 22.61 from L_e = 40 to 80, README), so there
    # −dE_d/dL_e > E_d/L_e and the balance is μ/F < 1: not a test of the moves.
    # Measured (seed 0, 60 M moves, ≈ 2 min): L_e = 40.16, ε_e = 21.03, μ/F = 1.003.
    from stiffknots.problems.open_force import anneal_open_force

    force = 0.013
    r = anneal_open_force("3_1", force, moves=60_000_000, replicas=1, seed=0, workers=1,
                          params=MoveParams(exclusion="tube", w=0.1, m_max=60))
    assert r.best.knot_verified
    assert r.eps_e < 22.0  # the loop (2π² = 19.74 in the thin limit), not a jammed state
    assert r.tension == pytest.approx(force, rel=0.10)  # E_d/L_e = F at equilibrium


# ------------------------------------------------------------------------------------------
# driver and CLI
# ------------------------------------------------------------------------------------------


def test_anneal_open_force_small_run_is_verified():
    from stiffknots.problems.open_force import anneal_open_force

    r = anneal_open_force("3_1", 0.05, n_beads=80, moves=200_000, replicas=1, seed=1,
                          workers=1)
    d = r.to_dict()
    assert d["knot"] == "3_1" and d["knot_verified"] and d["ensemble"] == "force"
    assert d["force"] == 0.05 and r.beads == 80
    le = (80 - 1) - r.best.extension
    assert d["excess_length"] == pytest.approx(le)
    assert d["tension"] == pytest.approx(d["energy"] / le)
    assert d["eps_e"] == pytest.approx(d["energy"] * le)
    assert d["total_energy"] == pytest.approx(d["energy"] - 0.05 * r.best.extension)
    assert d["settings"]["force"] == 0.05 and d["version"]
    with pytest.raises(ValueError, match="force"):
        anneal_open_force("3_1", 0.0, moves=1000)


def test_cli_open_force_json(capsys, tmp_path):
    from stiffknots.cli import app

    app(["open", "3_1", "--ensemble", "force", "--force", "0.05", "--beads", "80", "--moves",
         "200000", "--replicas", "1", "--json", "--out", str(tmp_path)], standalone_mode=False)
    d = json.loads(capsys.readouterr().out)
    # pictures: the chain as a tube and μ against 1/L_e² with the bounds
    assert (tmp_path / "F_0.05" / "best.png").stat().st_size > 10_000
    assert (tmp_path / "tension.png").stat().st_size > 10_000
    for key in ("knot", "force", "tension", "excess_length", "eps_e", "shape", "points"):
        assert key in d
    assert d["knot"] == "3_1" and d["force"] == 0.05 and d["ensemble"] == "force"
    assert d["tension"] == pytest.approx(d["eps_e"] / d["excess_length"] ** 2)


@pytest.mark.parametrize("args", [
    ("open", "3_1", "--ensemble", "force", "--force=-0.1"),
    ("open", "3_1", "--ensemble", "force", "--force", "0"),
    ("open", "3_1", "--ensemble", "force"),
    ("open", "3_1", "--ensemble", "isotension", "--force", "0.1"),
    ("open", "3_1", "--beads", "100"),
])
def test_cli_open_force_mistakes_exit_2_one_line(args):
    # the console-script entry point (``python -m stiffknots.cli`` does not see the commands
    # that cli_open registers on stiffknots.cli.app)
    p = subprocess.run([sys.executable, "-c", "from stiffknots.cli import main; main()", *args],
                       capture_output=True, text=True, timeout=120)
    assert p.returncode == 2
    assert "Traceback" not in p.stderr
    lines = [ln for ln in p.stderr.splitlines() if ln.strip()]
    assert len(lines) == 1 and lines[0].startswith("error:")
