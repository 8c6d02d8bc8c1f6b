"""Relax a curve brought by the user (an experiment, ElasticKnots, KnotPlot, a polymer
simulation) to the nearest stiff-knot equilibrium (§II, §VII).

The curve — a closed polygon of any bond lengths — is

1. named (:func:`~stiffknots.knots.identify.identify_name`: one catalogue name where an
   invariant can tell), and its normalised energy ε = E·L/C taken as given (``input_epsilon``:
   E = C Σ_i (1 − u_i·u_{i+1})/b̄_i with b̄_i the mean length of the two bonds at vertex i, so
   ε = E_d·N for unit bonds, :meth:`stiffknots.chain.Chain.epsilon`);
2. resampled to N unit bonds (:func:`~stiffknots.knots.resample.resample`: equal chords on the
   polygon, the isotopy certified and the HOMFLY-PT polynomial checked identical), which fixes
   the scale: L = N bonds;
3. given the thickness of the model — the paper's bead rule d = 1/√2 bond, or a tube of
   diameter w = (w/L)·N — which the resampled chain must already satisfy (a curve thinner
   than the model cannot be inflated without changing it: the error says the curve's own
   thickness and what would fit);
4. relaxed: a low-temperature Monte Carlo from the curve itself (the relaxation stage of the
   annealing, geometric cooling to T → 0, then a quench; :mod:`stiffknots.engine.schedules`),
   which keeps its shape class, and verified like every run (energy recomputed, bonds,
   exclusion, the start's polynomial).

``stiffknots anneal --from FILE`` (a full annealing from the curve) is
:class:`~stiffknots.problems.closed.ClosedAnneal` with ``initial=``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace
from typing import ClassVar

import numpy as np

from stiffknots.chain import Chain
from stiffknots.engine.driver import AnnealSettings
from stiffknots.engine.params import MoveParams
from stiffknots.engine.schedules import Schedule
from stiffknots.errors import InvalidParameter, UserInputError
from stiffknots.knots.catalogue import Knot
from stiffknots.problems import base
from stiffknots.problems import validate as V
from stiffknots.width import Width

#: default Monte Carlo moves of `relax` per bead (12 M at N = 150: the budget its defaults were
#: measured with, twice the annealing's own relaxation stage; docs/curves.md)
RELAX_MOVES_PER_BEAD = 80_000


@dataclass
class RelaxResult(base.ReplicaSet):
    """The relaxed curve: replicas best (lowest ε) first, with the input's own ε."""

    problem: ClassVar[str] = "relax"
    input_epsilon: float | None = None
    naming: dict | None = None

    @property
    def epsilon(self) -> float:
        return self.best.epsilon

    def physics(self) -> dict:
        ok = bool(self.replicas)
        obs = self.best.observables if ok else {}
        return {"input_epsilon": self.input_epsilon,
                "epsilon": self.best.epsilon if ok else None,
                "shape": obs.get("label"), "multiplicity": obs.get("multiplicity"),
                "naming": self.naming}


def prepare_curve(chain: Chain, width: Width, knot: str | Knot | None
                  ) -> tuple[Chain, str, dict, MoveParams]:
    """Name, resample and check a user's closed curve (module docstring, steps 1–3) for a
    chain of ``width.beads`` beads of the model ``width``.

    Returns the resampled chain, the knot's name, the naming evidence and the move parameters
    of the model. Raises UserInputError (one line) when the curve cannot be used as asked.
    """
    from stiffknots.knots.identify import identify_details, normalize_name
    from stiffknots.knots.resample import resample
    from stiffknots.knots.singular import refuse_singular

    if not chain.closed:
        raise UserInputError("relax takes a closed curve (a knot); for an open knot under "
                             "tension use `stiffknots open`")
    beads = width.beads
    if knot is not None:
        knot = _knot_name(knot)
    refuse_singular(chain.coords, source=chain.meta.get("source"))  # the curve is at fault
    naming = identify_details(chain.coords, closed=True).as_dict()
    name = naming.get("knot")
    if knot is not None:
        want = normalize_name(knot)
        cands = [naming.get("knot")] + list(naming.get("candidates") or [])
        if naming.get("knot") != "unknown" and want not in [c for c in cands if c]:
            raise UserInputError(f"the curve is {naming.get('knot') or cands}, not {knot}")
        name = want
    if name is None:
        raise UserInputError("the curve's knot type is ambiguous ("
                             + " or ".join(naming.get("candidates") or ["unknown"])
                             + "); give it with --knot")
    x = resample(chain, beads)
    params = MoveParams().at_width(width)
    need = width.thickness
    if width.exclusion == "tube":
        have = x.min_segment_distance()
    else:
        have = x.min_bead_distance()
    if have < need:
        fix = (f"use --beads ≥ {math.ceil(beads * need / have)}" if width.exclusion == "bead"
               else f"use --w-over-L ≤ {have / beads:.3g} (the curve's own thickness)")
        raise UserInputError(f"the curve resampled to {beads} beads is thinner than the model "
                             f"({have:.3g} < {need:.3g} bond lengths between non-adjacent "
                             f"{'beads' if width.exclusion == 'bead' else 'segments'}); {fix}")
    return x, name, naming, params.for_beads(beads)


