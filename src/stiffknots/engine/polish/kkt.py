"""The final minimiser's linear algebra: KKT systems, the min-norm projection, Schur updates.

* The base KKT matrix [H Aᵀ; A 0] of a QP step (A: the bonds and the gauge rows) is
  factorised once by sparse LU (``_factor_kkt()``), with a tiny dual regularisation
  [H Aᵀ; A −reg·I] when it is singular (dependent constraints); SuperLU's diagnostics on an
  exactly singular matrix are held back (``_superlu_diagnostics_held()``).
* Working-set changes go through a bordered inverse of the Schur complement J_W K⁻¹ J_Wᵀ
  (``_SchurInverse``).
* The projection's min-norm correction dx = Aᵀ(AAᵀ)⁻¹r (``_MinNormSolver``): the Gram
  matrix AAᵀ is assembled bead by bead in a compiled kernel and factorised by dense Cholesky
  (sparse LU for long chains).
"""

from __future__ import annotations

import contextlib
import ctypes
import os
import sys
import threading

import numpy as np
import scipy.linalg
import scipy.sparse as sp
from numba import njit
from scipy.sparse.linalg import splu


def _kkt_matrix(h, a, reg=0.0):
    """[h aᵀ; a −reg·I] as CSC, assembled from the blocks' triplets in one go: the same
    matrix as ``sp.bmat([[h, a.T], [a, -reg·I]])`` (tested), without bmat's per-call
    overhead, which cost more than the factorisation (docs/methods/minimiser.md)."""
    n, m = h.shape[0], a.shape[0]
    hc, ac = h.tocoo(), a.tocoo()
    rows = [hc.row, ac.col, ac.row + n]
    cols = [hc.col, ac.row + n, ac.col]
    vals = [hc.data, ac.data, ac.data]
    if reg > 0:
        d = np.arange(n, n + m)
        rows.append(d)
        cols.append(d)
        vals.append(np.full(m, -reg))
    return sp.csc_matrix((np.concatenate(vals), (np.concatenate(rows), np.concatenate(cols))),
                         shape=(n + m, n + m))


def _solve_kkt(h, a, rhs_top, rhs_bot, reg=0.0):
    """Solve [h aᵀ; a −reg·I][x; y] = [rhs_top; rhs_bot]; returns (x, y) or None."""
    n = h.shape[0]
    k = _kkt_matrix(h, a, reg)
    try:
        lu = _splu(k)
        z = lu.solve(np.r_[rhs_top, rhs_bot])
    except RuntimeError:
        return None
    if not np.all(np.isfinite(z)):
        return None
    return z[:n], z[n:]


@njit(cache=True)
def _row_entries(n, fmap, bk, bk1, b, idx, wts, direc):
    """The rows of A = [bond rows; piece rows] (free beads only), grouped by bead: bead v's
    entries are ``row[start[v]:start[v + 1]]`` with 3-vectors ``vec[...]`` (A's block of that
    row on bead v). Bond k: +2b_k on bead k + 1, −2b_k on bead k (∇(|b_k|² − 1)); piece p:
    w[p, s]·dir[p] on bead idx[p, s] (:meth:`_Cons.evaluate`)."""
    nb = bk.shape[0]
    m = idx.shape[0]
    cnt = np.zeros(n + 1, dtype=np.int64)
    for r in range(nb):
        if fmap[bk[r]] >= 0:
            cnt[bk[r] + 1] += 1
        if fmap[bk1[r]] >= 0:
            cnt[bk1[r] + 1] += 1
    for i in range(m):
        for s in range(4):
            v = idx[i, s]
            if v >= 0 and fmap[v] >= 0:
                cnt[v + 1] += 1
    start = np.cumsum(cnt)
    fill = start[:n].copy()
    row = np.empty(start[n], dtype=np.int64)
    vec = np.empty((start[n], 3))
    for r in range(nb):
        for v, sg in ((bk1[r], 2.0), (bk[r], -2.0)):
            if fmap[v] >= 0:
                e = fill[v]
                row[e] = r
                for c in range(3):
                    vec[e, c] = sg * b[r, c]
                fill[v] += 1
    for i in range(m):
        for s in range(4):
            v = idx[i, s]
            if v >= 0 and fmap[v] >= 0:
                e = fill[v]
                row[e] = nb + i
                for c in range(3):
                    vec[e, c] = wts[i, s] * direc[i, c]
                fill[v] += 1
    return start, row, vec


@njit(cache=True)
def _gram_dense(nrows, start, row, vec, reg):
    """G = A Aᵀ + reg·I (dense) from :func:`_row_entries`: G_ij = Σ_v A_iv·A_jv."""
    g = np.zeros((nrows, nrows))
    for v in range(start.shape[0] - 1):
        for p in range(start[v], start[v + 1]):
            for q in range(start[v], start[v + 1]):
                g[row[p], row[q]] += (vec[p, 0] * vec[q, 0] + vec[p, 1] * vec[q, 1]
                                      + vec[p, 2] * vec[q, 2])
    for i in range(nrows):
        g[i, i] += reg
    return g


