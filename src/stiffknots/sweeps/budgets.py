"""Budgets of a sweep: how many replicas of how many attempted moves each (knot, model) gets.

A budget is a name for (replicas, moves per replica, most replicas) and for how the bead-rule
ensembles search. A tube replica — and a bead-rule replica of ``bead_search = "annealing"`` —
runs the default annealing schedule of :class:`~stiffknots.engine.driver.AnnealSettings`
(relaxation, then geometric annealing from T = 0.1, §VII) on those moves; a bead-rule replica
of ``bead_search = "langevin"`` runs ``bead_steps`` steps of the guarded Langevin dynamics
(:mod:`stiffknots.engine.langevin`, ``anneal``'s default search of the bead rule). Every replica
is polished. The moves and the search are part of every replica's settings, hence of its
store key: two budgets with other moves never share results, while a budget with more
replicas of the same settings reuses the replicas a smaller one stored (replica r's seed does
not depend on the number of replicas). A (knot, model) whose ground state has not converged
once its replicas have ended gets two more, up to ``max_replicas`` (a Langevin bead ensemble:
``bead_max_replicas``; :func:`stiffknots.sweeps.run.run_sweep`): easy knots stop at two, hard
ones get more; a tube ensemble still not converged then gets up to ``legs`` continuation
legs, each continuing its second-lowest search by basin hops, a Langevin bead ensemble up to
``bead_legs`` Langevin legs, each continuing one of its lowest searches
(:mod:`stiffknots.sweeps.legs`).

=========  ========  ==========  ====  ====  =====================  ========================
budget     replicas  moves       most  legs  bead rule              CPU s per (knot, model)
=========  ========  ==========  ====  ====  =====================  ========================
tiny       2         200,000     2     0     annealing              ≈ 1 — a smoke test
small      2         5,000,000   2     0     annealing              ≈ 10
default    2         15,000,000  6     2     Langevin 10⁶ steps,    tube ≈ 30 converged at 3,
                                             up to 16, then 4       ≈ 60 at 6 (a leg ≈ 10–45);
                                             Langevin legs          bead ≈ 4 a replica, 1.3 a
                                                                    leg
full       4         60,000,000  12    2     Langevin 10⁶ steps,    tube ≈ 160 at 4, ≈ 480 at
                                             up to 32, 4 legs       12; bead ≈ 4 a replica
=========  ========  ==========  ====  ====  =====================  ========================

Why the Langevin bead search (docs/methods/search.md): on 18 knots of 9 and 10 crossings
(9_1, 9_7, …, 9_49, 10_1, 10_21, …, 10_161; both models, seed 0) the annealing's bead
ensembles (2 × 15 M moves, up to 6) converged 6 of 18 for 800 own CPU s, the Langevin ones
(up to 16 replicas of 10⁶ steps, 4.0 CPU s each) 13 of 18 for 607 CPU s, with lower grounds
for 10 knots and higher ones for 4; capped at 6 replicas they would have converged 10 for
323 CPU s. Both searches left two verdicts above the other's lowest state.
The tube ensembles' settings, and so their stored replicas, are the same under both.

Measurements behind the tube rows (``bench/defaults_survey.py``: the same replicas — 15 M
moves, polished — through ``stiffknots anneal``, 35 knots through 8 crossings): 7–13 CPU
seconds per replica; about half the knots' first two replicas agree, and their verdict then
needs one replica more (the tube's rule of three searches, :mod:`.convergence`). What the
whole atlas takes at each budget: docs/atlas.md.
"""

from __future__ import annotations

from dataclasses import dataclass

from stiffknots.errors import InvalidParameter
from stiffknots.problems import validate as V

__all__ = ["Budget", "BUDGETS", "BEAD_SEARCHES", "LEG_EXCLUSIONS", "budget_of",
           "MEASURED_CPU_SECONDS_PER_M_MOVES"]

#: How a bead-rule ensemble searches: ``annealing`` — the paper's Monte Carlo annealing (§VII)
#: of ``moves`` moves a replica, the tube model's search too — or ``langevin`` — the guarded
#: Langevin dynamics of :mod:`stiffknots.engine.langevin` (every bead moves at every step;
#: ``anneal``'s default for the bead rule) of ``bead_steps`` steps a replica.
BEAD_SEARCHES = ("annealing", "langevin")