def _knot_name(knot: str) -> str:
    """``--knot``: a catalogue name (any usual spelling) or a composite ``a#b`` of them."""
    from stiffknots.knots.catalogue import get_knot

    text = str(knot).strip()
    if not text:
        raise InvalidParameter("knot", knot, "a knot name such as 3_1 or 5_2")
    # UnknownKnotError: one line with the closest names
    names = [get_knot(part.strip().lstrip("+-")).name for part in text.split("#")]
    return names[0] if len(names) == 1 else text


class Relax(base.Problem):
    """Relax a user's curve; see :func:`relax`."""

    result_type = RelaxResult

    def __init__(self, chain: Chain, beads: int = 150, moves: int | None = None,
                 replicas: int = 2, seed: int = 0, *, exclusion: str = "bead",
                 w_over_L: float | None = None, knot: str | None = None,
                 polish: bool = True):
        from stiffknots.problems.base import start_code

        self.replicas = V.replicas(replicas)
        self.seed = V.seed(seed)
        self.beads = V.beads(beads)
        if moves is not None:
            moves = V.moves(moves)
        self.polish = bool(polish)
        width = V.width(self.beads, exclusion, w_over_L=w_over_L, default_w=None)
        x, self.knot_name, self.naming, params = prepare_curve(chain, width, knot)
        self.input_epsilon = chain.epsilon()
        self.coords = x.coords
        sch = Schedule().for_beads(beads)
        # the relaxation stage of the annealing only: low temperature, then a quench
        relax = Schedule(kind="geometric", t_start=sch.t_relax, t_end=sch.t_relax_end,
                         relax_fraction=0.0)
        # the budget and move law its defaults were measured with: 12 M moves at N = 150
        # (× N/150), uniform crankshaft lengths (docs/curves.md)
        self.settings = AnnealSettings(
            moves=V.moves(round(RELAX_MOVES_PER_BEAD * beads) if moves is None else moves),
            schedule=relax, params=replace(params, m_law="uniform"))
        self.settings.validate()
        self.code = start_code(self.knot_name, self.coords, True, "input")
        self._bounds = _bounds(self.knot_name)

    def jobs(self, first: int = 0) -> list[base.Job]:
        return self._replica_jobs(self.settings, lambda r: self.coords, lambda r: "input",
                                  lambda r: self.code, first=first)

    def state_of(self, r: base.Replica) -> tuple[str, float]:
        return r.observables["shape"], r.epsilon

    def observe(self, r: base.Replica) -> None:
        base.observe_shape(r, self.settings.params)

    def bounds(self) -> dict:
        return self._bounds

    def settings_dict(self) -> dict:
        return {**self.settings.as_dict(), "start": "input", "polish": self.polish}

    def result_fields(self, replicas):
        return {"input_epsilon": self.input_epsilon, "naming": self.naming}


def _bounds(name: str) -> dict:
    """Closed bounds of a catalogue knot (empty for a name outside the catalogue)."""
    from stiffknots.errors import UnknownKnotError
    from stiffknots.knots.catalogue import get_knot
    from stiffknots.theory.bounds import closed_bounds

    try:
        k = get_knot(name)
    except UnknownKnotError:
        return {}
    b = closed_bounds(k.bridge_number, k.braid_index)
    return {"lower": b.lower, "upper": b.upper, "attained_by": b.attained_by}


def relax(chain: Chain | np.ndarray, beads: int = 150, moves: int | None = None,
          replicas: int = 2, seed: int = 0, *, exclusion: str = "bead",
          w_over_L: float | None = None, knot: str | None = None,
          workers: int | None = None, on_progress=None, polish: bool = True
          ) -> RelaxResult:
    """Relax a closed curve of any bond lengths to the nearest stiff-knot equilibrium.

    Parameters
    ----------
    chain : Chain or ndarray
        A closed :class:`~stiffknots.chain.Chain` (or its (M, 3) coordinates).
    beads : int
        N of the resampled chain (bond length 1, L = N).
    moves : int or None
        Monte Carlo moves per replica (default :data:`RELAX_MOVES_PER_BEAD` per bead,
        12 M at N = 150).
    exclusion, w_over_L
        The paper's bead rule (``"bead"``, d = 1/√2 bond) or a tube of
        diameter w = w_over_L · N (``"tube"``).
    knot : str or None
        The knot's name, if the invariants cannot tell (a HOMFLY-PT tie) or to check it.

    Returns
    -------
    RelaxResult
        ``input_epsilon`` (the curve as given), ``epsilon`` and ``shape`` of the relaxed chain,
        ``converged`` (the replicas agree), and the naming evidence.
    """
    if not isinstance(chain, Chain):
        chain = Chain(chain, closed=True)
    problem = Relax(chain, beads, moves, replicas, seed, exclusion=exclusion,
                    w_over_L=w_over_L, knot=knot, polish=polish)
    return base.solve(problem, workers=workers, on_progress=on_progress)