@njit(cache=True)
def _gram_triplets(start, row, vec):
    """The (i, j, A_iv·A_jv) triplets of G = A Aᵀ (duplicates to be summed)."""
    tot = 0
    for v in range(start.shape[0] - 1):
        k = start[v + 1] - start[v]
        tot += k * k
    ri = np.empty(tot, dtype=np.int64)
    ci = np.empty(tot, dtype=np.int64)
    val = np.empty(tot)
    t = 0
    for v in range(start.shape[0] - 1):
        for p in range(start[v], start[v + 1]):
            for q in range(start[v], start[v + 1]):
                ri[t] = row[p]
                ci[t] = row[q]
                val[t] = vec[p, 0] * vec[q, 0] + vec[p, 1] * vec[q, 1] + vec[p, 2] * vec[q, 2]
                t += 1
    return ri, ci, val


@njit(cache=True)
def _apply_at(n, fmap, start, row, vec, y, out):
    """out[f(v)] = Σ_rows A_rv·y_r = (Aᵀy) on every free bead v (out: (N_f, 3))."""
    for v in range(n):
        f = fmap[v]
        if f < 0:
            continue
        for c in range(3):
            out[f, c] = 0.0
        for p in range(start[v], start[v + 1]):
            for c in range(3):
                out[f, c] += vec[p, c] * y[row[p]]


#: G = A Aᵀ of the projection is factorised densely (LAPACK Cholesky) up to this many rows
#: (bonds + held pieces), as a sparse LU above: dense is the cheaper at the sizes of the
#: paper's N = 150 (docs/methods/minimiser.md)
DENSE_GRAM_ROWS = 320


class _MinNormSolver:
    """The min-norm correction of the projection: dx = Aᵀ(AAᵀ)⁻¹r solves A dx = r with the
    least ‖dx‖ (the KKT system [I Aᵀ; A 0] of the projection, reduced to its Schur complement
    G = AAᵀ: symmetric positive definite when the rows are independent). Dependent rows (two
    contacts holding the same motion) get G + reg·I, reg = 10⁻¹², 10⁻⁹ in turn — the dual
    regularisation [I Aᵀ; A −reg·I] the full KKT system used. Dense Cholesky up to
    :data:`DENSE_GRAM_ROWS` rows, sparse LU of G above."""

    def __init__(self, prob, b, idx, wts, direc):
        self.p = prob
        self.nrows = len(prob.bk) + len(idx)
        self.start, self.row, self.vec = _row_entries(prob.n, prob.fmap, prob.bk, prob.bk1, b,
                                                      idx, wts, direc)
        self.solve_g = self._factor()

    def _factor(self):
        nr = self.nrows
        if nr <= DENSE_GRAM_ROWS:
            for reg in (0.0, 1e-12, 1e-9):
                g = _gram_dense(nr, self.start, self.row, self.vec, reg)
                try:
                    c = scipy.linalg.cho_factor(g, check_finite=False)
                except np.linalg.LinAlgError:
                    continue
                if np.all(np.isfinite(c[0])) and np.all(np.diag(c[0]) > 0.0):
                    return lambda r, c=c: scipy.linalg.cho_solve(c, r, check_finite=False)
            return None
        ri, ci, val = _gram_triplets(self.start, self.row, self.vec)
        for reg in (0.0, 1e-12, 1e-9):
            d = np.arange(nr)
            g = sp.csc_matrix((np.r_[val, np.full(nr, reg)], (np.r_[ri, d], np.r_[ci, d])),
                              shape=(nr, nr))
            try:
                lu = _splu(g)
            except RuntimeError:
                continue
            if np.all(np.isfinite(lu.solve(np.ones(nr)))):
                return lu.solve
        return None

    def solve(self, rhs):
        """dx (N_f, 3) with A dx = rhs and the least norm."""
        y = self.solve_g(rhs)
        out = np.empty((self.p.nf, 3))
        _apply_at(self.p.n, self.p.fmap, self.start, self.row, self.vec, y, out)
        return out


