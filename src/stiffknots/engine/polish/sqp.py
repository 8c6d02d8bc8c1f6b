"""The final minimiser's iteration: a feasible sequential quadratic programme (SQP).

One iteration, from an admissible x:

1. *Candidates*: every constraint piece within a margin of its limit
   (:mod:`stiffknots.engine.polish.pieces`; the margin follows the recent step length, at
   most 2·max_step + 0.05).
2. *QP*: minimise ∇E·dx + ½ dxᵀ(∇²L + σI)dx, L = E − Σ λ_k c_k − Σ μ_p g_p, subject to the
   linearised bonds (= 0), pieces (≥ 0) and six sparse gauge rows that remove the rigid
   motions (one, rotation about z, for a clamped open chain). A primal active-set method
   (Nocedal & Wright, Alg. 16.3) starts from dx = 0 with the tight pieces, adds one blocking
   piece or drops the most negative multiplier at a time, and follows directions of
   non-positive curvature until a piece blocks (inertia control). The base KKT matrix
   [H Aᵀ; A 0] is factorised once (sparse LU); working-set changes go through a bordered
   inverse of the Schur complement J_W K⁻¹ J_Wᵀ (:mod:`stiffknots.engine.polish.kkt`).
   σ ≥ 0 is raised only when the subproblem is unbounded; an unbounded direction is first
   tried as a negative-curvature step.
3. *Projection*: the trial x + α·dx goes back onto the bonds (to ~10⁻¹³) and the violated
   pieces (to their target) by min-norm Gauss–Newton corrections (chord iterations):
   dx = Aᵀ(AAᵀ)⁻¹r (``_MinNormSolver``).
4. *Acceptance*: the exclusion rule on *all* pairs (an O(N²) check, independent of the
   candidates), the strand gap, no energy increase (Armijo where resolvable in floating
   point) and the passage guard (:mod:`stiffknots.engine.guard`); otherwise α is halved.

Convergence is measured by the KKT residual: with A the Jacobian of the bonds and of the
pieces within 10⁻⁸ of their limit, restricted to the free beads,

    kkt_residual = min_{λ, μ ≥ 0} ‖∇E − Aᵀ(λ, μ)‖₂,

the part of the energy gradient that no combination of bond tensions and pushing contact
forces balances; it vanishes exactly at a KKT point (away from contacts it is the gradient
projected on the tangent space of the bond manifold). The run has converged when
kkt_residual ≤ tol·‖∇E‖₂, or when the exact model predicts no decrease that E can resolve
(``|ΔE| < 10⁻¹³·E``) and kkt_residual ≤ 10⁻⁶·‖∇E‖₂.

With ``exclusion="none"`` the chain may self-intersect (e.g. an m-covered circle), so the guard
is off by default there (``guard=None``); pass ``guard=True`` to keep it.
"""

from __future__ import annotations

import logging
import math

import numpy as np
import scipy.sparse as sp

from stiffknots.engine.guard import _passage_ok
from stiffknots.engine.kernel import energy_chain
from stiffknots.engine.polish.kkt import (
    _factor_kkt,
    _MinNormSolver,
    _SchurInverse,
    _solve_kkt_robust,
)
from stiffknots.engine.polish.pieces import TAU, _min_clearance
from stiffknots.engine.polish.problem import _energy_grad, _Problem

log = logging.getLogger(__name__)

ACTIVE_TOL = 1e-8  # a contact within this distance of its limit counts as active
BOND_TOL_OUT = 1e-13  # the projection stops when every bond is unit to this
#: the stall test of ``_Polisher.run()``: over the last STALL_STEPS accepted steps E fell by
#: ≤ STALL_REL·E while the KKT residual is ≤ STALL_KKT·‖∇E‖ — converged: the energy settles
#: long before the residual reaches ``tol`` (docs/methods/minimiser.md)
STALL_STEPS = 8
STALL_REL = 1e-10
STALL_KKT = 1e-6


