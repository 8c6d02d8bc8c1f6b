"""The settings of a replica's run: everything besides its starting chain and seed (§VII).

:class:`AnnealSettings` names the ensemble (a closed chain, or an open one at fixed extension
or at fixed force, §VIII), the moves and the energy (:class:`~stiffknots.engine.params.MoveParams`),
the temperature schedule (:class:`~stiffknots.engine.schedules.Schedule`), the plan that turns
them into chunks (:mod:`stiffknots.engine.plans`) and the moves of the whole run. The run
loop (:mod:`stiffknots.engine.driver`) and replica exchange
(:mod:`stiffknots.engine.tempering`) take it; a checkpoint records it
(:mod:`stiffknots.engine.checkpoints`).
"""

from __future__ import annotations

from dataclasses import dataclass, field

from stiffknots.engine.params import Ensemble, MoveParams
from stiffknots.engine.schedules import Schedule
from stiffknots.errors import InvalidParameter

PLANS = ("anneal", "tight")
DEFAULT_POWERS = (1, 2, 4, 8, 16, 32, 64)


@dataclass
class AnnealSettings:
    """Everything that defines a replica's run besides its starting chain and seed.

    Attributes
    ----------
    moves : int
        Attempted moves of the whole run.
    schedule : Schedule
        The temperature schedule (:class:`Schedule`).
    params : MoveParams
        Moves, exclusion and energy (:class:`MoveParams`).
    quench_fraction : float
        Fraction of each stage's moves spent in its T = 0 quench (``anneal``).
    n_chunks : int
        Chunks of the annealing (a chunk is the unit of traces and checkpoints).
    target_epsilon : float or None
        Record the wall and CPU seconds at which ε first falls to this value.
    ensemble : Ensemble
        Closed chain, open chain at fixed extension or at fixed force (:class:`Ensemble`).
    plan : str
        ``"anneal"`` or ``"tight"`` (see :mod:`stiffknots.engine.plans`).
    powers : tuple of int
        The powers p of the ``tight`` plan's continuation.

    Notes
    -----
    The defaults (``moves``, :class:`Schedule`, :class:`MoveParams`) won the measurements
    of docs/methods/search.md: 15 M moves, of which the first 40 % relax the starting chain
    (t = 5e-5 → 1e-7) and the rest anneal geometrically from t = 0.1 to 1e-6 (§VII).
    """

    moves: int = 15_000_000
    schedule: Schedule = field(default_factory=Schedule)
    params: MoveParams = field(default_factory=MoveParams)
    quench_fraction: float = 0.1
    n_chunks: int = 200
    target_epsilon: float | None = None
    ensemble: Ensemble = field(default_factory=Ensemble)
    plan: str = "anneal"
    powers: tuple[int, ...] = DEFAULT_POWERS

    @property
    def closed(self) -> bool:
        return self.ensemble.closed

    def validate(self) -> None:
        if self.moves < 1000:
            raise ValueError(f"moves must be ≥ 1000, got {self.moves}")
        if not 0 <= self.quench_fraction <= 1:
            raise ValueError(f"quench_fraction must be in [0, 1], got {self.quench_fraction}")
        if self.n_chunks < 1:
            raise ValueError(f"n_chunks must be ≥ 1, got {self.n_chunks}")
        if self.plan not in PLANS:
            raise ValueError(f"unknown plan {self.plan!r}; allowed: {', '.join(PLANS)}")
        if self.plan == "tight" and (not self.powers or any(int(p) != p or p < 1
                                                             for p in self.powers)):
            raise ValueError(f"powers must be integers ≥ 1, got {self.powers}")
        self.schedule.validate()
        self.ensemble.validate()
        if self.schedule.kind == "langevin" and (not self.closed or self.plan != "anneal"
                                                 or self.params.energy != "bending"):
            # here, not first in the worker (run_langevin_replica checks it there too)
            raise InvalidParameter(
                "schedule", "langevin", "a Monte Carlo schedule for "
                f"{'an open chain' if not self.closed else 'this problem'}: the langevin "
                "schedule runs closed chains under the bead rule with the bending energy")

    def as_dict(self) -> dict:
        d = {
            "moves": self.moves,
            "schedule": self.schedule.as_dict(),
            "params": self.params.as_dict(),
            "quench_fraction": self.quench_fraction,
            "n_chunks": self.n_chunks,
            "ensemble": self.ensemble.as_dict(),
            "plan": self.plan,
        }
        if self.plan == "tight":
            d["powers"] = [int(p) for p in self.powers]
        return d
