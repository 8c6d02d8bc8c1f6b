"""The restricted-curvature problem (paper §IX D): the shortest knot whose curvature ≤ 1/R.

Discrete model
--------------
A closed chain of N unit bonds (length L = N). A turning angle θ between consecutive bonds
is the bend of the circle of radius r = 1/(2 sin(θ/2)) through the three beads (the beads
lie on it at unit chords), so a chain whose largest turning angle is θ* has curvature at most
1/R with R = 1/(2 sin(θ*/2)), and its length in units of R is

    L/R = 2 N sin(θ*/2).

For fixed N the shortest knot in units of R is the chain with the smallest θ*, so the search
minimises the largest turning angle of a chain of the knot type at fixed N — the ``tight``
plan of the engine (:mod:`stiffknots.engine.driver`):

* a continuation in p of the energy Σ ((1 − cos θ_n)/s)^p: p = 1 is the paper's bending
  energy, annealed as in §VII (a smooth shape of the knot), then p = 2, 4, …, 64, each annealed
  from the previous shape with s = 1 − cos θ₉₀ (θ₉₀ the 90th percentile of the angles, so the
  energies stay of order one). As p grows the sum is dominated by the largest angles and its
  minimum approaches the minimax. A direct start at large p jams: the sharp joints of the
  embedding dominate and nothing else can move (measured: 5_2 stays near L/R ≈ 29–34
  instead of 19.7);
* a ratchet quench: the limit θ_max is lowered to the current largest angle after every
  chunk, and the kernel rejects any move that would bend a joint beyond it (unless it
  straightens it), so θ* never grows again;
* the exclusion (bead or tube) is kept, as a regulariser of the thin knot: it must be small
  compared with R (d/R ≈ 4π d/N for a doubly covered circle), so refining N approaches the
  thin limit.

The bounds are 2π n R ≤ L† ≤ 2π min(7n/3, i) R (§IX D); for n = i (the trefoil: 4π R) the
minimum is the i-fold covered circle.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import ClassVar

import numpy as np

from stiffknots.engine.params import MoveParams
from stiffknots.engine.schedules import PAPER_POWER_LAW
from stiffknots.engine.settings import DEFAULT_POWERS, AnnealSettings
from stiffknots.problems import validate as V
from stiffknots.problems.base import Job, Problem, Replica, ReplicaSet, solve
from stiffknots.width import Width

DEFAULT_TIGHT_MOVES = 30_000_000
#: the default tube of the thin knot of §IX D (bond lengths): a regulariser, small against R
DEFAULT_TIGHT_W = 0.25


def length_over_R(theta_max: float, n_beads: int) -> float:
    """L/R = 2N sin(θ*/2) for a closed chain of N unit bonds with largest turning angle θ*."""
    return float(2.0 * n_beads * np.sin(theta_max / 2.0))


def radius_of_turn(theta: float) -> float:
    """Radius 1/(2 sin(θ/2)) of the circle through three beads at unit chords turning by θ."""
    return float(1.0 / (2.0 * np.sin(theta / 2.0)))


@dataclass
class TightResult(ReplicaSet):
    """Replicas of the restricted-curvature search for one knot, best (shortest) first."""

    problem: ClassVar[str] = "tightest"

    @property
    def length_over_R(self) -> float:
        return self.best.observables["length_over_R"]

    def physics(self) -> dict:
        ok = bool(self.replicas)
        th = self.best.max_turn if ok else None
        return {
            "length_over_R": self.length_over_R if ok else None,
            "theta_max": th,
            "R": radius_of_turn(th) if ok else None,
            "lower_bound": self.bounds.get("lower"),
            "upper_bound": self.bounds.get("upper"),
        }

    def chain_meta(self, r: Replica) -> dict:
        return super().chain_meta(r) | {"length_over_R": r.observables["length_over_R"]}


class Tightest(Problem):
    """The restricted-curvature search (§IX D); see :func:`tightest`."""

    result_type = TightResult

    def __init__(self, knot: str, beads: int = 150, moves: int = DEFAULT_TIGHT_MOVES,
                 replicas: int = 2, seed: int = 0, *, exclusion: str = "tube",
                 d: float | None = None, w: float | None = None,
                 powers: tuple[int, ...] = DEFAULT_POWERS,
                 start: str | Sequence[str] = "all"):
        from stiffknots.theory.bounds import restricted_curvature_bounds

        self._setup(knot, replicas, seed, beads)
        self.polish = False  # the power energy of §IX D is not the minimiser's E_d
        if not powers:
            V.integer("powers", None)
        powers = tuple(V.integer("powers", p, 1, 1024) for p in powers)
        if d is not None and exclusion == "bead":
            width = Width.bead(self.beads, d=d)
        else:
            width = V.width(self.beads, exclusion, w=w, default_w=DEFAULT_TIGHT_W)
        # uniform crankshaft lengths, as its defaults were measured
        params = MoveParams(m_law="uniform", **({} if d is None else {"d": d})).at_width(width)
        self.settings = AnnealSettings(moves=V.moves(moves),
                                       schedule=PAPER_POWER_LAW.for_beads(self.beads),
                                       params=params.for_beads(self.beads),
                                       plan="tight", powers=powers)
        self.settings.validate()
        self.settings.params.validate(self.beads)
        self._closed_starts(start)
        self._bounds = restricted_curvature_bounds(self.knot.bridge_number,
                                                   self.knot.braid_index, R=1.0)

    def jobs(self, first: int = 0) -> list[Job]:
        return self._replica_jobs(self.settings, lambda r: self.chains[self._start(r)],
                                  self._start, lambda r: self.codes[self._start(r)],
                                  first=first)

    def bounds(self) -> dict:
        b = self._bounds
        return {"lower": b.lower, "upper": b.upper, "attained_by": b.attained_by}

    def settings_dict(self) -> dict:
        return {"moves": self.settings.moves, "powers": list(self.settings.powers),
                "params": self.settings.params.as_dict(), "start": self.starts,
                "plan": "tight"}

    def observe(self, r: Replica) -> None:
        r.observables["length_over_R"] = length_over_R(r.max_turn, len(r.coords))

    def sort_key(self, r: Replica) -> float:
        return r.observables["length_over_R"]


def tightest(knot: str, beads: int = 150, moves: int = DEFAULT_TIGHT_MOVES, replicas: int = 2,
             seed: int = 0, *, exclusion: str = "tube", d: float | None = None,
             w: float | None = None, powers: tuple[int, ...] = DEFAULT_POWERS,
             workers: int | None = None,
             on_replica_done: Callable[[Replica], None] | None = None,
             start: str | Sequence[str] = "all") -> TightResult:
    """Minimal length L†/R of ``knot`` under the curvature limit 1/R (paper §IX D).

    Parameters
    ----------
    knot : str
        Knot name.
    beads : int
        N; finer chains approach the thin limit (the exclusion is fixed in bond lengths).
    moves : int
        Attempted moves per replica, shared equally by the stages and the final quench.
    replicas, seed, workers
        As for :func:`stiffknots.anneal`.
    exclusion, d, w
        Exclusion model and distances in bond lengths. The thin knot of §IX D
        has no thickness: the default is a thin tube, w = :data:`DEFAULT_TIGHT_W` = 0.25 (the
        paper's bead rule, d = 1/√2, is available and gives longer knots at a given N).
    powers : tuple of int
        The continuation p = 1 (the bending energy, annealed as in §VII), 2, 4, …, 64
        of the minimax energy Σ((1 − cos θ)/s)^p.
    start : str or sequence of str
        Starting embedding(s), as for :func:`stiffknots.anneal`: ``'all'`` (default: every
        start that exists for the knot, round-robin over the replicas), ``'braid'``, ``'cage'``
        (two-box rational knots; see :mod:`stiffknots.knots.starts`) or one per replica.

    Returns
    -------
    TightResult
        ``length_over_R`` of the best replica and the bounds 2πn ≤ L†/R ≤ 2π min(7n/3, i).
    """
    problem = Tightest(knot, beads, moves, replicas, seed, exclusion=exclusion, d=d, w=w,
                       powers=powers, start=start)
    return solve(problem, workers=workers, on_replica_done=on_replica_done)
