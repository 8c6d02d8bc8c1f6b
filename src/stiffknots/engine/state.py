"""The Monte Carlo state: a closed chain, its cell list and its move parameters.

Thin Python layer over :mod:`stiffknots.engine.kernel` (validation here, computation there).
"""

from __future__ import annotations

from dataclasses import asdict, dataclass

import numpy as np

from stiffknots.engine import kernel as K

EXCLUSION_MODELS = ("bead", "tube")
ENERGY_MODELS = ("bending", "power")


@dataclass(frozen=True)
class MoveParams:
    """Parameters of the crankshaft moves and of the exclusion model (units: bond length 1).

    Attributes
    ----------
    delta : angle of the paper's single-bead move (±delta), default π/100 (§VII).
    p_single : probability that a move is the paper's single-bead move.
    m_max : largest number of beads rotated by one multi-bead crankshaft move (≥ 1; 1 disables
        multi-bead moves and leaves exactly the paper's move).
    phi_max : largest rotation angle of a multi-bead move (radians).
    l_cap, l_min : a multi-bead move first draws a displacement scale ℓ log-uniformly in
        [l_min, l_cap], then an angle uniform in ±min(phi_max, ℓ/ρ_max), ρ_max the largest
        distance of a moved bead from the axis; no point moves farther than l_cap.
    exclusion : ``"bead"`` (no two beads at index distance ≥ 2 closer than ``d``; the paper's
        rule, d = 1/√2) or ``"tube"`` (no two segments sharing no bead closer than ``w``).
    d : bead exclusion distance.
    w : tube diameter (``tube`` model only).
    energy : ``"bending"`` — the paper's E_d = Σ (1 − cos θ_n) (§VII) — or ``"power"`` —
        Σ (1 − cos θ_n)^power, whose minimum approaches the smallest achievable largest
        turning angle as ``power`` grows (the restricted-curvature search, §IX.D).
    power : exponent of the ``"power"`` energy (integer ≥ 1).
    energy_scale : the ``"power"`` energy is Σ ((1 − cos θ_n)/energy_scale)^power.
    max_turn : largest turning angle θ_max allowed at any joint (radians), or None for no
        limit; with unit bonds it is the curvature limit 1/R, R = 1/(2 sin(θ_max/2)).
    """

    delta: float = float(np.pi / 100)
    p_single: float = 0.5
    m_max: int = 75
    phi_max: float = 0.6
    l_cap: float = 0.5
    l_min: float = 0.03
    exclusion: str = "bead"
    d: float = float(1 / np.sqrt(2))
    w: float = float(1 / np.sqrt(2))
    energy: str = "bending"
    power: int = 8
    energy_scale: float = 1.0
    max_turn: float | None = None

    def validate(self, n_beads: int) -> None:
        if self.exclusion not in EXCLUSION_MODELS:
            raise ValueError(
                f"unknown exclusion model {self.exclusion!r}; "
                f"allowed: {', '.join(EXCLUSION_MODELS)}"
            )
        if not 0 < self.delta < 0.5:
            raise ValueError(f"delta must be in (0, 0.5) rad, got {self.delta}")
        if not 0 <= self.p_single <= 1:
            raise ValueError(f"p_single must be in [0, 1], got {self.p_single}")
        if self.m_max < 1:
            raise ValueError(f"m_max must be ≥ 1, got {self.m_max}")
        if not 0 < self.l_min <= self.l_cap:
            raise ValueError(f"need 0 < l_min ≤ l_cap, got {self.l_min}, {self.l_cap}")
        if not 0 < self.d < 1 or not 0 < self.w < 1:
            raise ValueError("exclusion distances d and w must lie in (0, 1) bond lengths")
        if self.energy not in ENERGY_MODELS:
            raise ValueError(
                f"unknown energy {self.energy!r}; allowed: {', '.join(ENERGY_MODELS)}"
            )
        if int(self.power) != self.power or self.power < 1:
            raise ValueError(f"power must be an integer ≥ 1, got {self.power}")
        if not self.energy_scale > 0:
            raise ValueError(f"energy_scale must be > 0, got {self.energy_scale}")
        if self.max_turn is not None and not 0 < self.max_turn < np.pi:
            raise ValueError(f"max_turn must be in (0, π) radians or None, got {self.max_turn}")
        if n_beads < 8:
            raise ValueError(f"a chain needs at least 8 beads, got {n_beads}")

    def as_dict(self) -> dict:
        return asdict(self)

    @property
    def cell(self) -> float:
        """Cell side: the reach of the single-bead move's checks (see kernel docstring)."""
        wt = self.w if self.exclusion == "tube" else 0.0
        return max(1.5 + max(wt, self.delta), self.d + 0.5)

    def arrays(self) -> tuple[np.ndarray, np.ndarray]:
        ip = np.zeros(K.I_NIPAR, dtype=np.int64)
        fp = np.zeros(K.F_NFPAR, dtype=np.float64)
        ip[K.I_MODE] = EXCLUSION_MODELS.index(self.exclusion)
        ip[K.I_MMAX] = self.m_max
        fp[K.F_DELTA] = self.delta
        fp[K.F_PSINGLE] = self.p_single if self.m_max > 1 else 1.0
        fp[K.F_PHIMAX] = self.phi_max
        fp[K.F_LCAP] = self.l_cap
        fp[K.F_LMIN] = self.l_min
        fp[K.F_D] = self.d
        fp[K.F_W] = self.w if self.exclusion == "tube" else 0.0
        fp[K.F_CELL] = self.cell
        ip[K.I_EMODE] = ENERGY_MODELS.index(self.energy)
        ip[K.I_POWER] = int(self.power)
        fp[K.F_EINV] = float(self.energy_scale)
        fp[K.F_CMIN] = -2.0 if self.max_turn is None else float(np.cos(self.max_turn))
        return ip, fp


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
    """A unit-bond chain prepared for the kernel.

    Parameters
    ----------
    coords : (N, 3) chain with unit bonds that satisfies the exclusion model.
    params : move, exclusion and energy parameters.
    seed : seed of the kernel's generator.
    closed : False for an open chain clamped on the z axis (see :func:`check_open_clamping`;
        the excess length L_e = (N−1) − Δz is then fixed, paper §VIII).
    """

    def __init__(self, coords: np.ndarray, params: MoveParams | None = None, seed: int = 0,
                 closed: bool = True):
        pos = np.array(coords, dtype=np.float64, order="C", copy=True)
        if pos.ndim != 2 or pos.shape[1] != 3:
            raise ValueError(f"coords must have shape (N, 3), got {pos.shape}")
        self.params = params or MoveParams()
        self.params.validate(pos.shape[0])
        self.closed = bool(closed)
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
        self.ipar, self.fpar = self.params.arrays()
        if not self.closed:
            zlo, zhi = check_open_clamping(pos)
            self.ipar[K.I_OPEN] = 1
            self.fpar[K.F_ZLO] = zlo
            self.fpar[K.F_ZHI] = zhi
        n = pos.shape[0]
        size = 1 << max(10, int(np.ceil(np.log2(8 * n))))
        self.head = np.empty(size, dtype=np.int64)
        self.nxt = np.empty(n, dtype=np.int64)
        self.prv = np.empty(n, dtype=np.int64)
        self.bucket = np.empty(n, dtype=np.int64)
        self.newpos = np.empty((max(2, self.params.m_max), 3), dtype=np.float64)
        self.counters = np.zeros(K.C_NCNT, dtype=np.int64)
        self.rng = K.new_rng_state(seed)
        K.cell_build(self.pos, self.params.cell, self.head, self.nxt, self.prv, self.bucket,
                     not self.closed)
        self.energy = self.recomputed_energy()
        viol = self.violation()
        if viol > 1e-12:
            raise ValueError(
                f"the chain violates the {self.params.exclusion} exclusion rule by {viol:.3g}"
            )

    @property
    def n_beads(self) -> int:
        return self.pos.shape[0]

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

    def run(self, n_moves: int, temperature: float) -> float:
        """Attempt ``n_moves`` moves at ``temperature``; returns the energy change."""
        de = K.run_moves(self.pos, int(n_moves), float(temperature), self.ipar, self.fpar,
                         self.head, self.nxt, self.prv, self.bucket, self.newpos, self.counters,
                         self.rng)
        self.energy += de
        return de

    def recomputed_energy(self) -> float:
        """The energy recomputed from scratch (to compare with the incremental one)."""
        p = self.params
        return float(K.energy_chain(self.pos, not self.closed, ENERGY_MODELS.index(p.energy),
                                    int(p.power), float(p.energy_scale)))

    def violation(self) -> float:
        p = self.params
        mode = EXCLUSION_MODELS.index(p.exclusion)
        return float(K.check_state(self.pos, mode, p.d, p.w, not self.closed))

    def set_max_turn(self, theta: float | None) -> None:
        """Change the curvature limit θ_max of the running state (None: no limit)."""
        self.fpar[K.F_CMIN] = -2.0 if theta is None else float(np.cos(theta))

    def acceptance(self) -> dict:
        return {name: acceptance_block(self.counters, cls)
                for cls, name in ((0, "single"), (1, "multi"))}
