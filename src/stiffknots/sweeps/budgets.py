"""Budgets of a sweep: how many replicas of how many attempted moves each (knot, model) gets.

A budget is a name for (replicas, moves per replica); every replica runs the default annealing
schedule of :class:`~stiffknots.engine.driver.AnnealSettings` (relaxation, then the paper's
power-law annealing, §VII) on those moves. The moves are part of every replica's settings,
hence of its store key: two budgets never share results, while a budget with more replicas
of the same moves reuses the replicas a smaller one stored (replica r's seed does not depend
on the number of replicas).

=========  ========  ============  ==================================================
budget     replicas  moves         CPU seconds per (knot, model) on one core, N = 150
=========  ========  ============  ==================================================
tiny       2         200,000       ≈ 0.3 — a smoke test of the machinery, nothing converges
small      2         5,000,000     ≈ 6 (measured 4.9–12.1 over 8 knots × 2 models)
default    4         30,000,000    ≈ 76 (measured 57–66 on 4 knots of n ≠ i, bead rule)
full       8         100,000,000   ≈ 500 (extrapolated)
=========  ========  ============  ==================================================

Measurements (``stiffknots atlas``, seed 0, CPU seconds of the replicas as the engine reports
them, on the shared 2-core machine): ``small`` on 3_1, 5_2, 6_2, 7_4, 8_19, 9_42, 10_1,
10_161 under both models — 32 replicas, 118.9 s for 160 M moves; ``default`` on 5_2, 6_2,
7_4, 10_1 under the bead rule — 16 replicas, 238.6 s for 480 M moves. Per million moves: the
knots with n ≠ i cost 0.43–0.66 s (0.50 at 30 M moves per replica), the n = i knots, whose
replicas end as circular braids, 0.71–1.21 s; the tube model costs ≈ 15 % more than the bead
rule. Through 10 crossings 46 of the 249 knots have n = i, so the mix costs ≈ 0.63 s per
million moves (:data:`MEASURED_CPU_SECONDS_PER_M_MOVES`). A sweep of every prime knot
through 10 crossings under both models (498 (knot, model) pairs) on 2 free cores then takes
about 26 min on ``small``, 5.3 h on ``default``, 35 h on ``full``, plus well under a second
of CPU per (knot, model) and worker to build its starts (seconds for the 80 starts).
"""

from __future__ import annotations

from dataclasses import dataclass

from stiffknots.errors import InvalidParameter
from stiffknots.problems import validate as V

__all__ = ["Budget", "BUDGETS", "budget_of", "MEASURED_CPU_SECONDS_PER_M_MOVES"]

#: CPU seconds per million attempted moves of one replica at N = 150 under the default
#: schedule, for the mix of knots through 10 crossings (module docstring).
MEASURED_CPU_SECONDS_PER_M_MOVES = 0.63


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
    """

    name: str
    replicas: int
    moves: int
    max_replicas: int | None = None

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
                "max_replicas": self.max_replicas or self.replicas}


BUDGETS: dict[str, Budget] = {
    "tiny": Budget("tiny", 2, 200_000),
    "small": Budget("small", 2, 5_000_000),
    "default": Budget("default", 2, 15_000_000, max_replicas=6),
    "full": Budget("full", 4, 60_000_000, max_replicas=12),
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
