"""The Monte Carlo state: a chain, its cell list and its parameters, in one of three ensembles.

Thin Python layer over the kernels (validation here, computation there):
:func:`stiffknots.engine.kernel.run_moves` (crankshafts: closed chains, and the interior of open
chains whose clamped ends stay fixed) and, in the fixed-force ensemble, the end moves of
:mod:`stiffknots.engine.force_kernel` (slides and pivots: the ends move along z). The
crankshafts and the end moves preserve the same fixed-force measure (see the force kernel's
docstring), and a fixed interleaving of them keeps it stationary; the energy is then
E = E_d − F·Δz (paper §VIII).
"""

from __future__ import annotations

import numpy as np

from stiffknots.engine import prims as K
from stiffknots.engine.force_kernel import run_end_moves, run_slide_moves
from stiffknots.engine.kernel import NB_NMETA, NB_RADIUS, NBR_PER_BEAD, run_moves, run_single_moves
from stiffknots.engine.params import (
    ENERGY_MODELS,
    Ensemble,
    MoveParams,
    ensemble_of,
)

__all__ = ["ChainState", "Ensemble", "MoveParams", "acceptance_block", "check_open_clamping"]

END_BLOCK = 2000  # moves per block of the fixed-force interleaving (crankshafts, then end moves)


def _split(total: int, parts: int) -> list[int]:
    q, r = divmod(int(total), parts)
    return [q + (1 if c < r else 0) for c in range(parts)]


def acceptance_block(counters: np.ndarray, cls: int) -> dict:
    """Tried, accepted and acceptance rate of move class ``cls`` from kernel counters."""
    tried = int(counters[K.C_TRIED + cls])
    acc = int(counters[K.C_ACCEPTED + cls])
    return {"tried": tried, "accepted": acc, "rate": acc / tried if tried else 0.0}


def check_open_clamping(pos: np.ndarray, tol: float = 1e-9) -> tuple[float, float]:
    """Check that an open chain is clamped as the kernel expects; returns (z_first, z_last).

    Beads 0, 1, N−2, N−1 lie on the z axis with z_1 = z_0 + 1 and z_{N−1} = z_{N−2} + 1 (the
    end segments point outward along ∓z), and every other bead lies strictly between z_0
    and z_{N−1} (paper §VIII: the ends are held straight along z).
    """
    ends = pos[[0, 1, -2, -1]]
    if np.max(np.abs(ends[:, :2])) > tol:
        raise ValueError("an open chain needs beads 0, 1, N−2, N−1 on the z axis (x = y = 0)")
    if abs(ends[1, 2] - ends[0, 2] - 1) > 1e-8 or abs(ends[3, 2] - ends[2, 2] - 1) > 1e-8:
        raise ValueError("an open chain's end segments must point along −z (first) and +z (last)")
    zlo, zhi = float(pos[0, 2]), float(pos[-1, 2])
    inner = pos[1:-1, 2]
    if np.any(inner <= zlo) or np.any(inner >= zhi):
        raise ValueError("every bead but the two end beads must lie strictly between z_0 and "
                         "z_{N−1} (the closure rays run along the z axis beyond the ends)")
    return zlo, zhi


