"""``stiffknots.anneal``: any knot of the catalogue to a verified minimum-energy chain (§VII).

Composes catalogue → starting embeddings → engine (replicas on all cores) → verification
(:mod:`stiffknots.problems.base`). ε = E_d·N/C with E_d = C Σ(1 − u_n·u_{n+1}) (§VII).

Long runs can checkpoint every replica (``checkpoint_dir``) and be resumed (``resume=True``)
with exactly the result of an uninterrupted run (:mod:`stiffknots.engine.driver`).
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import ClassVar

from stiffknots.engine.driver import AnnealSettings
from stiffknots.engine.langevin import DEFAULT_STEPS as LANGEVIN_STEPS
from stiffknots.engine.params import MoveParams
from stiffknots.engine.schedules import Schedule
from stiffknots.errors import InvalidParameter
from stiffknots.knots.catalogue import Knot
from stiffknots.problems import validate as V
from stiffknots.problems.base import (
    Job,
    Problem,
    Replica,
    ReplicaSet,
    agree_for,
    default_moves,
    observe_shape,
    solve,
)

#: rounds of replicas until the lowest state is reached by two searches
DEFAULT_ROUNDS = 8
#: the rounds of a ``langevin`` schedule by default (``stiffknots anneal``): a replica of 10⁶
#: dynamics steps costs about half an annealing replica (≈ 4.4 s at N = 150) and easy knots
#: stop after a few rounds; through 8 crossings 8_7 and 8_2 converge after 34 and 51 rounds,
#: and the 35 knots take about the annealing's time with its 8 rounds (≈ 29 min; a knot that
#: never converges ≈ 4.5–5 min; docs/history.md)
LANGEVIN_ROUNDS = 64


def langevin_schedule(beads: int) -> Schedule:
    """The langevin schedule of ``stiffknots anneal`` and of the atlas's Langevin bead
    ensembles at ``beads`` beads: the default schedule sized for N with ``kind = "langevin"``
    and the final temperature :data:`~stiffknots.engine.langevin.DEFAULT_T_END` scaled as
    (150/N)² (the bending energy's scale per bond)."""
    from dataclasses import replace

    from stiffknots.engine.langevin import DEFAULT_T_END

    return replace(Schedule().for_beads(beads), kind="langevin",
                   t_end=DEFAULT_T_END * (150 / beads) ** 2)

#: a continuation leg (rounds after the first two, :func:`stiffknots.problems.base.solve`):
#: this many basin hops from the search's lowest chain …
LEG_HOPS = 8
#: … of this fraction of a replica's moves in all (12 M of the default 15 M at N = 150)
LEG_FRACTION = 0.8
#: A Langevin continuation leg of the atlas's bead ensembles
#: (:meth:`ClosedAnneal.langevin_leg_jobs`): the dynamics from the parent's polished chain,
#: reheated to this temperature × (150/N)² (a replica starts at 0.1) …
LANGEVIN_LEG_T_START = 2e-3
#: … for this fraction of a replica's steps (3·10⁵ of the default 10⁶), cooled as a
#: replica to its ``t_end``. Measured on the 96 bead ensembles the 249-knot atlas left
#: unconverged (one leg from each of the four lowest own searches, 384 legs, 1.3 CPU s each):
#: 9 converged; reheated to 10⁻² (three legs each) 6 converged and 28 grounds went lower
#: by > 0.1 % — those legs leave the funnel (docs/history.md)
LANGEVIN_LEG_FRACTION = 0.3
#: Tube-route searches of the bead rule (opt-in: ``tube_route=True``): in a bead-rule run, the
#: new searches of this round on (0-based: the third, the first after the fresh rounds) anneal
#: under the tube rule of diameter w = d and are then polished under the bead rule. A tube
#: chain of w ≥ d is bead-admissible (beads at index distance ≥ 2 begin or end segments that
#: share no bead, at least w apart: proof in :mod:`stiffknots.sweeps.cross`), so such a
#: search is a search of the bead rule's landscape through the tube's smoother one (on 10_1 …
#: 10_8, tube annealings then bead polishes held the lowest bead state of 5 of 8 knots). Such
#: searches confirm a state but do not certify it (:func:`stiffknots.problems.base.verdict`).
#: Not on by default: over the first 20 knots of the survey through 8 crossings it found lower
#: grounds for 6 (7_5: 173.90 against 176.98; 8_2: 166.51 against 167.10) and higher ones for
#: 7 (8_4: 188.08 against 181.49), since it takes the place of the bead rule's own new
#: searches, and converged 13 of 20 against 14 (docs/history.md).
#: From the second round on, two tube-route searches counted like the others "converged" 7_5
#: at 183.65 (CB3): hence the fresh rounds stay the bead rule's own.
TUBE_ROUTE_FROM = 2


@dataclass
class AnnealResult(ReplicaSet):
    """Replicas of one closed knot, best (lowest ε) first."""

    problem: ClassVar[str] = "anneal"

    @property
    def epsilon(self) -> float:
        return self.best.epsilon

    @property
    def thin_limit(self) -> dict:
        """How far the best replica lies from the thin limit of its shape (w = 0, §V B):
        :func:`stiffknots.theory.references.thin_limit_note`."""
        from stiffknots.theory.references import thin_limit_note

        ob = self.best.observables if self.replicas else {}
        return thin_limit_note(self.best.epsilon if self.replicas else None,
                               ob.get("label"), ob.get("multiplicity"),
                               self.width.text if self.width else "a finite width")

    def physics(self) -> dict:
        return super().physics() | {"thin_limit": self.thin_limit}


def checkpoint_path(checkpoint_dir: str | Path, replica: int) -> Path:
    """The checkpoint file of one replica inside ``checkpoint_dir``."""
    return Path(checkpoint_dir) / f"replica_{replica}.ckpt.npz"


class ClosedAnneal(Problem):
    """Annealing of a closed knot (§VII); see :func:`anneal` for the parameters."""

    result_type = AnnealResult

    def __init__(self, knot: str | Knot, beads: int = 150, moves: int | None = None,
                 replicas: int = 2, seed: int = 0, *, schedule: Schedule | None = None,
                 params: MoveParams | None = None, quench_fraction: float = 0.1,
                 target_epsilon: float | None = None,
                 checkpoint_dir: str | Path | None = None, resume: bool = False,
                 checkpoint_seconds: float | None = 60.0,
                 start: str | Sequence[str] = "all", rounds: int = DEFAULT_ROUNDS,
                 agree: int | None = None, rel_tol: float = 1e-3, initial=None,
                 polish: bool = True,
                 tube_route: bool = False, coarse: int | None = None):
        from stiffknots.theory.bounds import closed_bounds

        if initial is not None:  # a curve of the user: named, resampled and checked first
            from stiffknots.problems.relax import prepare_curve

            width = (params or MoveParams()).width(V.beads(beads))
            x, name, self.naming, p0 = prepare_curve(initial, width, knot)
            knot = knot if isinstance(knot, Knot) and knot.name == name else name
            params = params or p0
        self._setup(knot, replicas, seed, beads)
        # the searches a verdict needs: the exclusion model's (base.AGREE: 3 for the tube)
        self._verdict_rule(rounds, agree_for((params or MoveParams()).exclusion)
                           if agree is None else agree, rel_tol)
        self.polish = bool(polish)
        if resume and checkpoint_dir is None:
            raise InvalidParameter("checkpoint_dir", None, "given when resume=True",
                                   "the folder of the checkpoints")
        if checkpoint_seconds is not None:
            V.number("checkpoint_seconds", checkpoint_seconds, 0, lo_open=True)
        if target_epsilon is not None:
            V.number("target_epsilon", target_epsilon)
        if moves is None:
            moves = (LANGEVIN_STEPS if schedule is not None and schedule.kind == "langevin"
                     else default_moves(self.beads))
        self.settings = AnnealSettings(moves=V.moves(moves),
                                       schedule=schedule or Schedule().for_beads(self.beads),
                                       params=(params or MoveParams()).for_beads(self.beads),
                                       quench_fraction=quench_fraction,
                                       target_epsilon=target_epsilon)
        self.settings.validate()
        self.settings.params.validate(self.beads)
        if self.settings.schedule.kind == "langevin" and (
                self.settings.params.exclusion != "bead" or tube_route):
            raise InvalidParameter("schedule", "langevin", "with the bead rule and without the "
                                   "tube route (its dynamics holds beads apart, not tubes)")
        #: the settings of the tube-route searches (:data:`TUBE_ROUTE_FROM`), None without
        self.tube_settings = None
        #: (start, exclusion, d, w) → the start chain's worst exclusion violation
        #: (:meth:`_check_admissible`)
        self._admissible: dict[tuple, float] = {}
        #: every new search first anneals its start at this many beads
        #: (:mod:`stiffknots.problems.coarse`); None: from the start
        self.coarse = None
        if coarse is not None:
            self.coarse = V.integer("coarse", coarse, 3, self.beads - 1)
            if self.settings.schedule.kind in ("tempering", "langevin"):
                raise InvalidParameter("coarse", coarse, "with an annealing schedule "
                                       "(geometric or power)")
        p = self.settings.params
        if tube_route and p.exclusion == "bead" and self.polish:
            from dataclasses import replace

            self.tube_settings = replace(self.settings,
                                         params=replace(p, exclusion="tube", w=p.d))
            self.tube_settings.params.validate(self.beads)
        if initial is None:
            self._closed_starts(start)
            self.adaptive_starts = isinstance(start, str) and start == "all"
        else:
            from stiffknots.problems.base import start_code

            self.starts = ["file"]
            self.chains = {"file": x.coords}
            self.codes = {"file": start_code(self.knot_name, x.coords, True, "file")}
        self.checkpoint_dir = checkpoint_dir
        self.resume = resume
        self.checkpoint_seconds = checkpoint_seconds
        self._bounds = closed_bounds(self.knot.bridge_number, self.knot.braid_index)

    def jobs(self, first: int = 0) -> list[Job]:
        """The replicas ``first`` … of one round; from round :data:`TUBE_ROUTE_FROM` on, a
        bead-rule run's new searches take the tube route."""
        route = (self.tube_settings is not None
                 and first >= TUBE_ROUTE_FROM * self.replicas)
        p = self.settings.params
        for r in range(first, first + self.replicas):
            self._check_admissible(self._start(r), (self.tube_settings if route
                                                    else self.settings).params)
        return self._replica_jobs(
            self.tube_settings if route else self.settings,
            lambda r: self.chains[self._start(r)], self._start,
            lambda r: self.codes[self._start(r)], self.checkpoint_dir, self.resume,
            self.checkpoint_seconds, first, polish_params=p if route else None,
            coarse=self.coarse,
            search=(f"tube rule w = {p.d:.6g}, then polished under the bead rule" if route
                    else None))

    def _check_admissible(self, start: str, params: MoveParams) -> None:
        """Refuse, before any worker starts, a starting embedding that the exclusion rule of
        ``params`` does not admit at this N (the engine would refuse the chain in the worker,
        with a message that names neither the start nor the way out): a braid closure laid
        out in few beads can bring two strands closer than the tube's w where they cross
        (10_101's braid at N = 100: 0.071 too close for w = 1/√2). Checked once per start
        and rule (O(N²) pairs).

        Raises
        ------
        EmbeddingError
            Naming the start, the knot, N, the rule and by how much, and what to change.
        """
        from stiffknots.errors import EmbeddingError

        seen = self._admissible
        key = (start, params.exclusion, params.d, params.w)
        if key not in seen:
            seen[key] = params.violation(self.chains[start])
        viol = seen[key]
        if viol > 1e-12:  # the engine's own threshold (engine.state.ChainState)
            rule = (f"bead rule (beads ≥ d = {params.d:.4g} apart)" if params.exclusion == "bead"
                    else f"tube of diameter w = {params.w:.4g} (segments ≥ w apart)")
            raise EmbeddingError(
                f"the {start} embedding of {self.knot_name} at N = {self.beads} beads is not "
                f"admissible for the {rule}: two strands come {viol:.3g} too close where they "
                "cross; use more beads (--beads, or a larger --coarse), a thinner tube, or "
                "another start")

    def continue_jobs(self, parents: list[Replica], first: int) -> list[Job] | None:
        """Continue each parent's search by :data:`LEG_HOPS` basin hops from its (polished)
        chain: the leg's plan is the hop stage of :class:`Schedule` alone — reheat to
        ``t_hop``, cool geometrically to ``t_end``, quench, polish; the lowest polished chain
        so far is where the next hop starts. None with a tempering or langevin schedule (they
        have no hops)."""
        from dataclasses import replace

        sch = self.settings.schedule
        if sch.kind in ("tempering", "langevin"):
            return None
        leg = replace(sch, kind="geometric", t_start=sch.t_hop, relax_fraction=0.0,
                      hops=LEG_HOPS - 1, hop_fraction=(LEG_HOPS - 1) / LEG_HOPS)
        return self._leg_jobs(parents, first, leg, LEG_FRACTION)

    def _leg_jobs(self, parents: list, first: int, schedule: Schedule,
                  fraction: float) -> list[Job]:
        """One job per parent from its chain and start, replicas ``first`` …, under
        ``schedule`` for ``fraction`` of a replica's moves (≥ 1,000)."""
        from dataclasses import replace

        settings = replace(self.settings, schedule=schedule,
                           moves=V.moves(max(1_000, round(fraction * self.settings.moves))))
        by_index = dict(enumerate(parents, start=first))
        return self._replica_jobs(settings, lambda r: by_index[r].coords,
                                  lambda r: by_index[r].start,
                                  lambda r: self.codes[by_index[r].start],
                                  self.checkpoint_dir, self.resume, self.checkpoint_seconds,
                                  first, count=len(parents))

    def langevin_leg_jobs(self, parents: list, first: int) -> list[Job] | None:
        """Continue each parent's search by the Langevin dynamics from its (polished) chain:
        reheated to :data:`LANGEVIN_LEG_T_START` × (150/N)², cooled to the schedule's
        ``t_end`` over :data:`LANGEVIN_LEG_FRACTION` of a replica's steps, then polished like
        a replica (the atlas's bead legs, :mod:`stiffknots.sweeps.legs`). None unless the
        schedule is ``langevin``. ``anneal``'s own rounds do not use it (their Langevin
        rounds start new searches, as measured: docs/methods/search.md)."""
        from dataclasses import replace

        sch = self.settings.schedule
        if sch.kind != "langevin":
            return None
        t0 = LANGEVIN_LEG_T_START * (150 / self.beads) ** 2
        leg = replace(sch, t_start=max(t0, 2.0 * sch.t_end))
        return self._leg_jobs(parents, first, leg, LANGEVIN_LEG_FRACTION)

    def state_of(self, r: Replica) -> tuple[str, float]:
        return r.observables["shape"], r.epsilon

    def observe(self, r: Replica) -> None:
        observe_shape(r, self.settings.params)

    def bounds(self) -> dict:
        b = self._bounds
        return {"lower": b.lower, "upper": b.upper, "attained_by": b.attained_by}

    def settings_dict(self) -> dict:
        d = {**self.settings.as_dict(), "start": self.starts, "polish": self.polish}
        if self.tube_settings is not None:
            d["tube_route_from_round"] = TUBE_ROUTE_FROM + 1  # 1-based, as the report counts
        if self.coarse is not None:
            d["coarse_per_replica"] = self.coarse
        return d


def anneal(
    knot: str,
    beads: int = 150,
    moves: int | None = None,
    replicas: int = 2,
    seed: int = 0,
    *,
    schedule: Schedule | None = None,
    params: MoveParams | None = None,
    workers: int | None = None,
    quench_fraction: float = 0.1,
    target_epsilon: float | None = None,
    on_replica_done: Callable[[Replica], None] | None = None,
    checkpoint_dir: str | Path | None = None,
    resume: bool = False,
    checkpoint_seconds: float | None = 60.0,
    start: str | Sequence[str] = "all",
    rounds: int = DEFAULT_ROUNDS,
    agree: int | None = None,
    rel_tol: float = 1e-3,
    on_progress: Callable[[dict], None] | None = None,
    initial=None,
    polish: bool = True,
    tube_route: bool = False,
) -> AnnealResult:
    """Anneal ``replicas`` independent chains of ``knot`` and return the verified results.

    Parameters
    ----------
    knot : str
        Knot name in any usual spelling ('4_1', '4.1', 'K11a1', 'T(2,3)').
    beads : int
        Number of beads N (bond length 1, so the chain length L = N).
    moves : int or None
        Attempted moves per replica (annealing plus the final quench); default
        :func:`default_moves` (15 M at N = 150, scaled as N).
    replicas : int
        Independent replicas; they run in parallel on ``workers`` processes
        (default: all cores).
    seed : int
        User seed; replica seeds are derived from it (recorded in every result).
    schedule, params
        Cooling schedule and move/exclusion parameters (defaults documented in
        :class:`Schedule` and :class:`MoveParams`; the default schedule's temperatures scale
        as (150/N)² and the default m_max is N/2, so that the same search runs at any N).
    quench_fraction : float
        Fraction of the moves spent in the final T = 0 quench.
    target_epsilon : float or None
        If given, each replica records the wall time at which ε first fell below.
    on_replica_done : callable or None
        Callback called in the parent process as each replica finishes.
    checkpoint_dir : str or Path or None
        If given, every replica writes ``replica_K.ckpt.npz`` there every 10
        chunks (of 210), every ``checkpoint_seconds`` seconds and when it ends (positions,
        generator state, counters, energy, chunk index, traces, best chain, settings, seed,
        version).
    resume : bool
        Continue every replica from its checkpoint in ``checkpoint_dir`` when there is
        one (the call must repeat the same knot, beads, moves, seed and settings; a mismatch
        raises CheckpointError); the result is exactly that of an uninterrupted run.
    checkpoint_seconds : float or None
        Wall-clock seconds between checkpoints (None: chunks only).
    start : str or sequence of str
        Starting embedding: ``'braid'`` (closure of KnotInfo's braid word), ``'cage'``
        (the 4-fold cage of a two-box rational knot [ab], §VII; see
        :mod:`stiffknots.knots.starts`), ``'eighty'``, ``'all'`` (the default: braid, the cage
        where it exists and the 80 for the knots of the 80 family,
        :func:`stiffknots.knots.starts.default_starts`; replica r of any round takes the
        (r mod k)-th), or one start per replica (a sequence of ``replicas`` names). Recorded in
        the settings and in every replica.
    rounds, agree, rel_tol
        The convergence rule: after each round of ``replicas`` replicas,
        the run stops when the lowest state (its shape class and ε within ``rel_tol``) was
        reached by at least ``agree`` independent searches (default: the exclusion model's,
        :data:`stiffknots.problems.base.AGREE` — 2 for the bead rule, 3 for the tube), and
        otherwise runs another round, up to ``rounds`` rounds; ``rounds=1`` is a fixed
        budget. The result says ``converged`` and
        why (:func:`stiffknots.problems.base.verdict`).
    on_progress : callable or None
        Receives progress records of the running replicas (moves done, best ε).
    initial
        A closed curve (:class:`~stiffknots.chain.Chain` of any bond lengths) to start
        every replica from instead of the built-in embeddings: it is named (``knot`` is then
        checked against it), resampled to ``beads`` unit bonds with its type kept and checked
        (:func:`stiffknots.problems.relax.prepare_curve`).
    polish : bool
        Take every replica's best chain to its local minimum with the final minimiser
        (:func:`stiffknots.engine.polish.polish`; unit bonds and exclusion held exactly, no
        strand passage); its report is in each replica's ``polish``.
    tube_route : bool
        In a bead-rule run (with ``polish``), the new searches from the third round
        on anneal under the tube rule of diameter w = d and are polished under the bead rule
        (:data:`TUBE_ROUTE_FROM`; each such replica says so in ``observables["search"]``);
        default False: every search is the bead rule's own Monte Carlo (the route's grounds
        were lower for some knots, higher for as many, :data:`TUBE_ROUTE_FROM`).

    Returns
    -------
    AnnealResult
        Replicas sorted by ε (best first); ε = E_d·N/C (paper §VII).

    Raises
    ------
    UserInputError
        For a wrong knot name, too few beads (the message gives the minimum), bad parameters.
    TopologyChangedError
        If any replica ends with a different knot type (never expected; see the kernel docs).
    """
    problem = ClosedAnneal(knot, beads, moves, replicas, seed, schedule=schedule, params=params,
                           quench_fraction=quench_fraction, target_epsilon=target_epsilon,
                           checkpoint_dir=checkpoint_dir, resume=resume,
                           checkpoint_seconds=checkpoint_seconds, start=start, rounds=rounds,
                           agree=agree, rel_tol=rel_tol, initial=initial, polish=polish,
                           tube_route=tube_route)
    return solve(problem, workers=workers, on_replica_done=on_replica_done,
                 on_progress=on_progress)