class _Polisher:
    """The SQP of the module docstring on one :class:`_Problem`: its measures, the KKT
    residual, the projection, one QP step and the iteration (:meth:`run`)."""

    def __init__(self, prob: _Problem, max_step: float, guard: bool, zlo: float, zhi: float,
                 max_depth: int):
        self.p = prob
        self.max_step = max_step
        self.guard = guard
        self.zlo = zlo
        self.zhi = zhi
        self.max_depth = max_depth
        self.margin = 2.0 * max_step + 0.05

    # ---- measures ------------------------------------------------------------------------
    def energy(self, pos):
        return float(energy_chain(pos, self.p.is_open))

    def grad_free(self, pos):
        e, g = _energy_grad(pos, self.p.is_open)
        return e, g[self.p.free].ravel()

    def clearance(self, pos):
        """Min over the exclusion rule of (distance − limit) (capped at 1; inf for none)."""
        if self.p.mode == 2:
            return math.inf
        return float(_min_clearance(pos, self.p.mode, self.p.limit, self.p.is_open))

    def strand_gap(self, pos):
        """Min distance between segments that share no bead (capped at 1)."""
        return float(_min_clearance(pos, 1, 0.0, self.p.is_open))

    def passage_ok(self, old, new):
        return bool(_passage_ok(old, new, self.p.is_open, self.p.nfix, self.zlo, self.zhi,
                                self.max_depth))

    def step_ok(self, old, new):
        p = self.p
        if p.is_open:
            inner = new[p.nfix:p.n - p.nfix, 2]
            if np.any(inner <= self.zlo) or np.any(inner >= self.zhi):
                return False
        if p.mode != 2 and self.clearance(new) < 0.0:
            return False
        if p.gap > 0 and self.strand_gap(new) < p.gap:
            return False
        return not self.guard or self.passage_ok(old, new)

    # ---- multipliers and the KKT residual ------------------------------------------------
    def kkt(self, pos):
        """(residual, ‖∇E‖, λ, active keys, μ) at ``pos``: least-squares multipliers with
        μ ≥ 0 over the pieces within ACTIVE_TOL of their limit (active-set NNLS)."""
        p = self.p
        _, g = self.grad_free(pos)
        gn = float(np.linalg.norm(g))
        cons = p.candidates(pos, 1e-3)
        dist, _, wts, direc = cons.evaluate(pos)
        act = np.flatnonzero(dist - cons.lim <= ACTIVE_TOL)
        _, b = p.bond_residual(pos)
        nb = len(p.bk)
        mu = np.zeros(0)
        for _ in range(100):
            a = p.jacobian(pos, b, cons.idx[act], wts[act], direc[act], rigid=False)
            out = _solve_kkt_robust(sp.identity(a.shape[1], format="csr"), a, g,
                                    np.zeros(a.shape[0]))
            if out is None:
                return math.inf, gn, np.zeros(nb), cons.key[act], np.zeros(len(act))
            _, nu = out
            mu = nu[nb:]
            if not len(mu) or mu.min() >= -1e-14 * max(1.0, float(np.abs(mu).max())):
                break
            act = np.delete(act, int(np.argmin(mu)))
        res = g - a.T @ nu
        return float(np.linalg.norm(res)), gn, nu[:nb], cons.key[act], np.clip(mu, 0.0, None)

    # ---- projection onto the bonds and the held pieces ------------------------------------
    def project(self, pos, cons, hold, max_it=25):
        """Min-norm projection onto c = 0 and g_p = 0 for the held and the violated pieces:
        Gauss–Newton with the factorisation reused while the held set does not change (chord
        method; the corrections are small, so it converges fast), refactorised when it does
        or when the residual stops shrinking. Stops when every bond is unit to ~1e-13 and
        every piece is at least its target up to τ/2."""
        p = self.p
        y = pos.copy()
        hold = hold.copy()
        lu = None
        held = None
        last = math.inf
        for _ in range(max_it):
            c, b = p.bond_residual(y)
            dist, g, wts, direc = cons.evaluate(y)
            bond_ok = not len(c) or np.max(np.abs(c)) <= 2 * BOND_TOL_OUT
            # one-sided: every piece at least its target (limit + τ) up to τ/2
            if bond_ok and (not len(dist) or np.min(dist - cons.target) >= -0.5 * TAU):
                return y
            hold |= g < 0.0
            sel = np.flatnonzero(hold)
            rhs = -np.r_[c, g[sel]]
            size = float(np.max(np.abs(rhs)))
            if size > 1e3 * last:
                return None  # diverging: the step was too long for the linearisation
            if lu is None or not np.array_equal(sel, held) or size > 0.25 * last:
                lu = _MinNormSolver(p, b, cons.idx[sel], wts[sel], direc[sel])
                if lu.solve_g is None:
                    return None
                held = sel
            last = size
            dx = lu.solve(rhs)
            if not np.all(np.isfinite(dx)) or np.max(np.abs(dx)) > 0.5:
                return None
            y[p.free] += dx
        return None

    # ---- one SQP step --------------------------------------------------------------------
    def qp_step(self, pos, g, lam, mu_of, sigma, margin):
        """Solve the QP by a primal active-set method (Nocedal & Wright, Alg. 16.3).

        Starts at dx = 0 (feasible: every piece has g ≥ 0 there) with the tight pieces as
        working set and adds one blocking piece or drops the most negative multiplier per
        iteration; a direction of non-positive curvature is followed until a piece blocks
        (inertia control). The base KKT matrix [H Aᵀ; A 0] (A: bonds and rigid rows) is
        factorised once; working-set changes go through the dense Schur complement
        S = J K⁻¹ Jᵀ over the candidate pieces. Returns (dx (nf, 3), λ, μ (per candidate),
        working set, candidates, predicted decrease, ∇E·dx, dxᵀ(H + σI)dx, clean, direction
        of non-positive curvature or None) or None; ``clean`` is False when the subproblem is
        unbounded along such a direction or does not finish.
        """
        p = self.p
        cons = p.candidates(pos, margin)
        dist, gval, wts, direc = cons.evaluate(pos)
        # the projection restores feasibility exactly, so the QP asks for a tangential step:
        # no bond correction, and pieces at (or within τ below) their target stay put
        gq = np.maximum(gval, 0.0)
        key = cons.key
        mu = np.array([mu_of.get(int(k), 0.0) for k in key]) if len(key) else np.zeros(0)
        _, b = p.bond_residual(pos)
        h = p.hessian(pos, lam, cons, wts, mu)
        if sigma > 0:
            h = h + sigma * sp.identity(h.shape[0])
        nb = len(p.bk)
        nm = len(key)
        n = h.shape[0]
        a0 = p.jacobian(pos, b, cons.idx[:0], wts[:0], direc[:0], rigid=True)
        na = a0.shape[0]
        lu = _factor_kkt(h, a0)
        if lu is None:
            return None
        u0 = lu.solve(np.r_[-g, np.zeros(na)])
        if nm:
            jall = p.jacobian(pos, b, cons.idx, wts, direc, rigid=False)[nb:]
            ju0 = jall @ u0[:n]
            vcols = np.zeros((n + na, nm), order="F")  # K⁻¹ [J_pᵀ; 0], on demand
            sv = np.zeros((nm, nm), order="F")  # J_p K⁻¹ J_qᵀ, columns on demand (dense)
            have = np.zeros(nm, dtype=bool)
        scale = np.where(cons.form == 0, 2.0 * cons.target, 1.0) if nm else np.zeros(0)
        work = gq <= 1e-12 * scale  # tight pieces (a distance within ~1e-12 of its target)
        dx = np.zeros(n)
        nu_b = np.zeros(nb)
        nu_c = np.zeros(nm)
        clean = True
        lin = gq.copy()
        ncdir = None
        schur = _SchurInverse()
        n_inner = 0
        for _ in range(4 * nm + 20):
            n_inner += 1
            sel = np.flatnonzero(work)
            if sel.size:
                need = sel[~have[sel]]
                if need.size:
                    rhs_cols = np.zeros((n + na, need.size))
                    for j, r in enumerate(need.tolist()):  # column j: J's row r (CSR)
                        lo, hi = jall.indptr[r], jall.indptr[r + 1]
                        np.add.at(rhs_cols[:, j], jall.indices[lo:hi], jall.data[lo:hi])
                    vcols[:, need] = lu.solve(rhs_cols)
                    sv[:, need] = jall @ vcols[:n, need]
                    have[need] = True
                # inverse of the Schur complement J_W K⁻¹ J_Wᵀ, kept up to date (its blocks
                # read from the dense columns: no sparse row indexing in the inner loop)
                sel = schur.sync(sel, lambda rows, cols: sv[np.ix_(rows, cols)])
                y = schur.inv @ (ju0[sel] + gq[sel])
                z = u0 - vcols[:, sel] @ y
            else:
                y = np.zeros(0)
                z = u0
            step = z[:n] - dx
            if np.max(np.abs(step)) > 1e-14 * max(1.0, float(np.max(np.abs(dx)))):
                hs = h @ step
                cs = float(step @ hs)
                alpha = 1.0
                if not cs > 0.0:
                    # non-positive curvature inside the working set: follow the direction
                    # downhill until a piece blocks (inertia control); unbounded otherwise
                    if float((g + h @ dx) @ step) > 0.0:
                        step = -step
                    smax = float(np.max(np.linalg.norm(step.reshape(-1, 3), axis=1)))
                    alpha = 1.0 / smax if smax > 0 else 0.0  # at most one bond length
                block = np.zeros(0, dtype=np.int64)
                if nm:
                    js = jall @ step
                    cand = np.flatnonzero(~work & (js < 0.0))
                    if cand.size:
                        ratios = np.maximum(lin[cand], 0.0) / -js[cand]
                        k = int(np.argmin(ratios))
                        if ratios[k] < alpha:
                            alpha = float(ratios[k])
                            # every piece that blocks at the same length (symmetric starts)
                            block = cand[ratios <= alpha * (1.0 + 1e-9) + 1e-300]
                if not cs > 0.0 and np.size(block) == 0:
                    clean = False
                    ncdir = step.reshape(-1, 3)
                    break
                dx = dx + alpha * step
                if nm:
                    lin = gq + jall @ dx
                if block.size:
                    work[block] = True
                    continue
                # full step: the multipliers of this working set are the QP's if all ≥ 0
            nu_b = -z[n:n + nb]
            nu_c = np.zeros(nm)
            nu_c[sel] = -y
            if not sel.size:
                break
            k = int(np.argmin(nu_c[sel]))
            tol_nu = -1e-12 * max(1e-300, float(np.max(np.abs(nu_c))))
            if nu_c[sel][k] >= tol_nu:
                break
            work[sel[k]] = False  # release the piece with the most negative multiplier
        else:
            clean = False
        log.debug("  QP: %d candidates, %d in the working set, %d inner iterations", nm,
                  int(work.sum()), n_inner)
        curv = float(dx @ (h @ dx))
        gd = float(g @ dx)
        pred = -(gd + 0.5 * (curv - sigma * float(dx @ dx)))
        return dx.reshape(-1, 3), nu_b, nu_c, work, cons, pred, gd, curv, clean, ncdir

    def curvature_step(self, x, e, direction, cons, length):
        """Line search along a direction of non-positive curvature (either sign, longest
        first); returns (y, E(y)) for the first admissible trial that lowers E, or
        (None, e)."""
        p = self.p
        dmax = float(np.max(np.linalg.norm(direction, axis=1)))
        if not dmax > 0.0 or not np.isfinite(dmax):
            return None, e
        _, g = self.grad_free(x)
        sgn = -1.0 if float(g @ direction.ravel()) > 0.0 else 1.0
        unit = sgn * direction / dmax
        t = length
        none = np.zeros(len(cons), dtype=bool)
        for _ in range(8):
            for sg in (1.0, -1.0):
                y = x.copy()
                y[p.free] += sg * t * unit
                y = self.project(y, cons, none)
                if y is not None and self.step_ok(x, y):
                    ey = self.energy(y)
                    if ey < e - 1e-13 * max(1.0, abs(e)):
                        return y, ey
                    log.debug("    curvature trial t=%.2e: dE=%.3e", sg * t, ey - e)
                else:
                    log.debug("    curvature trial t=%.2e: %s", sg * t,
                              "projection failed" if y is None else "inadmissible")
            t *= 0.5
        return None, e

    def run(self, pos, max_iter, tol):
        p = self.p
        x = pos
        e = self.energy(x)
        res, gn, lam, akeys, amu = self.kkt(x)
        mu_of = dict(zip(akeys.tolist(), amu.tolist(), strict=True))
        sigma = 0.0
        it = 0
        nc_tries = 0
        reset_at = -1
        last_step = self.max_step
        reason = "max_iter reached"
        converged = False
        hist = [e]  # E after every accepted step
        while True:
            if res <= tol * gn:
                converged = True
                reason = "KKT residual below tol"
                break
            if len(hist) > STALL_STEPS and hist[-1 - STALL_STEPS] - e <= STALL_REL * abs(e) \
                    and res <= STALL_KKT * gn:
                # the last steps crawl: E is settled far below the 1e-6 the minimiser
                # promises, and the KKT residual is already within it
                converged = True
                reason = (f"stalled at the minimum (E changed by ≤ {STALL_REL:g}·E over "
                          f"{STALL_STEPS} steps, KKT residual ≤ {STALL_KKT:g}·‖∇E‖)")
                break
            if it >= max_iter:
                break
            margin = min(self.margin, 4.0 * last_step + 0.02)
            out = self.qp_step(x, self.grad_free(x)[1], lam, mu_of, sigma, margin)
            if out is None:
                reason = "KKT system could not be solved"
                break
            dx, nu_b, nu_c, act, cons, pred, gd, curv, clean, ncdir = out
            rounding = 1e-13 * max(1.0, abs(e))
            log.debug("it %d E %.15g kkt %.3e sigma %.1e pred %.3e gd %.3e curv %.3e nact %d "
                      "clean %s", it, e, res, sigma, pred, gd, curv, int(np.sum(act)), clean)
            if abs(pred) < rounding and abs(gd) < rounding and sigma > 1e-8 \
                    and reset_at != it:
                # below the resolution of E only because σ damps the step: look again with
                # the exact model (once per iterate)
                reset_at = it
                sigma = 0.0
                continue
            if clean and sigma <= 1e-8 and abs(pred) < rounding and abs(gd) < rounding:
                # the exact model sees no decrease E can resolve: stationary to rounding
                converged = res <= 1e-6 * gn
                reason = ("stationary to rounding (model decrease below the resolution of E)"
                          if converged else "stalled: no resolvable decrease, KKT residual "
                          "above 1e-6·‖∇E‖")
                break
            dmax = float(np.max(np.linalg.norm(dx, axis=1)))
            if not clean or pred <= 0.0 or gd >= 0.0 or dmax > 1.0:
                # negative curvature: first try to descend along it, else convexify (H + σI)
                # and solve again
                if ncdir is not None and nc_tries < 3:
                    nc_tries += 1
                    y, ey = self.curvature_step(x, e, ncdir, cons,
                                                min(self.max_step, 4.0 * last_step))
                    if y is not None:
                        log.debug("  negative-curvature step: E %.15g -> %.15g", e, ey)
                        it += 1
                        x, e = y, ey
                        res, gn, lam, akeys, amu = self.kkt(x)
                        mu_of = dict(zip(akeys.tolist(), amu.tolist(), strict=True))
                        continue
                sigma = max(10.0 * sigma, 1e-6)
                if sigma > 1e6:
                    converged = res <= 1e-6 * gn
                    reason = ("no descent direction left (KKT residual ≤ 1e-6·‖∇E‖)"
                              if converged else "no descent direction found")
                    break
                continue
            nc_tries = 0
            alpha = min(1.0, self.max_step / dmax) if dmax > 0 else 1.0
            accepted = False
            fails = [0, 0, 0]
            for _ls in range(40):
                y = x.copy()
                y[p.free] += alpha * dx
                y = self.project(y, cons, np.zeros(len(cons), dtype=bool))
                if y is None:
                    fails[0] += 1
                elif not self.step_ok(x, y):
                    fails[1] += 1
                else:
                    ey = self.energy(y)
                    armijo = ey <= e + 1e-4 * alpha * gd
                    if armijo or (ey <= e and -alpha * gd < rounding):
                        accepted = True
                        break
                    fails[2] += 1
                    if -alpha * gd < 0.1 * rounding and curv >= 0.0:
                        break  # shorter steps cannot lower E by a resolvable amount
                alpha *= 0.5
                if alpha * dmax < 1e-15:
                    break
            log.debug("  alpha %.3e dmax %.3e accepted %s fails (projection, admissibility, "
                      "energy) %s", alpha, dmax, accepted, fails)
            if not accepted:
                if sigma <= 1e-8 and abs(gd) < rounding and abs(pred) < rounding:
                    converged = res <= 1e-6 * gn
                    reason = ("stationary to rounding (model decrease below the resolution of "
                              "E)" if converged else "stalled: line search failed")
                    break
                if sigma < 1e4:
                    sigma = max(10.0 * sigma, 1e-4)
                    continue
                reason = "line search failed"
                break
            it += 1
            last_step = max(alpha * dmax, 1e-3)
            x = y
            e = ey
            hist.append(e)
            lam = nu_b
            pos_mu = nu_c > 0
            mu_of = dict(zip(cons.key[pos_mu].tolist(), nu_c[pos_mu].tolist(), strict=True))
            if alpha * dmax >= 0.999 * min(dmax, self.max_step):
                sigma = sigma * 0.1 if sigma > 1e-10 else 0.0
            res, gn, _, _, _ = self.kkt(x)
        return x, e, it, converged, reason