class ChainState:
    """A unit-bond chain prepared for the kernels.

    Parameters
    ----------
    coords : ndarray
        (N, 3) chain with unit bonds that satisfies the exclusion model.
    params : MoveParams or None
        Move, exclusion and energy parameters.
    seed : int
        Seed of the kernels' generator (one generator for every move type).
    ensemble : Ensemble or str or None
        :class:`Ensemble` or its kind: ``"closed"`` (default), ``"extension"`` (an open
        chain clamped on the z axis, see :func:`check_open_clamping`; the excess length
        L_e = (N−1) − Δz is fixed, paper §VIII) or ``"force"`` (the ends slide along z under
        ``ensemble.force``).
    closed : bool or None
        Shorthand of older code: ``closed=False`` means ``ensemble="extension"``.

    Attributes
    ----------
    energy
        E_d (incremental, in the state's energy mode).
    total_energy
        E_d − F·Δz in the fixed-force ensemble (incremental); E_d otherwise.
    """

    def __init__(self, coords: np.ndarray, params: MoveParams | None = None, seed: int = 0,
                 closed: bool | None = None, ensemble: Ensemble | str | None = None):
        pos = np.array(coords, dtype=np.float64, order="C", copy=True)
        if pos.ndim != 2 or pos.shape[1] != 3:
            raise ValueError(f"coords must have shape (N, 3), got {pos.shape}")
        self.ensemble = ensemble_of(ensemble, closed)
        self.ensemble.validate()
        self.closed = self.ensemble.closed
        self.params = (params or MoveParams()).for_beads(pos.shape[0])
        self.params.validate(pos.shape[0])
        if self.closed:
            bonds = np.linalg.norm(np.roll(pos, -1, axis=0) - pos, axis=1)
        else:
            bonds = np.linalg.norm(np.diff(pos, axis=0), axis=1)
        if np.max(np.abs(bonds - 1.0)) > 1e-8:
            raise ValueError(
                f"bonds must have unit length (worst {np.max(np.abs(bonds - 1)):.2e}); "
                "use an embedding from stiffknots.knots"
            )
        self.pos = pos
        n = pos.shape[0]
        size = 1 << max(10, int(np.ceil(np.log2(8 * n))))
        self.head = np.empty(size, dtype=np.int64)
        self.nxt = np.empty(n, dtype=np.int64)
        self.prv = np.empty(n, dtype=np.int64)
        self.bucket = np.empty(n, dtype=np.int64)
        # neighbour lists of the single-bead kernel (run_single_moves), built on demand
        self.nbr = np.empty(NBR_PER_BEAD * n, dtype=np.int32)
        self.nbr_row = np.empty(2 * n, dtype=np.int64)
        self.nbr_ref = np.empty((n, 3), dtype=np.float64)
        self.nbr_meta = np.zeros(NB_NMETA, dtype=np.float64)
        self.counters = np.zeros(K.C_NCNT, dtype=np.int64)
        self.end_counters = np.zeros(K.C_NCNT, dtype=np.int64)
        self.slide_counters = np.zeros(K.C_NCNT, dtype=np.int64)
        self.rng = K.new_rng_state(seed)
        self._configure(self.params)
        viol = self.violation()
        if viol > 1e-12:
            raise ValueError(
                f"the chain violates the {self.params.exclusion} exclusion rule by {viol:.3g}"
            )

    def _configure(self, params: MoveParams) -> None:
        """Pack ``params`` for the kernels, size the scratch space, build the cell list and
        recompute the energy from scratch."""
        self.params = params
        self.ipar, self.fpar = params.arrays()
        if not self.closed:
            zlo, zhi = check_open_clamping(self.pos)
            self.ipar[K.I_OPEN] = 1
            self.fpar[K.F_ZLO] = zlo
            self.fpar[K.F_ZHI] = zhi
        n = self.n_beads
        rows = max(2, params.m_max)
        if self.ensemble.kind == "force":
            e = self.ensemble
            self.slide_m_max = n - 5 if e.slide_m_max is None else int(e.slide_m_max)
            rows = max(rows, e.end_m_max + 2, min(self.slide_m_max, n) + 3)
        self.newpos = np.empty((rows, 3), dtype=np.float64)
        self.nbr_meta[NB_RADIUS] = 0.0  # rebuild the neighbour lists at the next use
        K.cell_build(self.pos, params.cell, self.head, self.nxt, self.prv, self.bucket,
                     not self.closed)
        self.energy = self.recomputed_energy()
        self.total_energy = self.energy - self.force * self.extension

    def reconfigure(self, params: MoveParams, seed: int | None = None) -> None:
        """Continue from the current chain with new parameters (e.g. another energy mode): the
        energy is recomputed from scratch, the counters are reset and, if ``seed`` is given,
        the generator is re-seeded."""
        params = params.for_beads(self.n_beads)
        params.validate(self.n_beads)
        self._configure(params)
        for c in (self.counters, self.end_counters, self.slide_counters):
            c[:] = 0
        if seed is not None:
            self.rng[:] = K.new_rng_state(seed)

    def restore(self, coords: np.ndarray) -> None:
        """Replace the chain by ``coords`` (a chain this state held before, e.g. the lowest
        quenched one of a basin-hopping run): positions copied, cell list rebuilt, energy
        recomputed from scratch; parameters, counters and generator unchanged.

        This is a jump, not a motion: it is only used with a chain reached earlier by this
        state's own moves, so the knot type is the one the moves kept (none passes a strand
        through another).
        """
        pos = np.asarray(coords, dtype=np.float64)
        if pos.shape != self.pos.shape:
            raise ValueError(f"restore: shape {pos.shape}, expected {self.pos.shape}")
        self.pos[:] = pos
        self._configure(self.params)

    # -- observables -------------------------------------------------------------------------

    @property
    def n_beads(self) -> int:
        return self.pos.shape[0]

    @property
    def force(self) -> float:
        """F in C/b² (0 outside the fixed-force ensemble)."""
        return float(self.ensemble.force) if self.ensemble.kind == "force" else 0.0

    @property
    def extension(self) -> float:
        """Δz = z_{N−1} − z_0 of an open chain (0 if closed)."""
        if self.closed:
            return 0.0
        return float(self.pos[-1, 2] - self.pos[0, 2])

    @property
    def epsilon(self) -> float:
        """ε = E_d·N/C for a closed chain (paper §VII; bond length 1, so L = N); for an open
        one ε_e = E_d·L_e/C (paper §VIII)."""
        if self.closed:
            return self.energy * self.n_beads
        return self.energy * self.excess_length

    @property
    def excess_length(self) -> float:
        """L_e = ∫ds − ∫dz = (N − 1) − (z_{N−1} − z_0) for an open chain (0 if closed)."""
        if self.closed:
            return 0.0
        return float(self.n_beads - 1 - (self.pos[-1, 2] - self.pos[0, 2]))

    def turning_angles(self) -> np.ndarray:
        """θ_n at every joint (N for a closed chain, N − 2 for an open one)."""
        c = K.turning_cosines(self.pos, not self.closed)
        return np.arccos(np.clip(c, -1.0, 1.0))

    def recomputed_energy(self) -> float:
        """The energy recomputed from scratch (to compare with the incremental one)."""
        p = self.params
        return float(K.energy_chain(self.pos, not self.closed, ENERGY_MODELS.index(p.energy),
                                    int(p.power), float(p.energy_scale)))

    def recomputed_total(self) -> float:
        """E_d − F·Δz recomputed from scratch (E_d outside the fixed-force ensemble)."""
        return self.recomputed_energy() - self.force * self.extension

    def violation(self) -> float:
        """Worst violation of the exclusion rule (≤ 0: none), brute force."""
        return self.params.violation(self.pos, self.closed)

    def set_max_turn(self, theta: float | None) -> None:
        """Change the curvature limit θ_max of the running state (None: no limit)."""
        self.fpar[K.F_CMIN] = -2.0 if theta is None else float(np.cos(theta))

    @property
    def max_turn(self) -> float | None:
        """The current curvature limit θ_max (None: no limit)."""
        c = float(self.fpar[K.F_CMIN])
        return None if c < -1.0 else float(np.arccos(c))

    def acceptance(self) -> dict:
        out = {name: acceptance_block(self.counters, cls)
               for cls, name in ((0, "single"), (1, "multi"))}
        if self.ensemble.kind == "force":
            for c, cls, name in ((self.end_counters, 0, "pivot_top"),
                                 (self.end_counters, 1, "pivot_bottom"),
                                 (self.slide_counters, 0, "slide_top"),
                                 (self.slide_counters, 1, "slide_bottom")):
                out[name] = acceptance_block(c, cls)
        return out

    # -- moves -------------------------------------------------------------------------------

    @property
    def single_only(self) -> bool:
        """Is every crankshaft move the paper's single-bead move (m_max = 1 or p_single = 1)?"""
        return bool(self.ipar[K.I_MMAX] < 2 or self.fpar[K.F_PSINGLE] >= 1.0)

    def run_crankshafts(self, n_moves: int, temperature: float) -> float:
        """Crankshaft moves only (an open chain's ends stay fixed); returns ΔE_d.

        Runs of the paper's move alone go to :func:`run_single_moves` (neighbour lists):
        the same chain as :func:`run_moves` would give, faster."""
        if self.single_only:
            de = run_single_moves(self.pos, int(n_moves), float(temperature), self.ipar,
                                  self.fpar, self.head, self.nxt, self.prv, self.bucket,
                                  self.counters, self.rng, self.nbr, self.nbr_row,
                                  self.nbr_ref, self.nbr_meta)
        else:
            de = run_moves(self.pos, int(n_moves), float(temperature), self.ipar, self.fpar,
                           self.head, self.nxt, self.prv, self.bucket, self.newpos,
                           self.counters, self.rng)
        self.energy += de
        self.total_energy += de
        return de

    def _run_end_kernel(self, kernel, m_max: int, counters: np.ndarray, n_moves: int,
                        temperature: float) -> float:
        z0 = self.extension
        de = kernel(self.pos, int(n_moves), float(temperature), self.force, m_max, self.ipar,
                    self.fpar, self.head, self.nxt, self.prv, self.bucket, self.newpos,
                    counters, self.rng)
        self.total_energy += de
        self.energy += de + self.force * (self.extension - z0)
        return de

    def run_ends(self, n_moves: int, temperature: float) -> float:
        """Pivot end moves only (fixed-force ensemble); returns Δ(E_d − F·Δz)."""
        return self._run_end_kernel(run_end_moves, self.ensemble.end_m_max, self.end_counters,
                                    n_moves, temperature)

    def run_slides(self, n_moves: int, temperature: float) -> float:
        """Slide moves only (fixed-force ensemble); returns Δ(E_d − F·Δz)."""
        return self._run_end_kernel(run_slide_moves, self.slide_m_max, self.slide_counters,
                                    n_moves, temperature)

    def run(self, n_moves: int, temperature: float) -> float:
        """Attempt ``n_moves`` moves at ``temperature``; returns the change of the total energy.

        Closed chains and fixed extension: crankshafts. Fixed force: a fraction
        ``end_fraction`` of the moves are end moves (slides and pivots), interleaved with the
        crankshafts in blocks of ≈ END_BLOCK moves.
        """
        if self.ensemble.kind != "force":
            return self.run_crankshafts(n_moves, temperature)
        e = self.ensemble
        n_moves = int(n_moves)
        n_end = int(round(n_moves * e.end_fraction))
        n_slide = int(round(n_end * e.slide_fraction))
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