class _SchurInverse:
    """The inverse of S_WW = J_W K⁻¹ J_Wᵀ for a working set W that changes a few pieces at a
    time: bordering updates (O(|W|²)) on additions and removals, a fresh inverse every 64
    changes. If S_WW is numerically singular (dependent pieces: several contacts holding the
    same motion), S_WW + εI with ε = 10⁻¹²·max|S_ii| is inverted instead: it lets the
    linearised pieces move by ε·μ, which the projection removes."""

    def __init__(self):
        self.order = np.zeros(0, dtype=np.int64)
        self.inv = np.zeros((0, 0))
        self.changes = 0
        self.eps = 0.0

    def _fresh(self, sel, block):
        smat = block(sel, sel)
        self.order = sel
        self.changes = 0
        self.eps = 0.0
        eye = np.eye(len(sel))
        try:
            self.inv = np.linalg.inv(smat)
            ok = np.abs(self.inv @ smat - eye).max() < 1e-6 if len(sel) else True
        except np.linalg.LinAlgError:
            ok = False
        if not ok:  # dependent pieces: a tiny shift
            self.eps = 1e-12 * max(float(np.max(np.abs(np.diag(smat)))), 1e-300)
            self.inv = np.linalg.inv(smat + self.eps * eye)
        return sel

    def sync(self, sel, block):
        """Bring the inverse to the working set ``sel`` (sorted indices); returns the
        order of its rows (a permutation of ``sel``)."""
        cur = self.order
        in_cur = set(cur.tolist())
        in_sel = set(sel.tolist())
        added = [a for a in sel.tolist() if a not in in_cur]
        removed = [r for r in cur.tolist() if r not in in_sel]
        nchange = len(added) + len(removed)
        if self.changes + nchange > 64 or nchange > 16 or not cur.size:
            return self._fresh(sel, block)
        inv = self.inv
        for r in removed:
            k = int(np.flatnonzero(cur == r)[0])
            piv = inv[k, k]
            if abs(piv) < 1e-300:
                return self._fresh(sel, block)
            col = np.delete(inv[:, k], k)
            row = np.delete(inv[k, :], k)
            inv = np.delete(np.delete(inv, k, axis=0), k, axis=1)
            inv -= np.outer(col, row) / piv
            cur = np.delete(cur, k)
        for a in added:
            sv = block(cur, np.array([a]))[:, 0]
            c = float(block(np.array([a]), np.array([a]))[0, 0]) + self.eps
            isv = inv @ sv
            gam = c - float(sv @ isv)
            if abs(gam) <= 1e-12 * max(abs(c), 1e-300):
                return self._fresh(sel, block)
            m = cur.size
            grown = np.empty((m + 1, m + 1))
            grown[:m, :m] = inv + np.outer(isv, isv) / gam
            grown[:m, m] = -isv / gam
            grown[m, :m] = -isv / gam
            grown[m, m] = 1.0 / gam
            inv = grown
            cur = np.append(cur, a)
        self.order = cur
        self.inv = inv
        self.changes += nchange
        return cur


_LIBC: list = []
_HELD_LOCK = threading.Lock()
_HELD: list = []  # the saved (stdout, stderr) descriptors while diagnostics are held back
_HELD_COUNT = [0]  # threads inside _superlu_diagnostics_held


def _libc():
    """The C library (for fflush), or None where it cannot be loaded."""
    if not _LIBC:
        try:
            _LIBC.append(ctypes.CDLL(None))
        except OSError:  # pragma: no cover - every POSIX system has one
            _LIBC.append(None)
    return _LIBC[0]


@contextlib.contextmanager
def _superlu_diagnostics_held():
    """Hold back what SuperLU prints while it factorises.

    On an exactly singular matrix (dependent constraint pieces, e.g. several tube pieces
    holding the same motion) SuperLU's factorisation prints LAPACK-style lines such as
    ``** On entry to DTRSV parameter number 6 had an illegal value`` on C's standard output
    and then raises ``RuntimeError: Factor is exactly singular``, which the callers handle
    (a retry with a tiny dual regularisation). The lines said nothing a user could act on and
    read like a failure of the result, so C's standard output and error point at the null
    device for the factorisation alone (C's buffers are flushed on both sides of it)."""
    libc = _libc()
    if libc is None:  # pragma: no cover
        yield
        return
    # the file descriptors are the process's: threads that factorise at once share one
    # redirection (the first in saves and redirects, the last out restores), never save
    # each other's /dev/null
    with _HELD_LOCK:
        if not _HELD:
            for f in (sys.stdout, sys.stderr):
                with contextlib.suppress(Exception):
                    f.flush()
            libc.fflush(None)
            null = os.open(os.devnull, os.O_WRONLY)
            saved = (os.dup(1), os.dup(2))
            os.dup2(null, 1)
            os.dup2(null, 2)
            os.close(null)
            _HELD.append(saved)
        _HELD_COUNT[0] += 1
    try:
        yield
    finally:
        with _HELD_LOCK:
            _HELD_COUNT[0] -= 1
            if not _HELD_COUNT[0]:
                saved = _HELD.pop()
                libc.fflush(None)
                os.dup2(saved[0], 1)
                os.dup2(saved[1], 2)
                for fd in saved:
                    os.close(fd)


def _splu(k):
    """``splu(k)`` with SuperLU's diagnostics held back (:func:`_superlu_diagnostics_held`);
    a singular matrix still raises RuntimeError."""
    with _superlu_diagnostics_held():
        return splu(k)


def _factor_kkt(h, a):
    """Sparse LU of [h aᵀ; a 0] (with a tiny dual regularisation if it is singular)."""
    for reg in (0.0, 1e-12, 1e-9):
        try:
            lu = _splu(_kkt_matrix(h, a, reg))
        except RuntimeError:
            continue
        test = lu.solve(np.ones(h.shape[0] + a.shape[0]))
        if np.all(np.isfinite(test)):
            return lu
    return None


def _solve_kkt_robust(h, a, rhs_top, rhs_bot):
    """:func:`_solve_kkt`, with a growing dual regularisation if the matrix is singular
    (dependent constraints)."""
    for reg in (0.0, 1e-12, 1e-9):
        out = _solve_kkt(h, a, rhs_top, rhs_bot, reg)
        if out is not None:
            return out
    return None
