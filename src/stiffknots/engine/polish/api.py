"""The final minimiser's public entry point: :func:`polish` and :class:`PolishResult`.

:func:`polish` validates the chain and its settings, builds the problem
(:mod:`stiffknots.engine.polish.problem`), takes the input exactly onto its constraints and
runs the SQP (:mod:`stiffknots.engine.polish.sqp`) under the passage guard
(:mod:`stiffknots.engine.guard`), with one BLAS thread.
"""

from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np
from threadpoolctl import threadpool_limits

from stiffknots.engine.polish.pieces import _min_clearance
from stiffknots.engine.polish.problem import EXCLUSIONS, _Problem
from stiffknots.engine.polish.sqp import ACTIVE_TOL, _Polisher
from stiffknots.width import BEAD_D

BOND_TOL_IN = 1e-8  # input bonds must be unit to this (the output is unit to ~1e-14)


@dataclass(frozen=True)
class PolishResult:
    """Outcome of :func:`polish`.

    Attributes
    ----------
    pos : ndarray
        (N, 3) the polished chain (a new array; the input is untouched).
    energy_before, energy : float
        E_d = Σ (1 − u_n·u_{n+1}) of the input and of ``pos`` (paper §VII;
        ε = E_d·N for a closed chain).
    kkt_residual : float
        Min over bond tensions λ and contact forces μ ≥ 0 of ‖∇E − Aᵀ(λ, μ)‖₂ at
        ``pos`` (free beads only; A: Jacobian of the bonds and of the contacts within 10⁻⁸ of
        their limit). Zero at a KKT point; see :mod:`stiffknots.engine.polish.sqp`.
    grad_norm : float
        ‖∇E‖₂ over the free beads (the scale of ``kkt_residual``).
    iterations : int
        Accepted SQP steps.
    converged : bool
        kkt_residual ≤ tol·grad_norm, or no step can lower E by more than its
        floating-point resolution and kkt_residual ≤ 10⁻⁶·grad_norm.
    reason : str
        Why the iteration stopped.
    n_active : int
        Exclusion constraints within 10⁻⁸ of their limit at the end (bead pairs; in
        the tube model vertex–vertex, vertex–segment and segment–segment contact pieces).
    max_bond_error : float
        ``max_k | |r_{k+1} − r_k| − 1 |``.
    exclusion_margin : float
        Min over the exclusion constraints of (distance − limit) (≥ 0; capped
        at 1; +inf for ``exclusion="none"``).
    strand_gap : float
        Min distance between segments that share no bead (capped at 1).
    gap_force : float
        Σ of the multipliers of the strand-gap pieces (the force pressing strands
        through each other, C per bond length); the energy exceeds the touching limit
        (min_gap → 0) by ≈ gap_force·min_gap. Zero when no gap piece is active.
    seconds : float
        Wall time.
    """

    pos: np.ndarray
    energy_before: float
    energy: float
    kkt_residual: float
    grad_norm: float
    iterations: int
    converged: bool
    reason: str
    n_active: int
    max_bond_error: float
    exclusion_margin: float
    strand_gap: float
    gap_force: float
    seconds: float

    @property
    def relative_kkt(self) -> float:
        """kkt_residual / grad_norm."""
        return self.kkt_residual / self.grad_norm if self.grad_norm > 0 else 0.0


