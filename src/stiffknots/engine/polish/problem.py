"""The final minimiser's problem at fixed settings: energy, constraints, sparse matrices.

Written with the raw bond vectors b_n = r_{n+1} − r_n, E = Σ (1 − b_n·b_{n+1}) equals the
discrete bending energy E_d of §VII on the unit-bond manifold and is a quadratic form in the
positions; the bonds are ``c_k = |b_k|² − 1 = 0``, and the exclusion rule is a set of inequality
pieces (:mod:`stiffknots.engine.polish.pieces`). ``_Problem`` maps the free beads (an
open chain's clamped ends drop out) to coordinates interleaved x, y, z, gathers the candidate
pieces, and assembles the Jacobian of the bonds, the gauge rows and the pieces, and the exact
Hessian of the Lagrangian, as sparse matrices.
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp
from numba import njit

from stiffknots.engine.polish.pieces import (
    _bead_candidates,
    _Cons,
    _piece_hessians,
    _tube_candidates,
)

EXCLUSIONS = ("bead", "tube", "none")


@njit(cache=True)
def _energy_grad(pos, is_open):
    """E = Σ_joints (1 − b_{n−1}·b_n) with raw bond vectors, and its gradient (N, 3)."""
    n = pos.shape[0]
    g = np.zeros((n, 3))
    e = 0.0
    lo = 1 if is_open else 0
    hi = n - 1 if is_open else n
    for v in range(lo, hi):
        a = v - 1 if v > 0 else n - 1
        c = v + 1 if v < n - 1 else 0
        f = 0.0
        for q in range(3):
            f += (pos[v, q] - pos[a, q]) * (pos[c, q] - pos[v, q])
        e += 1.0 - f
        for q in range(3):
            u = pos[v, q] - pos[a, q]  # b_{v-1}
            w = pos[c, q] - pos[v, q]  # b_v
            # ∂f/∂r_a = −w, ∂f/∂r_v = w − u, ∂f/∂r_c = u; E = Σ (1 − f)
            g[a, q] += w
            g[v, q] -= w - u
            g[c, q] -= u
    return e, g


class _Problem:
    """The constrained problem at fixed settings: index maps, candidates, sparse assembly."""

    def __init__(self, n, closed, mode, limit, nfix, zrot_row, gap):
        self.n = n
        self.closed = closed
        self.is_open = not closed
        self.mode = mode  # 0 bead, 1 tube, 2 none
        self.limit = limit
        self.gap = gap  # strand gap (bead/none with the guard on), 0: none
        self.nfix = nfix
        self.free = np.arange(nfix, n - nfix)
        self.nf = self.free.size
        fmap = -np.ones(n, dtype=np.int64)
        fmap[self.free] = np.arange(self.nf)
        self.fmap = fmap
        # bonds touching a free bead
        ks = np.arange(n if closed else n - 1)
        k1 = (ks + 1) % n
        keep = (fmap[ks] >= 0) | (fmap[k1] >= 0)
        self.bk = ks[keep]
        self.bk1 = k1[keep]
        # joints (bead v between a and c)
        js = np.arange(n) if closed else np.arange(1, n - 1)
        self.ja = (js - 1) % n
        self.jv = js
        self.jc = (js + 1) % n
        self.nrigid = 6 if closed else (1 if zrot_row else 0)

    # ---- constraints -------------------------------------------------------------------
    def candidates(self, pos, margin):
        """The constraint pieces within ``margin`` of their limit."""
        parts = []
        big = self.n * self.n
        if self.mode == 0:
            pairs, key = _bead_candidates(pos, self.is_open, self.limit + margin, self.nfix)
            idx = np.full((len(key), 4), -1, dtype=np.int64)
            idx[:, :2] = pairs
            z = np.zeros(len(key), dtype=np.int64)
            parts.append(_Cons(z, idx, key, np.full(len(key), self.limit), z))
        elif self.mode == 1:
            ctype, idx, key = _tube_candidates(pos, self.is_open, self.limit + margin,
                                               self.nfix)
            key, first = np.unique(key, return_index=True)
            z = np.zeros(len(key), dtype=np.int64)
            parts.append(_Cons(ctype[first], idx[first], key, np.full(len(key), self.limit),
                               z))
        if self.gap > 0:
            ctype, idx, key = _tube_candidates(pos, self.is_open, self.gap + margin,
                                               self.nfix)
            key, first = np.unique(key, return_index=True)
            one = np.ones(len(key), dtype=np.int64)
            parts.append(_Cons(ctype[first], idx[first], key + 3 * big,
                               np.full(len(key), self.gap), one))
        return _Cons.concat(parts)

    def bond_residual(self, pos):
        b = pos[self.bk1] - pos[self.bk]
        return np.einsum("ij,ij->i", b, b) - 1.0, b

    # ---- sparse matrices (free coordinates, interleaved x, y, z) --------------------------
    def _triplets(self, rows, beads, vecs):
        """Rows with 3-vector entries on beads → (row, column, value) triplets over the free
        coordinates (interleaved x, y, z); clamped beads dropped."""
        f = self.fmap[beads]
        ok = f >= 0
        rows, f, vecs = rows[ok], f[ok], vecs[ok]
        return (np.repeat(rows, 3), (3 * f[:, None] + np.arange(3)).ravel(), vecs.ravel())

    def jacobian(self, pos, b, idx, wts, direc, rigid=True):
        """[bond rows; rigid rows (if ``rigid``); constraint rows], as CSR, assembled from
        the blocks' triplets in one go (the same matrix as stacking the blocks, tested)."""
        nb = len(self.bk)
        rows = np.arange(nb)
        parts = [self._triplets(np.r_[rows, rows], np.r_[self.bk1, self.bk],
                                np.r_[2 * b, -2 * b])]
        top = nb
        if rigid and self.nrigid:
            g = self.rigid_rows(pos).tocoo()
            parts.append((g.row + top, g.col, g.data))
            top += g.shape[0]
        m = len(idx)
        if m:
            beads = idx.ravel()
            vecs = (wts[:, :, None] * direc[:, None, :]).reshape(-1, 3)
            ok = beads >= 0
            r, c, v = self._triplets(np.repeat(np.arange(m), 4)[ok], beads[ok], vecs[ok])
            parts.append((r + top, c, v))
            top += m
        r, c, v = (np.concatenate(x) for x in zip(*parts, strict=True))
        return sp.csr_matrix((v, (r, c)), shape=(top, 3 * self.nf))

    def rigid_rows(self, pos):
        """Six sparse gauge rows that remove the rigid motions (closed chains): bead 0 does not
        move, bead 1 moves only along b_0 = r_1 − r_0, and the bead farthest from that line
        does not leave the plane it spans with it; E, the bonds and the exclusion rule are
        invariant under rigid motions, so this fixes nothing physical. A clamped open chain
        keeps one zero mode, the rotation about z: one free bead does not move azimuthally."""
        p = pos[self.free]
        if self.closed:
            e1 = p[1] - p[0]
            e1 = e1 / np.linalg.norm(e1)
            rel = p - p[0]
            perp = rel - np.outer(rel @ e1, e1)
            far = int(np.argmax(np.linalg.norm(perp, axis=1)))
            nrm = np.cross(e1, perp[far])
            nrm /= np.linalg.norm(nrm)
            t2 = np.cross(nrm, e1)
            beads = [0, 0, 0, 1, 1, far]
            vecs = [np.eye(3)[0], np.eye(3)[1], np.eye(3)[2], nrm, t2, nrm]
        else:
            rho = np.hypot(p[:, 0], p[:, 1])
            far = int(np.argmax(rho))
            beads = [far]
            vecs = [np.array([-p[far, 1], p[far, 0], 0.0]) / rho[far]]
        rows = np.repeat(np.arange(len(beads)), 3)
        cols = (3 * np.array(beads)[:, None] + np.arange(3)).ravel()
        return sp.csr_matrix((np.concatenate(vecs), (rows, cols)),
                             shape=(len(beads), 3 * self.nf))

    def hessian(self, pos, lam, cons, wts, mu):
        """Hessian of the Lagrangian ∇²E − Σ λ_k ∇²c_k − Σ μ_p ∇²g_p (free coordinates).

        E, the bonds and the vertex–vertex pieces are isotropic (an N_f × N_f matrix ⊗ I₃,
        exact); vertex–segment and segment–segment pieces add their exact 12 × 12 blocks.
        """
        fm = self.fmap
        ja, jv, jc = self.ja, self.jv, self.jc
        ones = np.ones(len(jv))
        # E = Σ (1 − b_{v−1}·b_v): (v,v) +2, (v,a) −1, (v,c) −1, (a,c) +1 (symmetrised)
        r = [jv, jv, ja, jv, jc, ja, jc]
        c = [jv, ja, jv, jc, jv, jc, ja]
        v = [2 * ones, -ones, -ones, -ones, -ones, ones, ones]
        # −λ_k ∇²(|b_k|² − 1): 2 on the diagonal, −2 off it
        k, k1 = self.bk, self.bk1
        r += [k, k1, k, k1]
        c += [k, k1, k1, k]
        v += [-2 * lam, -2 * lam, 2 * lam, 2 * lam]
        iso = np.zeros(0, dtype=bool)
        if len(cons):
            idx = cons.idx
            coef = np.where(cons.form == 0, -2.0 * mu, 0.0)
            iso = (cons.ctype == 0) & (coef != 0)  # vertex–vertex: −2μ w wᵀ ⊗ I, exact
            for s in range(4):
                for t in range(4):
                    ok = (idx[:, s] >= 0) & (idx[:, t] >= 0) & iso
                    r.append(idx[ok, s])
                    c.append(idx[ok, t])
                    v.append(coef[ok] * wts[ok, s] * wts[ok, t])
        r = np.concatenate(r)
        c = np.concatenate(c)
        v = np.concatenate(v)
        fr, fc = fm[r], fm[c]
        ok = (fr >= 0) & (fc >= 0)
        m = sp.coo_matrix((v[ok], (fr[ok], fc[ok])), shape=(self.nf, self.nf)).tocsr()
        h = sp.kron(m, sp.identity(3), format="csr")
        other = np.flatnonzero((mu != 0) & (cons.ctype != 0)) if len(cons) else []
        if len(other):
            h = h + self._piece_blocks(pos, cons.sub(other), mu[other])
        return h

    def _piece_blocks(self, pos, cons, mu):
        """−μ_p ∇²g_p for vertex–segment and segment–segment pieces (exact second
        derivatives of the point–line and line–line distances, :func:`_piece_hessians`)."""
        m = len(cons)
        hloc = np.empty((m, 12, 12))
        _piece_hessians(pos, cons.ctype, cons.idx, cons.form, hloc)
        hloc *= -mu[:, None, None]
        fm = self.fmap
        beads = np.where(cons.idx >= 0, cons.idx, 0)
        f = np.where(cons.idx >= 0, fm[beads], -1)  # (m, 4) free index or −1
        gi = (3 * f[:, :, None] + np.arange(3)).reshape(m, 12)
        ok = np.repeat(f >= 0, 3, axis=1)
        rows = np.broadcast_to(gi[:, :, None], (m, 12, 12))
        cols = np.broadcast_to(gi[:, None, :], (m, 12, 12))
        keep = ok[:, :, None] & ok[:, None, :] & (hloc != 0.0)
        n3 = 3 * self.nf
        return sp.coo_matrix((hloc[keep], (rows[keep], cols[keep])), shape=(n3, n3)).tocsr()
