"""Guarded Langevin dynamics: a collective search for the bead rule's closed chains (§VII).

The crankshaft Monte Carlo of :mod:`stiffknots.engine.kernel` moves a few beads at a time.
Some minima of the bead rule are reached far more easily by moving every bead at once: the
4_1's lowest states (two strands crossing close together) are found by the peer's Langevin
dynamics (LAMMPS, ``fix langevin``) far sooner than by the crankshafts
(docs/methods/search.md). :func:`run_langevin` runs that
dynamics in a compiled kernel (:func:`stiffknots.engine.langevin_kernel.run_dynamics`: the
peer's model — stiff harmonic bonds, the bending energy E_d, a WCA wall at the contact
distance — its schedule, T falling exponentially from ``t_start`` to ``t_end``, and a
passage guard that is proved in that module's docstring), settles it (blocks of 2,000 steps
at ``t_end`` with friction γ = 1, until the chain below is admissible), then takes the chain
back onto the exact model: every bond to unit length by min-norm Gauss–Newton corrections, a
straight-line motion certified by the passage guard that the final minimiser uses too
(:func:`stiffknots.engine.guard.passage_guard`), and the bead rule checked. The result is an
admissible chain of the same knot type for the final minimiser
(:func:`stiffknots.engine.polish.polish`), which the problems apply after every replica.

As a schedule (``Schedule(kind="langevin")``, ``stiffknots anneal K --schedule langevin``) a
replica is one such run from its start; ``settings.moves`` then counts dynamics *steps* (each
moves all N beads), and the temperatures are the schedule's ``t_start`` and ``t_end``.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable
from dataclasses import asdict, dataclass

import numpy as np
import scipy.sparse as sp
from scipy.sparse.linalg import spsolve

from stiffknots.engine.guard import passage_guard
from stiffknots.engine.langevin_kernel import run_dynamics
from stiffknots.engine.prims import check_state, energy_chain, new_rng_state
from stiffknots.errors import ChainGeometryError, InvalidParameter
from stiffknots.width import BEAD_D

#: default dynamics steps of a replica (N = 150: 1 M steps take ≈ 6 s on one core)
DEFAULT_STEPS = 1_000_000
#: the schedule's end temperature for the dynamics (the peer's protocol ends at 1e-4)
DEFAULT_T_END = 1e-4
#: steps of one settling block at the end (T = t_end, friction γ = 1: kinetic energy × e⁻¹⁰)
QUENCH_STEPS = 2_000
MAX_SETTLE_STEPS = 40_000


@dataclass(frozen=True)
class LangevinSettings:
    """The dynamics of :func:`run_langevin` (units: bond 1, C = 1, k_B = 1, mass 1).

    The defaults are the peer benchmark's LAMMPS protocol (bench/peer_lammps.py): damp 100
    (friction γ = 1/damp), dt 0.005, bonds K_b = 1000, WCA contact at 0.72 (≥ the bead rule's
    1/√2, so that the chain ends admissible), T from 0.1 to 10⁻⁴ over ``steps`` steps.
    ``skin`` is the Verlet list's; ``cap`` the distance below which the passage guard is
    exact (larger: fewer guard checks, each dearer).
    """

    steps: int = DEFAULT_STEPS
    dt: float = 0.005
    damp: float = 100.0
    t_start: float = 0.1
    t_end: float = DEFAULT_T_END
    k_bond: float = 1000.0
    contact: float = 0.72
    skin: float = 0.3
    cap: float = 0.5
    chunks: int = 20

    def validate(self, d: float = BEAD_D) -> None:
        if not (isinstance(self.steps, int | np.integer) and self.steps >= 1):
            raise InvalidParameter("steps", self.steps, "an integer ≥ 1")
        for name in ("dt", "damp", "t_start", "t_end", "k_bond", "contact", "skin", "cap"):
            v = getattr(self, name)
            if not (isinstance(v, int | float) and math.isfinite(v) and v > 0):
                raise InvalidParameter(name, v, "a finite number > 0")
        if not self.t_end < self.t_start:
            raise InvalidParameter("t_end", self.t_end, f"below t_start = {self.t_start:g}")
        if self.dt > 0.02:
            raise InvalidParameter("dt", self.dt, "≤ 0.02 (the bonds' period is ≈ 0.14)")
        if self.contact < d:
            raise InvalidParameter("contact", self.contact,
                                   f"≥ the bead diameter d = {d:.6g}: the wall must keep the "
                                   "beads admissible")
        if not (isinstance(self.chunks, int) and self.chunks >= 1):
            raise InvalidParameter("chunks", self.chunks, "an integer ≥ 1")

    def as_dict(self) -> dict:
        return asdict(self)


@dataclass
class LangevinResult:
    """What :func:`run_langevin` did. ``pos``: the admissible unit-bond chain it ends on;
    ``refused_steps``: bead-steps the passage guard held back (a bead kept in place for one
    step, its velocity reversed), summed over the beads, dynamics and settling."""

    pos: np.ndarray
    epsilon: float
    epsilon_dynamics: float
    max_bond_error_dynamics: float
    settling_steps: int
    projection_shift: float
    refused_steps: int
    guard_checks: int
    list_builds: int
    lowest_guard_distance: float
    wall_time: float
    cpu_time: float
    trace_steps: np.ndarray
    trace_temperature: np.ndarray
    trace_epsilon: np.ndarray
    trace_seconds: np.ndarray


def unit_epsilon(pos: np.ndarray) -> float:
    """ε = N·Σ(1 − û_n·û_{n+1}) of a closed chain, bond directions û (any bond lengths)."""
    b = np.roll(pos, -1, axis=0) - pos
    u = b / np.linalg.norm(b, axis=1)[:, None]
    return float(len(pos) * np.sum(1.0 - np.sum(u * np.roll(u, -1, axis=0), axis=1)))


def project_bonds(pos: np.ndarray, tol: float = 1e-14, max_iter: int = 20) -> np.ndarray:
    """The closed chain moved to unit bonds by min-norm Gauss–Newton corrections.

    Each iteration solves ``min |Δx|²`` subject to the linearised bonds,
    ``2 b_n·(Δr_{n+1} − Δr_n) = 1 − |b_n|²``, i.e. Δx = Aᵀ(AAᵀ)⁻¹r (A sparse, AAᵀ cyclic
    tridiagonal); quadratic convergence from bonds within a few 10⁻³ of 1.
    """
    x = np.array(pos, dtype=float)
    n = len(x)
    idx = np.arange(n)
    nxt = (idx + 1) % n
    rows = np.repeat(idx, 6)
    cols = np.concatenate([3 * nxt[:, None] + np.arange(3), 3 * idx[:, None] + np.arange(3)],
                          axis=1).ravel()
    for _ in range(max_iter):
        b = x[nxt] - x
        r = 1.0 - np.sum(b * b, axis=1)
        if np.max(np.abs(r)) < tol:
            return x
        vals = np.concatenate([2 * b, -2 * b], axis=1).ravel()
        a = sp.csr_matrix((vals, (rows, cols)), shape=(n, 3 * n))
        y = spsolve((a @ a.T).tocsc(), r)
        x += (a.T @ y).reshape(n, 3)
    b = x[nxt] - x
    if np.max(np.abs(np.sum(b * b, axis=1) - 1.0)) > 1e-10:
        raise ChainGeometryError("the bonds did not converge to unit length after the "
                                 "dynamics (bonds too far from 1: lower dt or raise k_bond)")
    return x


def _check_start(coords: np.ndarray, d: float) -> np.ndarray:
    x = np.asarray(coords, dtype=float)
    if x.ndim != 2 or x.shape[1] != 3 or x.shape[0] < 6:
        raise InvalidParameter("coords", f"array of shape {x.shape}",
                               "a closed chain of shape (N, 3), N ≥ 6")
    if not np.all(np.isfinite(x)):
        raise InvalidParameter("coords", "non-finite values", "finite coordinates")
    bonds = np.linalg.norm(np.roll(x, -1, axis=0) - x, axis=1)
    if np.max(np.abs(bonds - 1.0)) > 1e-8:
        raise InvalidParameter("coords", f"bonds {bonds.min():.6g}–{bonds.max():.6g}",
                               "unit bonds (to 1e-8)")
    if check_state(x, 0, d, d, False) > 1e-10:
        raise InvalidParameter("coords", "beads closer than the bead diameter d",
                               f"a chain that obeys the bead rule (d = {d:.6g})")
    return x


def run_langevin(coords: np.ndarray, settings: LangevinSettings | None = None, seed: int = 0,
                 *, d: float = BEAD_D,
                 progress: Callable[[dict], None] | None = None) -> LangevinResult:
    """Anneal a closed bead-rule chain by guarded Langevin dynamics and return it admissible.

    Parameters
    ----------
    coords : ndarray
        (N, 3) closed chain with unit bonds that obeys the bead rule with diameter ``d``.
    settings : LangevinSettings or None
        The dynamics (:class:`LangevinSettings`; default the peer's protocol).
    seed : int
        Seed of the noise (xoshiro256+) and of the initial velocities (Maxwell at
        ``t_start``).
    d : float
        The bead rule's diameter (§VII: 1/√2); the result obeys it.
    progress : callable or None
        Called after every chunk with ``{"done", "total", "epsilon", "temperature"}``
        (steps done and planned).

    Returns
    -------
    LangevinResult
        ``pos`` has unit bonds (to 10⁻¹³) and obeys the bead rule; every step of the dynamics
        and the final projection were certified free of strand passage, so its knot type is
        the start's.

    Raises
    ------
    InvalidParameter
        A bad chain or setting (what was wrong, what is allowed).
    ChainGeometryError
        The final chain could not be made admissible (never seen at the defaults).
    """
    s = settings or LangevinSettings()
    s.validate(d)
    x = _check_start(coords, d).copy()
    n = len(x)
    t0, c0 = time.perf_counter(), time.process_time()
    rng = new_rng_state(seed)
    vel = np.random.default_rng(seed).normal(0.0, math.sqrt(s.t_start), size=x.shape)
    vel -= vel.mean(axis=0)
    stats = np.zeros(5)
    refused = checks = builds = 0
    lowest = math.inf
    per = [s.steps // s.chunks + (1 if c < s.steps % s.chunks else 0) for c in range(s.chunks)]
    per = [p for p in per if p > 0]
    ratio = s.t_end / s.t_start
    done = 0
    tr_steps, tr_temp, tr_eps, tr_sec = [], [], [], []
    for p in per:
        ta = s.t_start * ratio ** (done / s.steps)
        tb = s.t_start * ratio ** ((done + p) / s.steps)
        run_dynamics(x, vel, p, s.dt, 1.0 / s.damp, ta, tb, s.k_bond, s.contact, s.skin,
                     s.cap, rng, stats)
        if stats[3] < 0:
            raise ChainGeometryError("the dynamics' pair list overflowed (more than 64 beads "
                                     "within reach of one bead): the chain is crushed")
        refused += int(stats[1])
        checks += int(stats[2])
        builds += int(stats[3])
        lowest = min(lowest, float(stats[4]))
        done += p
        eps = unit_epsilon(x)
        tr_steps.append(done)
        tr_temp.append(tb)
        tr_eps.append(eps)
        tr_sec.append(time.perf_counter() - t0)
        if progress is not None:
            progress({"done": done, "total": s.steps, "epsilon": eps, "temperature": tb})
    eps_md = tr_eps[-1]  # the chain as the dynamics left it
    # the settling: blocks of QUENCH_STEPS at t_end with strong friction (γ = 1) until the
    # chain projects onto unit bonds without passage and obeys the bead rule (a short or hot
    # run can end with beads pressed inside the wall); the same guarded kernel
    settle = 0
    while True:
        run_dynamics(x, vel, QUENCH_STEPS, s.dt, 1.0, s.t_end, s.t_end, s.k_bond, s.contact,
                     s.skin, s.cap, rng, stats)
        if stats[3] < 0:
            raise ChainGeometryError("the dynamics' pair list overflowed while settling")
        refused += int(stats[1])
        checks += int(stats[2])
        lowest = min(lowest, float(stats[4]))
        settle += QUENCH_STEPS
        bond_err = float(np.max(np.abs(np.linalg.norm(np.roll(x, -1, axis=0) - x, axis=1)
                                       - 1)))
        xp = None
        if bond_err < 0.05:
            try:
                xp = project_bonds(x)
            except ChainGeometryError:  # not converged: settle on
                xp = None
        if (xp is not None and passage_guard(x, xp)
                and check_state(xp, 0, d, d, False) <= 0.0):
            break
        if settle >= MAX_SETTLE_STEPS:
            raise ChainGeometryError(
                f"after the dynamics and {settle:,} settling steps the chain is not admissible "
                f"(beads closer than d = {d:.6g}, or bonds {bond_err:.3g} from unit length): "
                f"raise contact (now {s.contact:g}) or lower t_end (now {s.t_end:g})")
    return LangevinResult(
        pos=xp, epsilon=float(energy_chain(xp, False)) * n, epsilon_dynamics=eps_md,
        max_bond_error_dynamics=bond_err, settling_steps=settle,
        projection_shift=float(np.max(np.linalg.norm(xp - x, axis=1))),
        refused_steps=refused, guard_checks=checks, list_builds=builds,
        lowest_guard_distance=lowest, wall_time=time.perf_counter() - t0,
        cpu_time=time.process_time() - c0, trace_steps=np.asarray(tr_steps, dtype=np.int64),
        trace_temperature=np.asarray(tr_temp), trace_epsilon=np.asarray(tr_eps),
        trace_seconds=np.asarray(tr_sec))


def settings_from(settings) -> LangevinSettings:
    """The dynamics of a ``Schedule(kind="langevin")`` replica: ``settings.moves`` steps,
    the schedule's ``t_start`` and ``t_end``, the rest at :class:`LangevinSettings`'s
    defaults."""
    sch = settings.schedule
    return LangevinSettings(steps=int(settings.moves), t_start=float(sch.t_start),
                            t_end=float(sch.t_end))


def run_langevin_replica(coords: np.ndarray, settings, seed: int, replica: int = 0, *,
                         checkpoint=None, resume: bool = False, checkpoint_every=None,
                         checkpoint_seconds=None,
                         progress: Callable[[dict], None] | None = None):
    """One replica of a ``langevin`` schedule (:func:`run_langevin` from ``coords``), packed
    and verified like an annealing replica (:func:`stiffknots.engine.driver.make_result`:
    bookkeeping, unit bonds, the bead rule). The problems then polish it and check its knot
    type. Closed chains under the bead rule and the bending energy only; no checkpoints (a
    replica takes seconds)."""
    from stiffknots.engine.driver import Clock, make_result
    from stiffknots.engine.state import ChainState

    if checkpoint is not None:
        raise InvalidParameter("checkpoint", str(checkpoint),
                               "none with the langevin schedule (a replica takes seconds)")
    p = settings.params
    if not settings.closed or p.exclusion != "bead" or p.energy != "bending":
        raise InvalidParameter(
            "schedule", "langevin",
            "the Monte Carlo schedules here: the langevin schedule runs closed chains under "
            f"the bead rule with the bending energy (got {settings.ensemble.kind}, "
            f"{p.exclusion}, {p.energy})")
    clock = Clock()
    ls = settings_from(settings)

    def report(rec: dict) -> None:
        if progress is not None:
            progress({"replica": replica, "done": rec["done"], "total": rec["total"],
                      "epsilon": rec["epsilon"], "best": rec["epsilon"]})

    res = run_langevin(coords, ls, seed, d=p.d, progress=report)
    state = ChainState(res.pos, p, seed=0, ensemble=settings.ensemble)
    acc = {"single": {"tried": 0, "accepted": 0, "rate": 0.0},
           "multi": {"tried": 0, "accepted": 0, "rate": 0.0},
           "steps": {"tried": ls.steps, "frozen_bead_steps": res.refused_steps}}
    traces = {"moves": list(res.trace_steps), "temperature": list(res.trace_temperature),
              "epsilon": list(res.trace_epsilon),
              "seconds": list(res.trace_seconds)}  # wall seconds at the end of each chunk
    return make_result(replica, seed, settings, state, acc, traces, clock, (None, None),
                       stage_epsilon={"langevin": res.epsilon}, best_stage="langevin",
                       langevin={"epsilon_dynamics": res.epsilon_dynamics,
                                 "max_bond_error_dynamics": res.max_bond_error_dynamics,
                                 "settling_steps": res.settling_steps,
                                 "projection_shift": res.projection_shift,
                                 "refused_steps": res.refused_steps,
                                 "guard_checks": res.guard_checks,
                                 "lowest_guard_distance": res.lowest_guard_distance})