def _validate(pos, closed, exclusion, d, w, clamp_ends, max_iter, tol, max_step):
    x = np.array(pos, dtype=np.float64, order="C", copy=True)
    if x.ndim != 2 or x.shape[1] != 3:
        raise ValueError(f"pos must have shape (N, 3), got {x.shape}")
    n = x.shape[0]
    if n < 8:
        raise ValueError(f"a chain needs at least 8 beads, got {n}")
    if not np.all(np.isfinite(x)):
        raise ValueError("pos contains NaN or infinite coordinates")
    if exclusion not in EXCLUSIONS:
        raise ValueError(f"unknown exclusion {exclusion!r}; allowed: {', '.join(EXCLUSIONS)}")
    if not 0 < d < 1 or not 0 < w < 1:
        raise ValueError(f"d and w must lie in (0, 1) bond lengths, got d={d}, w={w}")
    if int(max_iter) != max_iter or max_iter < 0:
        raise ValueError(f"max_iter must be an integer ≥ 0, got {max_iter}")
    if not tol > 0:
        raise ValueError(f"tol must be > 0, got {tol}")
    if not 0 < max_step <= 1:
        raise ValueError(f"max_step must be in (0, 1], got {max_step}")
    bonds = np.linalg.norm((np.roll(x, -1, axis=0) - x) if closed else np.diff(x, axis=0),
                           axis=1)
    err = float(np.max(np.abs(bonds - 1.0)))
    if err > BOND_TOL_IN:
        raise ValueError(f"bonds must have unit length to {BOND_TOL_IN:g} (worst {err:.2e})")
    nfix = 0
    if closed:
        if clamp_ends not in (None, 0):
            raise ValueError("clamp_ends applies to open chains only (closed=False)")
    else:
        nfix = 2 if clamp_ends is None else int(clamp_ends)
        if nfix != clamp_ends and clamp_ends is not None:
            raise ValueError(f"clamp_ends must be an integer, got {clamp_ends}")
        if nfix < 2 or n - 2 * nfix < 2:
            raise ValueError(f"clamp_ends must be ≥ 2 and leave ≥ 2 free beads, got {nfix} "
                             f"for N = {n}")
        ends = x[[0, 1, -2, -1]]
        if np.max(np.abs(ends[:, :2])) > 1e-9:
            raise ValueError("an open chain needs beads 0, 1, N−2, N−1 on the z axis")
        if ends[1, 2] <= ends[0, 2] or ends[3, 2] <= ends[2, 2]:
            raise ValueError("an open chain's end segments must point along −z (first) and "
                             "+z (last)")
        inner = x[1:-1, 2]
        if np.any(inner <= x[0, 2]) or np.any(inner >= x[-1, 2]):
            raise ValueError("every bead but the end beads must lie strictly between z_0 and "
                             "z_{N−1} (the closure rays run along z beyond the ends)")
    return x, nfix


