"""Parameters of a Monte Carlo run that the kernels read: the moves, the exclusion model, the
energy, and the ensemble (closed chain, open chain at fixed extension or at fixed force).

Plain frozen dataclasses; :meth:`MoveParams.arrays` packs them into the kernels' integer and
float parameter arrays (slots in :mod:`stiffknots.engine.prims`).
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass, replace

import numpy as np

from stiffknots.engine import prims as K
from stiffknots.errors import InvalidParameter
from stiffknots.width import BEAD_D, EXCLUSIONS, Width

EXCLUSION_MODELS = EXCLUSIONS
ENERGY_MODELS = ("bending", "power")
ENSEMBLES = ("closed", "extension", "force")
M_LAWS = ("uniform", "log", "mixed")
#: the largest force F (C/b²) of the ``force`` ensemble. The energy bookkeeping holds to 1e-9
#: up to F = 1e4 and fails at 1e6 (open 3_1: the term F·Δz swamps E_d); every force that
#: selects an excess length ≥ 8 bonds, (ε_e C/F)^½ ≥ 8, is below 50 for every knot of the
#: catalogue (ε_e ≤ 2π² i₁², i ≤ 13).
MAX_FORCE = 100.0

__all__ = ["ENERGY_MODELS", "ENSEMBLES", "EXCLUSION_MODELS", "MAX_FORCE", "Ensemble",
           "MoveParams"]


@dataclass(frozen=True)
class MoveParams:
    """Parameters of the crankshaft moves and of the exclusion model (units: bond length 1).

    Attributes
    ----------
    delta : float
        Angle of the paper's single-bead move (±delta), default π/100 (§VII).
    p_single : float
        Probability that a move is the paper's single-bead move.
    m_law : str
        How a multi-bead move draws its length m in [2, m_max]: ``"uniform"``, ``"log"``
        (log-uniform: as many moves at every scale of m, the mean cost ∝ m_max/ln m_max) or
        ``"mixed"`` (half of each, the default: more moves per second than the uniform law,
        and its large moves, which the 4_1's 4-fold cage needs to reach its lowest ε;
        docs/methods/moves.md).
    m_max : int or None
        Largest number of beads rotated by one multi-bead crankshaft move (≥ 1; 1 disables
        multi-bead moves and leaves exactly the paper's move). None (the default): N/2, set by
        :meth:`for_beads` — a whole loop of a doubly covered circle must be able to turn in
        its plane at any N (75 at the paper's N = 150).
    phi_max : float
        Largest rotation angle of a multi-bead move (radians).
    l_cap, l_min : float
        A multi-bead move first draws a displacement scale ℓ log-uniformly in
        [l_min, l_cap], then an angle uniform in ±min(phi_max, ℓ/ρ_max), ρ_max the largest
        distance of a moved bead from the axis; no point moves farther than l_cap.
    exclusion : str
        ``"bead"`` (no two beads at index distance ≥ 2 closer than ``d``; the paper's
        rule, d = 1/√2) or ``"tube"`` (no two segments sharing no bead closer than ``w``).
    d : float
        Bead exclusion distance.
    w : float
        Tube diameter (``tube`` model only).
    energy : str
        ``"bending"`` — the paper's E_d = Σ (1 − cos θ_n) (§VII) — or ``"power"`` —
        Σ (1 − cos θ_n)^power, whose minimum approaches the smallest achievable largest
        turning angle as ``power`` grows (the restricted-curvature search, §IX D).
    power : int
        Exponent of the ``"power"`` energy (integer ≥ 1).
    energy_scale : float
        The ``"power"`` energy is Σ ((1 − cos θ_n)/energy_scale)^power.
    max_turn : float or None
        Largest turning angle θ_max allowed at any joint (radians), or None for no
        limit; with unit bonds it is the curvature limit 1/R, R = 1/(2 sin(θ_max/2)).
    """

    delta: float = float(np.pi / 100)
    p_single: float = 0.5
    m_max: int | None = None
    m_law: str = "mixed"
    phi_max: float = 0.6
    l_cap: float = 0.5
    l_min: float = 0.03
    exclusion: str = "bead"
    d: float = BEAD_D
    w: float = BEAD_D
    energy: str = "bending"
    power: int = 8
    energy_scale: float = 1.0
    max_turn: float | None = None

    def validate(self, n_beads: int) -> None:
        """InvalidParameter (naming the parameter) unless every value is allowed for a chain
        of ``n_beads`` beads."""
        if self.exclusion not in EXCLUSION_MODELS:
            raise InvalidParameter("exclusion", self.exclusion,
                                   "one of " + ", ".join(EXCLUSION_MODELS))
        if self.m_law not in M_LAWS:
            raise InvalidParameter("m_law", self.m_law, "one of " + ", ".join(M_LAWS))
        if self.energy not in ENERGY_MODELS:
            raise InvalidParameter("energy", self.energy, "one of " + ", ".join(ENERGY_MODELS))
        for name, lo, hi in (("delta", 0, 0.5), ("p_single", 0, 1), ("phi_max", 0, math.pi),
                             ("l_cap", 0, 10), ("l_min", 0, 10), ("d", 0, 1), ("w", 0, 1),
                             ("energy_scale", 0, math.inf)):
            v = getattr(self, name)
            ok = isinstance(v, int | float) and math.isfinite(v) and lo <= v <= hi
            if not ok or (v == lo and name != "p_single") or (v == hi and name in ("d", "w")):
                raise InvalidParameter(name, v, f"a finite number in ({lo:g}, {hi:g})"
                                       if name != "p_single" else "in [0, 1]")
        if not self.l_min <= self.l_cap:
            raise InvalidParameter("l_min", self.l_min, f"≤ l_cap = {self.l_cap:g}")
        if n_beads < 8:
            raise InvalidParameter("beads", n_beads, "an integer ≥ 8")
        if self.m_max is None:
            raise InvalidParameter("m_max", None, "set (MoveParams.for_beads(N) sets N/2)")
        if int(self.m_max) != self.m_max or not 1 <= self.m_max <= 20_000:
            raise InvalidParameter("m_max", self.m_max, "an integer in [1, 20,000] (the kernel "
                                   "caps it at N − 3, N − 4 for an open chain)")
        if int(self.power) != self.power or not 1 <= self.power <= 1024:
            raise InvalidParameter("power", self.power, "an integer in [1, 1024]")
        if self.max_turn is not None and not (math.isfinite(self.max_turn)
                                              and 0 < self.max_turn < math.pi):
            raise InvalidParameter("max_turn", self.max_turn, "in (0, π) radians, or None")

    def as_dict(self) -> dict:
        return asdict(self)

    def width(self, beads: int, closed: bool = True) -> Width:
        """The width of these parameters at N = ``beads``: the exclusion model and its
        thickness (d for the bead rule, w for the tube)."""
        t = self.w if self.exclusion == "tube" else self.d
        return Width.of(self.exclusion, t, beads, closed=closed)

    def at_width(self, width: Width) -> MoveParams:
        """These parameters with the exclusion model and thickness of ``width`` (the other
        fields kept; the bead distance d stays when the model is the tube)."""
        if width.exclusion == "tube":
            return replace(self, exclusion="tube", w=width.thickness)
        return replace(self, exclusion="bead", d=width.thickness)

    def for_beads(self, n_beads: int) -> MoveParams:
        """These parameters for a chain of ``n_beads`` beads: ``m_max`` = N/2 if unset (the
        scale-free rule: sub-chains up to half the chain, whatever N)."""
        if self.m_max is not None:
            return self
        return replace(self, m_max=max(1, int(n_beads) // 2))

    @property
    def cell(self) -> float:
        """Cell side of the kernels' spatial hash: twice the reach of the single-bead move's
        checks (kernel docstring, Cell list).

        Any side gives the same decisions (every scan covers the cells that overlap the balls
        its tests need; tested against a brute-force scan), so it is chosen for speed alone:
        a crankshaft scans a box about every moved bead, and cells of twice the reach (3.06
        bond lengths for the bead rule, 4.41 for the tube w = 1/√2) visit fewer cells per
        bead than cells of the reach itself, and sides of 3 to 4 bond lengths were the
        fastest measured (docs/benchmarks.md)."""
        wt = self.w if self.exclusion == "tube" else 0.0
        return 2.0 * max(1.5 + max(wt, self.delta), self.d + 0.5)

    def violation(self, pos: np.ndarray, closed: bool = True) -> float:
        """The worst violation of this exclusion rule by the chain ``pos`` (≤ 0: none),
        brute force (:func:`~stiffknots.engine.prims.check_state`)."""
        mode = EXCLUSION_MODELS.index(self.exclusion)
        return float(K.check_state(pos, mode, self.d, self.w, not closed))

    def arrays(self) -> tuple[np.ndarray, np.ndarray]:
        """The kernels' integer and float parameter arrays (slots in
        :mod:`stiffknots.engine.prims`)."""
        ip = np.zeros(K.I_NIPAR, dtype=np.int64)
        fp = np.zeros(K.F_NFPAR, dtype=np.float64)
        ip[K.I_MODE] = EXCLUSION_MODELS.index(self.exclusion)
        ip[K.I_MMAX] = self.m_max
        ip[K.I_MLAW] = M_LAWS.index(self.m_law)
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


@dataclass(frozen=True)
class Ensemble:
    """The statistical ensemble of a chain (paper §VII for closed knots, §VIII for open ones).

    Attributes
    ----------
    kind : str
        ``"closed"`` — a closed chain (a knot); ``"extension"`` — an open chain whose two
        end segments are clamped on the z axis, so that Δz and the excess length
        L_e = (N − 1) − Δz are fixed (the force term −F·Δz is then a constant); ``"force"`` —
        the same open chain whose ends slide along z under the pulling force ``force``: the
        energy is E_d − F·Δz and L_e is measured (end moves of
        :mod:`stiffknots.engine.force_kernel`).
    force : float
        F in C/b² (``force`` ensemble only).
    end_fraction : float
        Fraction of the attempted moves that move an end (slides and pivots).
    slide_fraction : float
        Fraction of the end moves that are slides (the others are pivots).
    end_m_max : int
        Largest number of beads rotated by a pivot move (≥ 1).
    slide_m_max : int or None
        Largest number of free beads translated by a slide move (None: all).
    """

    kind: str = "closed"
    force: float = 0.0
    end_fraction: float = 0.1
    slide_fraction: float = 0.8
    end_m_max: int = 30
    slide_m_max: int | None = None

    def validate(self) -> None:
        if self.kind not in ENSEMBLES:
            raise ValueError(f"unknown ensemble {self.kind!r}; allowed: {', '.join(ENSEMBLES)}")
        if self.kind != "force":
            return
        f = self.force
        if not (isinstance(f, int | float) and math.isfinite(f) and 0 <= f <= MAX_FORCE):
            raise InvalidParameter("force", f, f"a finite number in [0, {MAX_FORCE:g}] C/b²")
        if not 0 <= self.end_fraction <= 1:
            raise ValueError(f"end_fraction must be in [0, 1], got {self.end_fraction}")
        if not 0 <= self.slide_fraction <= 1:
            raise ValueError(f"slide_fraction must be in [0, 1], got {self.slide_fraction}")
        if int(self.end_m_max) != self.end_m_max or self.end_m_max < 1:
            raise ValueError(f"end_m_max must be an integer ≥ 1, got {self.end_m_max}")
        if self.slide_m_max is not None and (int(self.slide_m_max) != self.slide_m_max
                                             or self.slide_m_max < 0):
            raise ValueError(f"slide_m_max must be an integer ≥ 0, got {self.slide_m_max}")

    @property
    def closed(self) -> bool:
        return self.kind == "closed"

    def as_dict(self) -> dict:
        if self.kind != "force":
            return {"kind": self.kind}
        return asdict(self)


def ensemble_of(ensemble: Ensemble | str | None, closed: bool | None = None) -> Ensemble:
    """An :class:`Ensemble` from an ensemble, its kind, or the older ``closed`` flag."""
    if isinstance(ensemble, Ensemble):
        return ensemble
    if isinstance(ensemble, str):
        return Ensemble(kind=ensemble)
    if closed is None or closed:
        return Ensemble("closed")
    return Ensemble("extension")
