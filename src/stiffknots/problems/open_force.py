"""Open knots at fixed force (paper §VIII): anneal E_d − F·Δz and measure the excess length.

The fixed-extension route (:mod:`stiffknots.problems.open_extension`) fixes L_e and measures
the tension μ = E_d/L_e. Here the ends slide along the z axis under a constant pulling force
F (the ``force`` ensemble of the engine: slide and pivot end moves of
:mod:`stiffknots.engine.force_kernel`, interleaved with the interior crankshafts), the energy
is E = E_d − F·Δz, and L_e = (N − 1) − Δz is *measured*. At T → 0 the chain minimises
ε_e C/L_e + F·L_e, i.e. it settles where the tension μ = E_d/L_e equals the applied force
(force balance, L_e = (ε_e C/F)^½): the result reports F, the measured L_e, E_d,
ε_e = E_d·L_e/C, μ = E_d/L_e and the ratio μ/F.

Each replica is verified like every other (:mod:`stiffknots.problems.base`): bonds of unit
length (1e-10), the end segments exactly on the z axis, the exclusion rule, the incremental
energies E_d and E_d − F·Δz against a recomputation, and the knot type of the closure along z.
Runs checkpoint and resume like closed ones. Units: b = 1, C = 1.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import ClassVar

import numpy as np

from stiffknots.engine.driver import AnnealSettings
from stiffknots.engine.params import Ensemble, MoveParams
from stiffknots.engine.schedules import Schedule
from stiffknots.errors import EmbeddingError, InvalidParameter
from stiffknots.problems import validate as V
from stiffknots.problems.base import Job, Problem, Replica, solve, start_code
from stiffknots.problems.open_extension import (
    DEFAULT_OPEN_MOVES,
    OpenResult,
    default_open_params,
    excess_length_for_force,
    open_chain,
    with_w_over_L,
)

DEFAULT_END_FRACTION = 0.1
DEFAULT_SLIDE_FRACTION = 0.8
DEFAULT_END_M_MAX = 30


def default_force_schedule() -> Schedule:
    """Geometric cooling 1e-2 → 1e-6 without the relaxation stage (measured, open 3_1, tube
    w = 0.1, F = 0.013, 10 M moves, seeds 1–2: ε_e = 21.1–21.3 — the loop — against 32–36 with
    the default power-law schedule and its relaxation stage, whose hot phase is too short for
    L_e and the loop to form). L_e relaxes slowly (≈ 30 M moves at T = 1e-3 to grow the loop
    from L_e = 35.5 to the balance point ≈ 40): use tens of millions of moves."""
    return Schedule(kind="geometric", t_start=1e-2, t_end=1e-6, relax_fraction=0.0)


@dataclass
class ForceResult(OpenResult):
    """Replicas of one open knot at fixed force F, best (lowest E_d − F·Δz) first.

    ``excess_length``, ``energy``, ``eps_e`` and ``tension`` (μ = E_d/L_e) are those of the best
    replica; ``force`` is the applied F.
    """

    problem: ClassVar[str] = "open-force"
    force: float = 0.0

    @property
    def force_balance(self) -> float:
        """μ/F: 1 at equilibrium at T → 0 (E_d = ε_e C/L_e, −dE_d/dL_e = E_d/L_e = F)."""
        return self.tension / self.force

    def physics(self) -> dict:
        ok = bool(self.replicas)
        return super().physics() | {
            "ensemble": "force",
            "force": self.force,
            "force_balance": self.force_balance if ok else None,
            "extension": self.best.extension if ok else None,
            "total_energy": self.best.total_energy if ok else None,
        }


def start_chain(knot, force: float, n_beads: int | None = None,
                excess_length: int | None = None, seed: int = 0) -> tuple[np.ndarray, int]:
    """The starting chain (an open embedding padded to ``n_beads``) and its excess length.

    Without ``excess_length`` the embedding starts near the L_e the force selects in the thin
    limit, (ε_e C/F)^½ with ε_e the knot's lower bound 2π²n₁² (§VIII); if the embedding needs
    more, larger excess lengths are tried. Without ``n_beads`` each straight end is lengthened
    by ⌈L_e/4⌉ beads, room for the knot to take up more length; longer tails only slow the
    annealing down (the crankshafts spend their moves on straight tails).
    """
    from stiffknots.knots.catalogue import Knot, get_knot
    from stiffknots.knots.open_embedding import pad_open_chain
    from stiffknots.theory.bounds import open_bounds

    def padded(le: int) -> tuple[np.ndarray, int]:
        x = open_chain(k, le, seed=seed)
        n = len(x) + 2 * math.ceil(le / 4) if n_beads is None else n_beads
        return pad_open_chain(x, n), le

    k = knot if isinstance(knot, Knot) else get_knot(knot)
    if excess_length is not None:
        return padded(int(excess_length))
    eps = open_bounds(k.bridge_number, k.braid_index).lower or 2 * math.pi**2
    le = max(V.MIN_EXCESS_LENGTH, int(round(excess_length_for_force(eps, force))))
    if le > V.MAX_EXCESS_LENGTH:
        f_min = eps / V.MAX_EXCESS_LENGTH**2
        raise InvalidParameter("force", force, f"≥ {f_min:.3g} C/b² for {k.name}",
                               f"the excess length it selects, (ε_e C/F)^½ with ε_e ≥ "
                               f"{eps:.4g}, must be ≤ {V.MAX_EXCESS_LENGTH:,} bonds")
    err = None
    for _ in range(6):
        try:
            return padded(le)
        except EmbeddingError as exc:
            err = exc
            le += 5
    raise err


class OpenForce(Problem):
    """An open knot at fixed force (§VIII); see :func:`anneal_open_force`."""

    result_type = ForceResult

    def __init__(self, knot: str, force: float, n_beads: int | None = None,
                 moves: int = DEFAULT_OPEN_MOVES, replicas: int = 2, seed: int = 0, *,
                 excess_length: int | None = None, params: MoveParams | None = None,
                 schedule: Schedule | None = None,
                 end_fraction: float = DEFAULT_END_FRACTION,
                 slide_fraction: float = DEFAULT_SLIDE_FRACTION,
                 end_m_max: int = DEFAULT_END_M_MAX, quench_fraction: float = 0.1,
                 checkpoint_dir: str | Path | None = None, resume: bool = False,
                 checkpoint_seconds: float | None = 60.0,
                 w_over_L: float | None = None):  # noqa: N803
        from stiffknots.theory.bounds import open_bounds

        self._setup(knot, replicas, seed)
        self.polish = False  # the ends move at fixed force: the minimiser holds them fixed
        self.force = V.number("force", force, 0, lo_open=True)
        V.number("end_fraction", end_fraction, 0, 1, lo_open=True)
        V.number("slide_fraction", slide_fraction, 0, 1, lo_open=True)
        V.integer("end_m_max", end_m_max, 1)
        if n_beads is not None:
            V.beads(n_beads, "n_beads")
        if excess_length is not None:
            V.integer("excess_length", excess_length, V.MIN_EXCESS_LENGTH, V.MAX_EXCESS_LENGTH)
        if resume and checkpoint_dir is None:
            raise InvalidParameter("checkpoint_dir", None, "given when resume=True",
                                   "the folder of the checkpoints")
        self.coords, self.start_excess_length = start_chain(
            self.knot, self.force, n_beads, excess_length, seed=self.seed)
        self.beads = len(self.coords)
        self.code = start_code(self.knot_name, self.coords, False, "open")
        self.moves_kw = {"end_fraction": end_fraction, "slide_fraction": slide_fraction,
                         "end_m_max": end_m_max}
        self.settings = AnnealSettings(
            moves=V.moves(moves), schedule=schedule or default_force_schedule(),
            params=with_w_over_L(params or default_open_params(), w_over_L,
                                 self.beads).for_beads(self.beads),
            quench_fraction=quench_fraction,
            ensemble=Ensemble("force", force=self.force, **self.moves_kw))
        self.settings.validate()
        self.settings.params.validate(self.beads)
        self.checkpoint_dir = checkpoint_dir
        self.resume = resume
        self.checkpoint_seconds = checkpoint_seconds
        self._bounds = open_bounds(self.knot.bridge_number, self.knot.braid_index)

    def jobs(self, first: int = 0) -> list[Job]:
        return self._replica_jobs(self.settings, lambda r: self.coords, lambda r: "open",
                                  lambda r: self.code, self.checkpoint_dir, self.resume,
                                  self.checkpoint_seconds, first)

    def bounds(self) -> dict:
        return {"eps_e_lower": self._bounds.lower, "eps_e_upper": self._bounds.upper}

    def settings_dict(self) -> dict:
        return (self.settings.as_dict() | {"force": self.force,
                                           "start_excess_length": self.start_excess_length}
                | self.moves_kw)

    def sort_key(self, r: Replica) -> float:
        return r.total_energy

    def result_fields(self, replicas):
        return {"force": self.force,
                "excess_length": replicas[0].excess_length if replicas else float("nan")}


def anneal_open_force(knot: str, force: float, n_beads: int | None = None,
                      moves: int = DEFAULT_OPEN_MOVES, replicas: int = 2, seed: int = 0, *,
                      excess_length: int | None = None, params: MoveParams | None = None,
                      schedule: Schedule | None = None,
                      end_fraction: float = DEFAULT_END_FRACTION,
                      slide_fraction: float = DEFAULT_SLIDE_FRACTION,
                      end_m_max: int = DEFAULT_END_M_MAX, workers: int | None = None,
                      quench_fraction: float = 0.1,
                      on_replica_done: Callable[[Replica], None] | None = None,
                      checkpoint_dir: str | Path | None = None, resume: bool = False,
                      checkpoint_seconds: float | None = 60.0) -> ForceResult:
    """Anneal an open knot at fixed end force F (energy E_d − F·Δz, paper §VIII); measure L_e.

    Parameters
    ----------
    knot : str
        Knot name ('3_1', '4_1', …).
    force : float
        F > 0 in C/b².
    n_beads : int or None
        Beads of the chain: the open embedding is lengthened along the axis to this many
        (default: by ⌈L_e/4⌉ beads at each end, see :func:`start_chain`).
    moves, replicas, seed, params, workers, quench_fraction, on_replica_done
        As for :func:`stiffknots.problems.open_extension.anneal_open`.
    schedule : Schedule or None
        Default :func:`default_force_schedule` (geometric, no relaxation stage).
    excess_length : int or None
        Excess length of the starting embedding (default: near (ε_e C/F)^½ with
        the thin-limit ε_e; see :func:`start_chain`). The annealing moves it.
    end_fraction : float
        Fraction of the moves that move an end (slide and pivot moves).
    slide_fraction : float
        Fraction of the end moves that are slides (the others are pivots).
    end_m_max : int
        Largest number of beads rotated by a pivot move.
    checkpoint_dir, resume, checkpoint_seconds
        Checkpoints, as for :func:`stiffknots.anneal`.

    Returns
    -------
    ForceResult
        Replicas sorted by E_d − F·Δz; ``excess_length`` (measured), ``eps_e``,
        ``tension`` (μ = E_d/L_e), ``force``, ``force_balance`` (μ/F), ``shape()``.

    Raises
    ------
    TopologyChangedError, EnergyBookkeepingError, ChainGeometryError
        If a replica's knot type, energy bookkeeping or chain geometry is wrong (never
        expected: each would be a bug).
    """
    problem = OpenForce(knot, force, n_beads, moves, replicas, seed,
                        excess_length=excess_length, params=params, schedule=schedule,
                        end_fraction=end_fraction, slide_fraction=slide_fraction,
                        end_m_max=end_m_max, quench_fraction=quench_fraction,
                        checkpoint_dir=checkpoint_dir, resume=resume,
                        checkpoint_seconds=checkpoint_seconds)
    return solve(problem, workers=workers, on_replica_done=on_replica_done)
