"""Temperature schedules for simulated annealing (paper §VII: "a power law decrease").

Every schedule maps the fraction s ∈ [0, 1] of the annealing moves done to a temperature
(k_B T in units of C, bond length 1). A zero-temperature quench follows the schedule in the
driver.

Two stages
----------
With ``relax_fraction`` r > 0 a run has two stages, each ending with its own quench:

1. *relaxation*: the first fraction r of the moves cools the starting chain geometrically from
   ``t_relax`` to ``t_relax_end``. ``t_relax`` is low (the default 5e-5 gives a thermal
   excess δε ≈ 1, persistence length 2·10⁴ ≫ N): the chain keeps the topology-level shape of
   its braid embedding and only relaxes. For the n = i knots the closed minimal braid *is* the
   circular braid that the paper proves to be the ground state (§VI C), so this stage is what
   finds it, far sooner than a hot start; it also finds the 4_1's 4-fold cage
   (docs/methods/search.md).
2. *annealing*: the rest of the moves anneal from ``t_start`` (hot) down to ``t_end`` with the
   power law (the paper's method) or geometrically, which explores other shapes (the 4-fold
   cage, the "80", metastable states).

3. *hops* (``hops`` = K > 0): the last fraction ``hop_fraction`` of the moves is K equal
   basin hops. Each hop starts from the lowest quenched chain found so far, reheats it to
   ``t_hop`` and cools it geometrically to ``t_end``, then quenches; a hop that ends lower
   becomes the chain the next hop starts from (a greedy walk over the local minima, the
   basin-hopping of Wales & Doye, J. Phys. Chem. A 101, 5111 (1997)). The knots beyond the
   simplest have many minima within a few tenths of a percent of each other (the shape is
   decided, the beads' registry at contacts is not); one hot annealing lands in any of them,
   the hops walk down to the bottom of its funnel, so that independent replicas agree. The
   default ``t_hop`` = 2·10⁻³ at N = 150 (a thermal excess δε ≈ 45) is enough to rearrange
   contacts, not to undo the shape (docs/methods/search.md).

The driver keeps the lowest-energy quenched chain of all stages. r = 0 and K = 0 is the plain
annealing of the paper.

Langevin dynamics
-----------------
``kind = "langevin"`` replaces the Monte Carlo by guarded Langevin dynamics of the whole chain
(:mod:`stiffknots.engine.langevin`: every bead moves at every step, the way the peer LAMMPS
searches), T falling exponentially from ``t_start`` to ``t_end``; ``moves`` then counts
dynamics steps. Closed chains under the bead rule only; ``relax_fraction`` and the hops are
not used.

Parallel tempering
------------------
``kind = "tempering"`` replaces annealing by replica exchange
(:mod:`stiffknots.engine.tempering`): ``n_temps`` chains at the fixed geometric ladder
``t_end … t_start`` (:meth:`Schedule.ladder`); ``relax_fraction``, ``t_relax``,
``t_relax_end`` and ``exponent`` are not used. It is slower than annealing on the benchmark
knots, so it is not the default (docs/methods/search.md).
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass, replace

import numpy as np

from stiffknots.errors import InvalidParameter

#: the kinds of :class:`Schedule`, by name
SCHEDULES = ("power", "geometric", "tempering", "langevin")


@dataclass(frozen=True)
class Schedule:
    """Cooling from ``t_start`` to ``t_end`` (paper §VII), optionally after a relaxation stage.

    ``power`` (the paper's form, §VII):  T(s) = t_start · (1 + s·c)^(−a), with
    c = (t_start/t_end)^(1/a) − 1 so that T(1) = t_end; ``a`` is the power-law exponent.
    ``geometric``:  T(s) = t_start · (t_end/t_start)^s.
    ``tempering``: replica exchange on the ladder :meth:`ladder` (see the module docstring).

    Attributes
    ----------
    relax_fraction : float
        Fraction of the moves spent first relaxing the starting chain
        (geometric cooling ``t_relax`` → ``t_relax_end``, then a quench); 0 disables the stage
        and leaves the paper's plain annealing.
    t_relax, t_relax_end : float
        First and last temperature of the relaxation stage.
    hops, hop_fraction, t_hop
        The number of basin hops that end the run, the fraction of
        the moves they take (shared equally) and the temperature each reheats to (then
        geometric cooling to ``t_end``); ``hops = 0`` disables them.
    n_temps : int
        Number of temperatures of the tempering ladder (``tempering`` only).

    Notes
    -----
    Temperatures are k_B T in units of C per joint. A chain of N beads in equilibrium at T
    carries a thermal excess δε ≈ N²T (about N·T of energy E_d over its ~2N degrees of
    freedom, and ε = E_d·N), so the same schedule at another N means T ∝ 1/N²: the defaults are
    the measured ones at the paper's N = 150 and :meth:`for_beads` scales them by (150/N)².

    The defaults: the relaxation stage takes 0.4 of the moves and cools 5e-5 → 1e-7; the
    annealing stage cools geometrically from 0.1 to 1e-6 — the range of the LAMMPS protocol
    of the solver benchmark. The paper's power law from 3e-2 (:data:`PAPER_POWER_LAW`)
    spends most of its moves cold and leaves the 4_1 in its 4-fold cage, where the geometric
    cooling reaches the lower states (docs/methods/search.md).
    """

    kind: str = "geometric"
    t_start: float = 1e-1
    t_end: float = 1e-6
    exponent: float = 2.0
    relax_fraction: float = 0.4
    t_relax: float = 5e-5
    t_relax_end: float = 1e-7
    n_temps: int = 6
    hops: int = 0
    hop_fraction: float = 0.0
    t_hop: float = 2e-3

    def for_beads(self, n_beads: int, reference: int = 150) -> Schedule:
        """The same cooling for a chain of ``n_beads`` beads: every temperature times
        (reference/N)², so that the thermal excess δε ≈ N²T of each stage is unchanged."""
        f = (reference / int(n_beads)) ** 2
        return replace(self, t_start=self.t_start * f, t_end=self.t_end * f,
                       t_relax=self.t_relax * f, t_relax_end=self.t_relax_end * f,
                       t_hop=self.t_hop * f)

    def validate(self) -> None:
        if self.kind not in SCHEDULES:
            raise InvalidParameter("schedule", self.kind, "one of " + ", ".join(SCHEDULES))
        for name in ("t_start", "t_end", "exponent", "t_relax", "t_relax_end", "t_hop"):
            v = getattr(self, name)
            if not (isinstance(v, int | float) and math.isfinite(v) and v > 0):
                raise InvalidParameter(name, v, "a finite number > 0")
        if not self.t_end < self.t_start:
            raise InvalidParameter("t_end", self.t_end, f"below t_start = {self.t_start:g}")
        if not 0 <= self.relax_fraction < 1:
            raise InvalidParameter("relax_fraction", self.relax_fraction, "in [0, 1)")
        if self.relax_fraction > 0 and self.kind in ("power", "geometric") and not (
                self.t_relax > self.t_relax_end):
            raise InvalidParameter("t_relax_end", self.t_relax_end,
                                   f"below t_relax = {self.t_relax:g}")
        if not (isinstance(self.hops, int) and 0 <= self.hops <= 100):
            raise InvalidParameter("hops", self.hops, "an integer in [0, 100]")
        if self.hops > 0 and not 0 < self.hop_fraction < 1 - self.relax_fraction:
            raise InvalidParameter("hop_fraction", self.hop_fraction,
                                   f"in (0, {1 - self.relax_fraction:g}) (1 − relax_fraction: "
                                   "the annealing stage keeps the rest) when hops > 0")
        if self.hops > 0 and self.kind == "langevin":
            raise InvalidParameter("hops", self.hops, "0 with the langevin schedule")
        if self.hops > 0 and self.kind in ("power", "geometric") and not self.t_hop > self.t_end:
            raise InvalidParameter("t_hop", self.t_hop, f"above t_end = {self.t_end:g}")
        if self.kind == "tempering" and not 2 <= self.n_temps <= 64:
            raise InvalidParameter("n_temps", self.n_temps, "an integer in [2, 64]")

    @property
    def stages(self) -> tuple[str, ...]:
        """The stages of an annealing run, in order: ``relax`` (if any), ``anneal``, then the
        hops ``hop1`` … ``hopK`` (if any)."""
        if self.kind in ("tempering", "langevin"):
            return (self.kind,)
        first = ("relax", "anneal") if self.relax_fraction > 0 else ("anneal",)
        return first + tuple(f"hop{k}" for k in range(1, self.hops + 1))

    def stage_fractions(self) -> dict[str, float]:
        """The fraction of the moves of each stage (:attr:`stages`)."""
        fr = {"relax": self.relax_fraction} if self.relax_fraction > 0 else {}
        hop = self.hop_fraction / self.hops if self.hops > 0 else 0.0
        fr["anneal"] = 1.0 - self.relax_fraction - (self.hop_fraction if self.hops else 0.0)
        fr.update({f"hop{k}": hop for k in range(1, self.hops + 1)})
        return fr

    def hop_temperature(self, s: float | np.ndarray, k: int = 1) -> float | np.ndarray:
        """Temperature of hop ``k`` (1, 2, …): geometric from its start to ``t_end``; odd hops
        start at ``t_hop``, even hops at ``t_hop``/4 (two sizes of perturbation: the hot one
        rearranges contacts, the mild one slides a strand's registry without undoing it)."""
        s = np.clip(s, 0.0, 1.0)
        t0 = self.t_hop if k % 2 else self.t_hop / 4
        return t0 * (self.t_end / t0) ** s

    def temperature(self, s: float | np.ndarray) -> float | np.ndarray:
        """Temperature of the annealing stage at the fraction ``s`` of its moves."""
        s = np.clip(s, 0.0, 1.0)
        if self.kind == "geometric":
            return self.t_start * (self.t_end / self.t_start) ** s
        c = (self.t_start / self.t_end) ** (1.0 / self.exponent) - 1.0
        return self.t_start * (1.0 + s * c) ** (-self.exponent)

    def relax_temperature(self, s: float | np.ndarray) -> float | np.ndarray:
        """Temperature of the relaxation stage: geometric from ``t_relax`` to ``t_relax_end``."""
        s = np.clip(s, 0.0, 1.0)
        return self.t_relax * (self.t_relax_end / self.t_relax) ** s

    def ladder(self) -> np.ndarray:
        """The tempering ladder: ``n_temps`` temperatures, geometric, coldest first."""
        return np.geomspace(self.t_end, self.t_start, self.n_temps)

    def as_dict(self) -> dict:
        return asdict(self)


#: The paper's power-law annealing (§VII) from 3e-2 after the relaxation stage: the former
#: default, kept for the open-knot and tightest-knot problems whose defaults were measured
#: with it (docs/history.md).
PAPER_POWER_LAW = Schedule(kind="power", t_start=3e-2, t_end=1e-6, exponent=2.0)