def polish(
    pos,
    *,
    closed: bool = True,
    exclusion: str = "bead",
    d: float = BEAD_D,
    w: float = BEAD_D,
    clamp_ends: int | None = None,
    max_iter: int = 200,
    tol: float = 1e-10,
    max_step: float = 0.25,
    guard: bool | None = None,
    min_gap: float = 1e-4,
    guard_depth: int = 20,
) -> PolishResult:
    """Minimise the bending energy E_d of a unit-bond chain under its exclusion rule exactly.

    Finds the local minimum of E_d = Σ_joints (1 − u_n·u_{n+1}) (paper §VII) reached by a
    descent path from the input, with unit bonds and the exclusion rule held at every accepted
    iterate and no strand passage along the way (see :mod:`stiffknots.engine.polish.sqp` for
    the method and the KKT residual, :mod:`stiffknots.engine.guard` for the proof).

    Parameters
    ----------
    pos
        (N, 3) chain with unit bonds (to 10⁻⁸) that satisfies its exclusion rule (to
        10⁻¹⁰).
    closed : bool
        Closed ring (N bonds, N joints) or open chain (N − 1 bonds, N − 2 joints) with
        clamped ends (the fixed-extension ensemble of §VIII: beads 0, 1 and N−2, N−1 on the z
        axis, end segments along −z and +z, every other bead strictly between z_0 and
        z_{N−1}; the excess length L_e does not change).
    exclusion : ``"bead"`` (beads at index distance ≥ 2 at least ``d`` apart, §VII),
        ``"tube"`` (segments sharing no bead at least ``w`` apart, §II) or ``"none"``.
    d, w : float
        Exclusion distances (bond lengths).
    clamp_ends : int or None
        Open chains: beads held fixed at each end (default 2, the end segments).
    max_iter : int
        Largest number of accepted steps.
    tol : float
        Converged when the KKT residual is ≤ tol·‖∇E‖₂ (or, once no decrease of E is
        resolvable in floating point, ≤ 10⁻⁶·‖∇E‖₂; see :mod:`stiffknots.engine.polish.sqp`).
    max_step : float
        Largest displacement of any bead in one step (bond lengths).
    guard : bool or None
        Strand-passage guard (default: on for ``bead`` and ``tube``, off for ``none``).
    min_gap : float
        With the guard on and a rule that does not keep strands apart by itself
        (``bead``, ``none``), segments that share no bead are also kept ≥ ``min_gap`` apart.
        The bead rule with d = 1/√2 lets two segments touch (crossing at right angles at their
        midpoints, all four beads exactly d apart) and tight bead-model knots press into that
        singular configuration; the gap keeps the chain embedded and the problem well posed
        (nearly flat four-bead contacts make it degenerate as the gap goes to zero). The
        energy then lies above that of the touching limit by ≈ ``gap_force``·min_gap (first
        order; ≈ 3e-6 relative on the worst fixture at the default). If the input's strands
        are closer, half their distance is used instead.
    guard_depth : int
        Bisection levels the guard may use to certify a close pair (the guard
        rejects what it cannot certify).

    Returns
    -------
    PolishResult
        ``energy ≤ energy_before`` always: if no step lowers the energy the input comes back.

    Raises
    ------
    ValueError
        For a malformed chain (shape, non-unit bonds, exclusion violated by more than 10⁻¹⁰,
        bad open-chain clamping) or bad parameters.
    """
    t0 = time.perf_counter()
    x, nfix = _validate(pos, closed, exclusion, d, w, clamp_ends, max_iter, tol, max_step)
    if not 0 <= min_gap < 0.1:
        raise ValueError(f"min_gap must be in [0, 0.1), got {min_gap}")
    if int(guard_depth) != guard_depth or not 0 <= guard_depth <= 40:
        raise ValueError(f"guard_depth must be an integer in [0, 40], got {guard_depth}")
    n = x.shape[0]
    mode = EXCLUSIONS.index(exclusion)
    limit = d if mode == 0 else (w if mode == 1 else 0.0)
    guard = mode != 2 if guard is None else bool(guard)
    zrot = (not closed) and bool(np.max(np.abs(x[:nfix, :2])) <= 1e-12
                                 and np.max(np.abs(x[n - nfix:, :2])) <= 1e-12)
    zlo, zhi = (float(x[0, 2]), float(x[-1, 2])) if not closed else (0.0, 0.0)
    gap = 0.0
    if guard and mode != 1 and min_gap > 0:
        gap0 = float(_min_clearance(x, 1, 0.0, not closed))
        gap = min(float(min_gap), 0.5 * gap0)
    prob = _Problem(n, bool(closed), mode, limit, nfix, zrot, gap)
    pol = _Polisher(prob, float(max_step), guard, zlo, zhi, int(guard_depth))
    clear0 = pol.clearance(x)
    if clear0 < -1e-10:
        raise ValueError(f"the chain violates the {exclusion} exclusion rule by {-clear0:.3g}")
    e0 = pol.energy(x)
    # one BLAS thread: the dense matrices are small (the Cholesky of ≤ DENSE_GRAM_ROWS rows,
    # the working set's Schur complement), and replicas run on every core (the pool, Dask
    # workers), where OpenBLAS's threads oversubscribed them (docs/methods/minimiser.md)
    with threadpool_limits(limits=1, user_api="blas"):
        # exact admissibility first: bonds to 1e-13, violated pieces pushed to limit + τ
        cons = prob.candidates(x, 1e-3)
        x1 = pol.project(x, cons, np.zeros(len(cons), dtype=bool))
        if x1 is None or (guard and not pol.passage_ok(x, x1)):
            x1 = x
        xf, ef, it, converged, reason = pol.run(x1, int(max_iter), float(tol))
        res, gn, _, akeys, amu = pol.kkt(xf)
    if ef > e0:  # nothing gained (only possible from the initial projection): keep the input
        xf, ef = x, e0
        reason += "; no energy decrease found, input returned"
        with threadpool_limits(limits=1, user_api="blas"):
            res, gn, _, akeys, amu = pol.kkt(xf)
    gap_force = float(np.sum(amu[akeys >= 3 * n * n])) if len(akeys) else 0.0
    cons = prob.candidates(xf, 1e-3)
    dist = cons.evaluate(xf)[0]
    n_active = int(np.sum(dist - cons.lim <= ACTIVE_TOL))
    bonds = np.linalg.norm((np.roll(xf, -1, axis=0) - xf) if closed else np.diff(xf, axis=0),
                           axis=1)
    if res <= tol * gn:
        converged = True
    return PolishResult(pos=xf.copy(), energy_before=e0, energy=ef, kkt_residual=res,
                        grad_norm=gn, iterations=it, converged=bool(converged), reason=reason,
                        n_active=n_active, max_bond_error=float(np.max(np.abs(bonds - 1.0))),
                        exclusion_margin=pol.clearance(xf), strand_gap=pol.strand_gap(xf),
                        gap_force=gap_force, seconds=time.perf_counter() - t0)