#: the exclusion models whose annealed ensembles get basin-hop legs (``Budget.legs``). Not the
#: bead rule (its Langevin ensembles get Langevin legs instead, ``Budget.bead_legs``): one leg
#: from the second-lowest replica of six unconverged annealed bead ensembles of the same run
#: ended at its parent's ε in three (10_100, 10_102, 10_104: the hops at ``t_hop`` do not
#: leave a bead-rule registry minimum), 0.07 % lower and still 0.82 % above the lowest in one
#: (10_10), and at the lowest in two whose parent and lowest are both seeded replicas (10_101,
#: 10_106: a seeded search cannot certify); none converged (docs/history.md)
LEG_EXCLUSIONS = ("tube",)

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
        The tube model's only (:data:`LEG_EXCLUSIONS`; the annealed bead rule gets none).
    bead_search : str
        How the bead-rule ensembles search (:data:`BEAD_SEARCHES`); the tube model always
        anneals.
    bead_steps : int
        Dynamics steps of a bead-rule replica with ``bead_search = "langevin"``.
    bead_max_replicas : int or None
        The most replicas of a bead-rule ensemble with ``bead_search = "langevin"`` (None:
        ``max_replicas``): its replicas cost about half an annealing replica.
    bead_legs : int
        A Langevin bead ensemble still not converged at ``bead_max_replicas`` gets up to this
        many Langevin legs, one at a time, leg k continuing the (k+1)-th lowest of its own
        searches (:mod:`stiffknots.sweeps.legs`; ≈ 1.3 CPU s a leg at N = 150).
    coarse : int or None
        The tube model's replicas first anneal their start at this many beads and search from
        that chain resampled (:mod:`stiffknots.problems.coarse`); None: from the start. Part
        of the replicas' settings (another ensemble in the store).
    """

    name: str
    replicas: int
    moves: int
    max_replicas: int | None = None
    legs: int = 0
    bead_search: str = "annealing"
    bead_steps: int = 1_000_000
    bead_max_replicas: int | None = None
    bead_legs: int = 0
    coarse: int | None = None

    def validate(self) -> Budget:
        """Return self, or raise :class:`InvalidParameter` for a bad count (the limits of
        :mod:`stiffknots.problems.validate`) or an unknown bead search."""
        V.replicas(self.replicas)
        V.moves(self.moves)
        if self.bead_search not in BEAD_SEARCHES:
            raise InvalidParameter("bead_search", self.bead_search,
                                   " or ".join(BEAD_SEARCHES))
        V.moves(self.bead_steps, "bead_steps")
        if self.coarse is not None:
            V.integer("coarse", self.coarse, 3, 10**6)
        return self

    def coarse_of(self, model) -> int | None:
        """The coarse stage's bead count of ``model``'s replicas: ``coarse`` for the tube
        model, None for the bead rule (its Langevin search has no coarse stage)."""
        return self.coarse if model.exclusion == "tube" else None

    def langevin(self, model) -> bool:
        """Whether ``model``'s replicas run the Langevin dynamics (bead rule, ``bead_search =
        "langevin"``)."""
        return model.exclusion == "bead" and self.bead_search == "langevin"

    def search_of(self, model) -> tuple[int, object]:
        """(moves, :class:`~stiffknots.engine.schedules.Schedule`) of every replica of
        ``model``: the dynamics steps and the langevin schedule
        (:func:`stiffknots.problems.closed.langevin_schedule`) where :meth:`langevin`, else
        ``moves`` and the default annealing schedule sized for N."""
        from stiffknots.engine.schedules import Schedule
        from stiffknots.problems.closed import langevin_schedule

        if self.langevin(model):
            return self.bead_steps, langevin_schedule(model.beads)
        return self.moves, Schedule().for_beads(model.beads)

    def most_replicas(self, model) -> int:
        """The most replicas of one ``model`` ensemble (``bead_max_replicas`` for a Langevin
        bead ensemble where set, else ``max_replicas``, else ``replicas``)."""
        if self.langevin(model) and self.bead_max_replicas:
            return self.bead_max_replicas
        return self.max_replicas or self.replicas

    def legs_of(self, model) -> int:
        """The most continuation legs of one ``model`` ensemble: ``bead_legs`` for a Langevin
        bead ensemble, else ``legs`` for the tube model; the annealed bead rule gets none
        (:data:`LEG_EXCLUSIONS`: its basin hops do not leave a registry minimum)."""
        if self.langevin(model):
            return self.bead_legs
        return self.legs if model.exclusion in LEG_EXCLUSIONS else 0

    def cpu_seconds(self) -> float:
        """Estimated CPU seconds of one (knot, model) on one core (N = 150)."""
        return self.replicas * self.moves * 1e-6 * MEASURED_CPU_SECONDS_PER_M_MOVES

    def as_dict(self) -> dict:
        return {"name": self.name, "replicas": self.replicas, "moves": self.moves,
                "max_replicas": self.max_replicas or self.replicas, "legs": self.legs,
                "bead_search": self.bead_search,
                **({"bead_steps": self.bead_steps,
                    "bead_max_replicas": self.bead_max_replicas or self.max_replicas
                    or self.replicas, "bead_legs": self.bead_legs}
                   if self.bead_search == "langevin" else {}),
                **({"coarse": self.coarse} if self.coarse is not None else {})}


#: the named budgets of a sweep (``--budget``)
BUDGETS: dict[str, Budget] = {
    "tiny": Budget("tiny", 2, 200_000),
    "small": Budget("small", 2, 5_000_000),
    "default": Budget("default", 2, 15_000_000, max_replicas=6, legs=2,
                      bead_search="langevin", bead_max_replicas=16, bead_legs=4),
    "full": Budget("full", 4, 60_000_000, max_replicas=12, legs=2,
                   bead_search="langevin", bead_max_replicas=32, bead_legs=4),
}


def budget_of(name: str, *, replicas: int | None = None, moves: int | None = None,
              bead_search: str | None = None, bead_steps: int | None = None,
              coarse: int | None = None) -> Budget:
    """The named budget, with ``replicas`` or ``moves`` overridden where given (the name then
    becomes ``custom``, with no replicas added and no legs), its bead-rule search where
    ``bead_search`` is given (:data:`BEAD_SEARCHES`; the name stays), and the dynamics steps
    of a Langevin bead replica where ``bead_steps`` is given (the name and the caps stay; the
    replicas are another ensemble: the steps are part of their settings), and the tube
    replicas' coarse stage where ``coarse`` is given (likewise).

    Why a deeper bead search is offered (docs/methods/search.md): on
    24 knots whose 16 Langevin replicas of 10⁶ steps never converged in the 249-knot atlas,
    4 replicas of 3·10⁶ steps converged 6 and reached states up to 8 % lower (10_30: 267.18
    against 291.09) — and for 12 of the 24 stayed higher: the bead rule's landscape there has
    funnels far apart that any search finds by chance.

    Raises
    ------
    InvalidParameter
        An unknown name (the message lists the budgets), a bad count, an unknown search,
        ``bead_steps`` with a bead search that is not Langevin dynamics.
    """
    from dataclasses import replace

    if name not in BUDGETS:
        raise InvalidParameter("budget", name, "one of " + ", ".join(BUDGETS))
    b = BUDGETS[name]
    if bead_search is not None:
        b = replace(b, bead_search=bead_search).validate()
    if bead_steps is not None:
        if b.bead_search != "langevin":
            raise InvalidParameter(
                "bead_steps", bead_steps,
                "given with a Langevin bead search only (bead search langevin, the default "
                f"and full budgets'), not with {b.bead_search}, which counts Monte Carlo moves")
        b = replace(b, bead_steps=bead_steps).validate()
    if coarse is not None:  # the name and caps stay: another ensemble of the tube model
        b = replace(b, coarse=coarse).validate()
    if replicas is None and moves is None:
        return b
    return replace(b, name="custom", replicas=b.replicas if replicas is None else replicas,
                   moves=b.moves if moves is None else moves, max_replicas=None, legs=0,
                   bead_max_replicas=None, bead_legs=0).validate()
