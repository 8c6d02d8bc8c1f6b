"""Budgets of a sweep: how many replicas of how many attempted moves each (knot, model) gets.

A budget is a name for (replicas, moves per replica, most replicas); every replica runs the
default annealing schedule of :class:`~stiffknots.engine.driver.AnnealSettings` (relaxation,
then geometric annealing from T = 0.1, §VII) on those moves and is polished. The moves are
part of every replica's settings, hence of its store key: two budgets never share results,
while a budget with more replicas of the same moves reuses the replicas a smaller one stored
(replica r's seed does not depend on the number of replicas). A (knot, model) whose ground
state has not converged once its replicas have ended gets two more, up to ``max_replicas``
(:func:`stiffknots.sweeps.run.run_sweep`): easy knots stop at two, hard ones get more; a tube
ensemble still not converged then gets up to ``legs`` continuation legs, each continuing its
second-lowest search by basin hops (:mod:`stiffknots.sweeps.legs`).

=========  ========  ============  ============  ====  ====================================
budget     replicas  moves         most          legs  CPU seconds per (knot, model), N = 150
=========  ========  ============  ============  ====  ====================================
tiny       2         200,000       2             0     ≈ 1 — a smoke test of the machinery
small      2         5,000,000     2             0     ≈ 10
default    2         15,000,000    6             2     ≈ 20 converged at 2, ≈ 60 at 6 replicas
                                                       (a tube leg: ≈ 10–45 more)
full       4         60,000,000    12            2     ≈ 160 at 4 replicas, ≈ 480 at 12
=========  ========  ============  ============  ====  ====================================

Measurements behind the default row (2026-11-29, ``bench/defaults_survey.py``: the same
replicas — 15 M moves, polished — through ``stiffknots anneal``, 35 knots through 8
crossings, bead rule): 7–13 CPU seconds per replica; about half the knots converge with
their first two replicas. A sweep of every prime knot through 10 crossings under both models
(498 (knot, model) pairs) on 2 free cores then takes about 3 h on ``default`` (projected from
10_1 … 10_8: 351 s, 2026-12-03, with every tube replica seeding a bead replica, which spares
the bead ensembles most added replicas; the 249-knot run has not been made in one piece on
this machine: the README says what has been run), 45 min on ``small``. Before 2026-11-29
``default`` was 4 × 30 M moves of the uniform-length crankshafts (≈ 76 CPU s per pair, 5.3 h).
"""

from __future__ import annotations

from dataclasses import dataclass

from stiffknots.errors import InvalidParameter
from stiffknots.problems import validate as V

__all__ = ["Budget", "BUDGETS", "budget_of", "MEASURED_CPU_SECONDS_PER_M_MOVES"]

#: CPU seconds per million attempted moves of one replica at N = 150 under the default
#: schedule, its polish included: 7–13 CPU s per 15 M-move replica over the knots through 8
#: crossings (module docstring), ≈ 10/15.
MEASURED_CPU_SECONDS_PER_M_MOVES = 0.67


@dataclass(frozen=True)
class Budget:
    """Replicas and attempted moves per replica of every (knot, model) of a sweep.

    Attributes
    ----------
    name : str
        ``tiny``, ``small``, ``default``, ``full`` or ``custom``.
    replicas : int
        Independent replicas per (knot, model) (≥ 1).
    moves : int
        Attempted moves per replica (≥ 1000).
    max_replicas : int or None
        Replicas are added, two at a time, to a (knot, model) whose ground state has not
        converged, up to this many in all (None: ``replicas``, none added).
    legs : int
        Then, while it has not converged, up to this many continuation legs, one at a time,
        each continuing the second-lowest search by basin hops (:mod:`stiffknots.sweeps.legs`).
    """

    name: str
    replicas: int
    moves: int
    max_replicas: int | None = None
    legs: int = 0

    def validate(self) -> Budget:
        """Return self, or raise :class:`InvalidParameter` for a bad count (the limits of
        :mod:`stiffknots.problems.validate`)."""
        V.replicas(self.replicas)
        V.moves(self.moves)
        return self

    def cpu_seconds(self) -> float:
        """Estimated CPU seconds of one (knot, model) on one core (N = 150)."""
        return self.replicas * self.moves * 1e-6 * MEASURED_CPU_SECONDS_PER_M_MOVES

    def as_dict(self) -> dict:
        return {"name": self.name, "replicas": self.replicas, "moves": self.moves,
                "max_replicas": self.max_replicas or self.replicas, "legs": self.legs}


BUDGETS: dict[str, Budget] = {
    "tiny": Budget("tiny", 2, 200_000),
    "small": Budget("small", 2, 5_000_000),
    "default": Budget("default", 2, 15_000_000, max_replicas=6, legs=2),
    "full": Budget("full", 4, 60_000_000, max_replicas=12, legs=2),
}


def budget_of(name: str, *, replicas: int | None = None, moves: int | None = None) -> Budget:
    """The named budget, with ``replicas`` or ``moves`` overridden where given (the name then
    becomes ``custom``).

    Raises
    ------
    InvalidParameter
        An unknown name (the message lists the budgets) or a bad count.
    """
    if name not in BUDGETS:
        raise InvalidParameter("budget", name, "one of " + ", ".join(BUDGETS))
    b = BUDGETS[name]
    if replicas is None and moves is None:
        return b
    return Budget("custom", b.replicas if replicas is None else replicas,
                  b.moves if moves is None else moves).validate()
