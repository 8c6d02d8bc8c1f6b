"""An open chain at fixed force F (paper §VIII): crankshafts plus end moves.

Thin Python layer over :func:`stiffknots.engine.kernel.run_moves` (interior crankshafts, ends
fixed) and the end moves of :mod:`stiffknots.engine.force_kernel` (slide and pivot moves: the
ends move along z). All preserve the fixed-force measure (see the force kernel's docstring),
and a fixed interleaving of them keeps it stationary. The energy is E = E_d − F·Δz.
"""

from __future__ import annotations

import math

import numpy as np

from stiffknots.engine import kernel as K
from stiffknots.engine.force_kernel import run_end_moves, run_slide_moves
from stiffknots.engine.state import ChainState, MoveParams, acceptance_block

END_BLOCK = 2000  # moves per block of the interleaving (crankshafts, then end moves)


def _split(total: int, parts: int) -> list[int]:
    q, r = divmod(int(total), parts)
    return [q + (1 if c < r else 0) for c in range(parts)]


class ForceChainState(ChainState):
    """An open chain clamped on the z axis whose ends slide along z under the force ``force``.

    Parameters
    ----------
    coords : (N, 3) open chain (see :func:`stiffknots.engine.state.check_open_clamping`).
    params : crankshaft, exclusion and energy parameters (the end moves use the same
        exclusion, energy, curvature limit and angle scales).
    seed : seed of the kernels' generator (one generator for both move types).
    force : F ≥ 0 in C/b².
    end_fraction : fraction of the attempted moves that move an end (0 … 1).
    slide_fraction : fraction of those that are slide moves; the others are pivot moves.
    end_m_max : largest number of beads rotated by a pivot move (≥ 1).
    slide_m_max : largest number of free beads translated by a slide move (≥ 0; None: all).

    Attributes
    ----------
    energy : E_d (incremental), as for :class:`ChainState`.
    total_energy : E_d − F·Δz (incremental).
    """

    def __init__(self, coords: np.ndarray, params: MoveParams | None = None, seed: int = 0,
                 force: float = 0.0, end_fraction: float = 0.1, end_m_max: int = 30,
                 slide_fraction: float = 0.8, slide_m_max: int | None = None):
        super().__init__(coords, params, seed=seed, closed=False)
        if not (math.isfinite(force) and force >= 0):
            raise ValueError(f"the force must be ≥ 0 (in units of C/b²), got {force}")
        if not 0 <= end_fraction <= 1:
            raise ValueError(f"end_fraction must be in [0, 1], got {end_fraction}")
        if not 0 <= slide_fraction <= 1:
            raise ValueError(f"slide_fraction must be in [0, 1], got {slide_fraction}")
        if int(end_m_max) != end_m_max or end_m_max < 1:
            raise ValueError(f"end_m_max must be an integer ≥ 1, got {end_m_max}")
        n = self.n_beads
        if slide_m_max is None:
            slide_m_max = n - 5
        if int(slide_m_max) != slide_m_max or slide_m_max < 0:
            raise ValueError(f"slide_m_max must be an integer ≥ 0, got {slide_m_max}")
        self.force = float(force)
        self.end_fraction = float(end_fraction)
        self.slide_fraction = float(slide_fraction)
        self.end_m_max = int(end_m_max)
        self.slide_m_max = int(slide_m_max)
        rows = max(2, self.params.m_max, self.end_m_max + 2, min(self.slide_m_max, n) + 3)
        self.newpos = np.empty((rows, 3), dtype=np.float64)
        self.end_counters = np.zeros(K.C_NCNT, dtype=np.int64)
        self.slide_counters = np.zeros(K.C_NCNT, dtype=np.int64)
        self.total_energy = self.energy - self.force * self.extension

    @property
    def extension(self) -> float:
        """Δz = z_{N−1} − z_0."""
        return float(self.pos[-1, 2] - self.pos[0, 2])

    def recomputed_total(self) -> float:
        """E_d − F·Δz recomputed from scratch."""
        return self.recomputed_energy() - self.force * self.extension

    def run_crankshafts(self, n_moves: int, temperature: float) -> float:
        """Interior crankshafts only (Δz fixed); returns ΔE_d (= Δ(E_d − F·Δz))."""
        de = ChainState.run(self, n_moves, temperature)
        self.total_energy += de
        return de

    def run_ends(self, n_moves: int, temperature: float) -> float:
        """Pivot end moves only; returns Δ(E_d − F·Δz) of the accepted moves."""
        z0 = self.extension
        de = run_end_moves(self.pos, int(n_moves), float(temperature), self.force,
                           self.end_m_max, self.ipar, self.fpar, self.head, self.nxt, self.prv,
                           self.bucket, self.newpos, self.end_counters, self.rng)
        self.total_energy += de
        self.energy += de + self.force * (self.extension - z0)
        return de

    def run_slides(self, n_moves: int, temperature: float) -> float:
        """Slide moves only; returns Δ(E_d − F·Δz) of the accepted moves."""
        z0 = self.extension
        de = run_slide_moves(self.pos, int(n_moves), float(temperature), self.force,
                             self.slide_m_max, self.ipar, self.fpar, self.head, self.nxt,
                             self.prv, self.bucket, self.newpos, self.slide_counters, self.rng)
        self.total_energy += de
        self.energy += de + self.force * (self.extension - z0)
        return de

    def run(self, n_moves: int, temperature: float) -> float:
        """``n_moves`` moves, a fraction ``end_fraction`` of them end moves (slides and pivots),
        interleaved in blocks of ≈ END_BLOCK; returns Δ(E_d − F·Δz)."""
        n_moves = int(n_moves)
        n_end = int(round(n_moves * self.end_fraction))
        n_slide = int(round(n_end * self.slide_fraction))
        blocks = max(1, -(-n_moves // END_BLOCK))
        de = 0.0
        for nc, ns, ne in zip(_split(n_moves - n_end, blocks), _split(n_slide, blocks),
                              _split(n_end - n_slide, blocks), strict=True):
            if nc:
                de += self.run_crankshafts(nc, temperature)
            if ns:
                de += self.run_slides(ns, temperature)
            if ne:
                de += self.run_ends(ne, temperature)
        return de

    def acceptance(self) -> dict:
        out = super().acceptance()
        for c, cls, name in ((self.end_counters, 0, "pivot_top"),
                             (self.end_counters, 1, "pivot_bottom"),
                             (self.slide_counters, 0, "slide_top"),
                             (self.slide_counters, 1, "slide_bottom")):
            out[name] = acceptance_block(c, cls)
        return out
