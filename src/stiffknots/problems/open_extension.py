"""Open knots under tension (paper §VIII): anneal at fixed excess length, measure the tension.

An open knot is a chain whose two end segments are clamped on the z axis, pointing along −z
and +z (:mod:`stiffknots.knots.open_embedding`). The kernel keeps the ends fixed, so the
end-to-end distance Δz and the excess length L_e = ∫ds − ∫dz = (N − 1) − Δz are fixed: this
is the fixed-extension ensemble. The force term −F·Δz of the fixed-force energy is then a
constant, and the tension is *measured*:

* from the scaling of the elastic energy, μ = E/L_e (paper §VIII: E = ε_e C/L_e, and
  μ = −dE/dL_e = ε_e C/L_e² = E/L_e), and
* independently, from the slope of E against L_e over a scan of excess lengths
  (:func:`tension_scan`, finite differences), which checks the relation above.

Fixed force F and fixed extension are Legendre-conjugate at T → 0: the excess length a force
F selects is L_e(F) = (ε_e C/F)^{1/2} (:func:`excess_length_for_force`).

Units: bond length b = 1 and bending rigidity C = 1, so μ is in C/b² and ε_e = E·L_e/C is
dimensionless (the paper's eq. (41) prints "ε_e = E/L_e", a misprint for E·L_e/C). The bounds
are 2π²n₁² ≤ ε_e ≤ 2π² min(α²n₁², i₁²), n₁ = n − 1, i₁ = i − 1 (eq. (45), with the α²
misprint fixed; see :func:`stiffknots.theory.bounds.open_bounds`).
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from typing import ClassVar

import numpy as np

from stiffknots._version import __version__
from stiffknots.analysis.open_shape import open_shape
from stiffknots.engine.driver import AnnealSettings
from stiffknots.engine.params import Ensemble, MoveParams
from stiffknots.engine.schedules import PAPER_POWER_LAW, Schedule
from stiffknots.errors import EmbeddingError, InvalidParameter
from stiffknots.problems import validate as V
from stiffknots.problems.base import Job, Problem, Replica, ReplicaSet, solve, start_code
from stiffknots.width import Width

DEFAULT_OPEN_MOVES = 30_000_000
#: The default tube diameter of open knots (bond units): w = 0.05 at N ≈ 150 is w/L ≈ 3·10⁻⁴.
#: The paper's bead rule (d = 1/√2) is a thick tube for an open knot: its loop of ~L_e/4 beads
#: is only ~20 bead diameters around, and 3_1 ends at ε_e ≈ 25.7, 30 % above the thin limit
#: 2π² of §VIII; with this tube the defaults give ε_e within ~3 % (measured: 20.33).
DEFAULT_OPEN_W = 0.05


#: crankshaft lengths of open chains: uniform, the law their defaults were measured with
#: (the closed knots' default is ``"mixed"``, :class:`MoveParams`)
OPEN_M_LAW = "uniform"


def default_open_params() -> MoveParams:
    """The default exclusion of open knots: a thin tube, w = :data:`DEFAULT_OPEN_W`."""
    return MoveParams(exclusion="tube", w=DEFAULT_OPEN_W, m_law=OPEN_M_LAW)


def open_params(exclusion: str = "tube", *, w: float | None = None,
                w_over_L: float | None = None, m_max: int | None = None  # noqa: N803
                ) -> MoveParams:
    """The move parameters of open knots from width options, cross-checked
    (:func:`~stiffknots.problems.validate.width_model`): the tube of diameter ``w`` (default
    :data:`DEFAULT_OPEN_W`) or the bead rule. A diameter given as ``w_over_L`` is set by each
    problem for its own chain (``w_over_L=``: N is the embedding's)."""
    model = V.width_model(exclusion, w=w, w_over_L=w_over_L)
    if model == "tube" and w is None and w_over_L is None:
        w = DEFAULT_OPEN_W
    return MoveParams(exclusion=model, m_max=m_max, m_law=OPEN_M_LAW,
                      **({} if w is None else {"w": w}))


def with_w_over_L(params: MoveParams, w_over_L: float | None, beads: int  # noqa: N802, N803
                  ) -> MoveParams:
    """``params`` with the tube w = (w/L)·(N − 1) of an open chain of ``beads`` beads (its
    contour length L = N − 1 bonds), or unchanged when ``w_over_L`` is None."""
    if w_over_L is None:
        return params
    return params.at_width(Width.tube(beads, w_over_L=w_over_L, closed=False))
TWO_PI2 = 2.0 * np.pi**2


def excess_length_for_force(eps_e: float, force: float, C: float = 1.0) -> float:
    """The excess length a tension F selects at equilibrium: L_e = (ε_e C/F)^{1/2} (§VIII)."""
    V.number("force", force, 0, lo_open=True)
    return float(np.sqrt(eps_e * C / force))


@dataclass
class OpenResult(ReplicaSet):
    """Replicas of one open knot at one excess length, best (lowest E_d) first."""

    problem: ClassVar[str] = "open"
    closed: ClassVar[bool] = False
    excess_length: float = 0.0

    @property
    def eps_e(self) -> float:
        """ε_e = E·L_e/C of the best replica (paper §VIII)."""
        return self.best.epsilon

    @property
    def energy(self) -> float:
        return self.best.energy

    @property
    def tension(self) -> float:
        """μ = E/L_e (in C/b²) of the best replica (paper §VIII)."""
        return self.best.energy / self.best.excess_length

    def shape(self) -> dict:
        return open_shape(self.best.coords)

    def physics(self) -> dict:
        ok = bool(self.replicas)
        shape = self.shape() if ok else {"label": None, "features": {}}
        return {
            "excess_length": self.best.excess_length if ok else self.excess_length,
            "energy": self.energy if ok else None,
            "eps_e": self.eps_e if ok else None,
            "tension": self.tension if ok else None,
            "shape": shape["label"],
            "shape_features": shape["features"],
        }

    def chain_meta(self, r: Replica) -> dict:
        return super().chain_meta(r) | {"eps_e": r.epsilon, "excess_length": r.excess_length}


def open_chain(knot, excess_length: int, seed: int = 0) -> np.ndarray:
    """The starting chain of an open knot (a catalogue entry or name) with the given (integer)
    excess length."""
    from stiffknots.knots.catalogue import Knot, get_knot
    from stiffknots.knots.open_embedding import embed_open

    k = knot if isinstance(knot, Knot) else get_knot(knot)
    if not k.braid_word:
        raise EmbeddingError(f"{k.name} has no braid word in the catalogue; cannot embed it open")
    le = V.integer("excess_length", excess_length, V.MIN_EXCESS_LENGTH, V.MAX_EXCESS_LENGTH)
    try:
        return embed_open(k.braid_word, k.braid_strands, le, expected=k.name, seed=seed)
    except EmbeddingError as exc:
        # the closed chain cut open has L_e beads (one arm bond on each side, §VIII)
        msg = (str(exc).replace(" beads are too few", " bonds of excess length are too few")
               .replace("least number of beads", "least excess length"))
        raise EmbeddingError(f"{k.name}: {msg}") from None


class OpenExtension(Problem):
    """An open knot at fixed excess length (§VIII); see :func:`anneal_open`."""

    result_type = OpenResult

    def __init__(self, knot: str, excess_length: int = 80, moves: int = DEFAULT_OPEN_MOVES,
                 replicas: int = 2, seed: int = 0, *, params: MoveParams | None = None,
                 schedule: Schedule | None = None, quench_fraction: float = 0.1,
                 polish: bool = True, w_over_L: float | None = None):  # noqa: N803
        from stiffknots.theory.bounds import open_bounds

        self._setup(knot, replicas, seed)
        self.polish = bool(polish)
        self.excess_length = V.integer("excess_length", excess_length, V.MIN_EXCESS_LENGTH,
                                       V.MAX_EXCESS_LENGTH)
        self.coords = open_chain(self.knot, self.excess_length, seed=self.seed)
        self.beads = len(self.coords)
        params = with_w_over_L(params or default_open_params(), w_over_L, self.beads)
        self.settings = AnnealSettings(moves=V.moves(moves),
                                       schedule=schedule or PAPER_POWER_LAW.for_beads(self.beads),
                                       params=params.for_beads(self.beads),
                                       quench_fraction=quench_fraction,
                                       ensemble=Ensemble("extension"))
        self.settings.validate()
        self.settings.params.validate(self.beads)
        self.code = start_code(self.knot_name, self.coords, False, "open")
        self._bounds = open_bounds(self.knot.bridge_number, self.knot.braid_index)

    def jobs(self, first: int = 0) -> list[Job]:
        return self._replica_jobs(self.settings, lambda r: self.coords, lambda r: "open",
                                  lambda r: self.code, first=first)

    def state_of(self, r: Replica) -> tuple[str, float]:
        return open_shape(r.coords)["label"], self.sort_key(r)

    def bounds(self) -> dict:
        return {"eps_e_lower": self._bounds.lower, "eps_e_upper": self._bounds.upper}

    def settings_dict(self) -> dict:
        return self.settings.as_dict() | {"polish": self.polish}

    def sort_key(self, r: Replica) -> float:
        return r.energy

    def result_fields(self, replicas):
        return {"excess_length": float(self.excess_length)}


def anneal_open(knot: str, excess_length: int = 80, moves: int = DEFAULT_OPEN_MOVES,
                replicas: int = 2, seed: int = 0, *, params: MoveParams | None = None,
                schedule: Schedule | None = None, workers: int | None = None,
                quench_fraction: float = 0.1,
                on_replica_done: Callable[[Replica], None] | None = None,
                polish: bool = True) -> OpenResult:
    """Anneal an open knot at fixed excess length L_e (paper §VIII) and verify it.

    Parameters
    ----------
    knot : str
        Knot name ('3_1', '4_1', …).
    excess_length : int
        L_e in bond lengths (integer in [8, 10000]; the knot needs a minimum,
        reported if too small).
    moves, replicas, seed, params, schedule, workers, quench_fraction, on_replica_done
        As for :func:`stiffknots.anneal`. ``params.exclusion = "tube"`` with a small ``w``
        approaches the thin limit.

    Returns
    -------
    OpenResult
        Replicas sorted by energy; ``eps_e``, ``tension``, ``shape()``.

    Raises
    ------
    TopologyChangedError
        If the closure along z of any replica is not the requested knot (never expected).
    """
    problem = OpenExtension(knot, excess_length, moves, replicas, seed, params=params,
                            schedule=schedule, quench_fraction=quench_fraction, polish=polish)
    return solve(problem, workers=workers, on_replica_done=on_replica_done)


@dataclass
class TensionScan:
    """μ against L_e for one knot (paper §VIII) and its fits."""

    knot: str
    n: int | None
    i: int | None
    points: list[dict]
    bounds: dict
    version: str = __version__
    results: list = field(default_factory=list, repr=False)

    @property
    def fit_eps_e(self) -> float:
        """Least-squares slope of μ against 1/L_e² through the origin: μ L_e²/C."""
        x = np.array([1 / p["excess_length"] ** 2 for p in self.points])
        y = np.array([p["tension"] for p in self.points])
        return float((x @ y) / (x @ x))

    def finite_differences(self) -> list[dict]:
        """:func:`finite_differences` of the scan's points."""
        return finite_differences(self.points)

    def to_dict(self) -> dict:
        return {"knot": self.knot, "n": self.n, "i": self.i, "points": self.points,
                "fit_eps_e": self.fit_eps_e, "finite_differences": self.finite_differences(),
                "bounds": self.bounds, "version": self.version}


def finite_differences(points: list[dict]) -> list[dict]:
    """μ = −dE/dL_e between neighbouring excess lengths, next to E/L_e at the midpoint
    (the paper's relation μ = E/L_e, checked by an independent estimate, §VIII)."""
    pts = sorted(points, key=lambda p: p["excess_length"])
    out = []
    for a, b in zip(pts, pts[1:], strict=False):
        la, lb = a["excess_length"], b["excess_length"]
        mu_fd = -(b["energy"] - a["energy"]) / (lb - la)
        mid = float(np.sqrt(la * lb))
        # E/L_e at the geometric midpoint, with E ∝ 1/L_e interpolated
        mu_rel = float(np.sqrt(a["tension"] * b["tension"]))
        out.append({"L_e": mid, "mu_finite_difference": mu_fd, "mu_E_over_L": mu_rel})
    return out


def scan_point(res: OpenResult, seed: int) -> dict:
    """One point of a tension scan from the result at one excess length."""
    d = res.to_dict()
    return ({key: d[key] for key in ("excess_length", "energy", "eps_e", "tension", "shape",
                                     "beads", "wall_time", "knot_verified")}
            | {"seed": seed, "min_segment_distance": res.best.min_segment_distance,
               "shape_features": d["shape_features"]})


def tension_scan(knot: str, excess_lengths: Sequence[int], moves: int = DEFAULT_OPEN_MOVES,
                 replicas: int = 2, seed: int = 0, *, params: MoveParams | None = None,
                 workers: int | None = None,
                 progress: Callable[[OpenResult], None] | None = None,
                 on_replica_done: Callable[[Replica], None] | None = None) -> TensionScan:
    """Anneal ``knot`` open at every excess length and collect (L_e, E, ε_e, μ, shape)."""
    from stiffknots.knots.catalogue import get_knot
    from stiffknots.theory.bounds import open_bounds

    if not excess_lengths:
        raise InvalidParameter("excess_lengths", list(excess_lengths), "at least one value")
    problems = [OpenExtension(knot, le, moves, replicas, seed, params=params)
                for le in excess_lengths]  # every input checked before any work
    k = get_knot(knot)
    pts, results = [], []
    for p in problems:
        res = solve(p, workers=workers, on_replica_done=on_replica_done)
        results.append(res)
        if not res.replicas:  # interrupted before a replica finished
            break
        pts.append(scan_point(res, seed))
        if progress:
            progress(res)
    b = open_bounds(k.bridge_number, k.braid_index)
    return TensionScan(knot=k.name, n=k.bridge_number, i=k.braid_index, points=pts,
                       bounds={"eps_e_lower": b.lower, "eps_e_upper": b.upper},
                       results=results)
