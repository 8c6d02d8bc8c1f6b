"""What ``stiffknots anneal`` runs, decided once from its options: the knot, the width, the N
rule, the schedule, the cross-checks of the options and the coarse-to-fine stage.

:func:`plan_anneal` takes the options as the user gave them (None: not given), checks every one
of them and how they combine before any work, and returns an :class:`AnnealPlan` whose
:meth:`~AnnealPlan.problem` is the :class:`~stiffknots.problems.closed.ClosedAnneal` to solve.
Errors name the API's parameters (:class:`~stiffknots.errors.InvalidParameter`,
:class:`~stiffknots.errors.ParameterConflict`); the command line re-words them with its
options' names.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any

from stiffknots.chain import Chain
from stiffknots.engine.params import MoveParams
from stiffknots.engine.schedules import SCHEDULES, Schedule
from stiffknots.errors import InvalidParameter, ParameterConflict
from stiffknots.knots.catalogue import Knot, get_knot
from stiffknots.problems import validate as V
from stiffknots.problems.closed import (
    DEFAULT_ROUNDS,
    LANGEVIN_ROUNDS,
    ClosedAnneal,
    langevin_schedule,
)
from stiffknots.width import Width

__all__ = ["AnnealPlan", "CoarseStart", "beads_for_knot", "plan_anneal"]

#: the schedules a plan accepts by name: ``auto`` and every schedule of the engine
SCHEDULE_CHOICES = ("auto", *SCHEDULES)
#: the rounds of the coarse stage (:meth:`AnnealPlan.coarse_problem`): every default start
COARSE_ROUNDS = 2


def read_curve(path: str | Path) -> Chain:
    """The closed curve in a file (any format of :func:`stiffknots.formats.load`), for
    ``initial=``.

    Raises
    ------
    ParameterConflict
        No file name, an unreadable file, or a curve read as open; the message names the
        parameter (``--from`` on the command line) and the file.
    """
    from stiffknots.errors import ChainFormatError
    from stiffknots.formats import load

    def esc(text) -> str:
        return str(text).replace("{", "{{").replace("}", "}}")

    if not str(path).strip():
        raise ParameterConflict("{} must name a curve file, got ''", "initial")
    try:
        curve = load(path)
    except ChainFormatError as exc:
        raise ParameterConflict("{} " + esc(exc), "initial") from None
    if not curve.closed:
        raise ParameterConflict("{} " + esc(path) + ": the curve was read as open; anneal "
                                "takes a closed curve (a knot)", "initial")
    return curve


def beads_for_knot(knot: Knot, w_over_L: float,  # noqa: N803
                   rel_error: float = V.DISCRETISATION_REL_ERROR) -> int:
    """The N rule at fixed w/L (:func:`~stiffknots.problems.validate.beads_for_width`) with
    the knot's upper bound 2π² min(α²n², i²) (§VI) as the energy estimate, or 4× its lower
    bound where the catalogue gives no upper one."""
    from stiffknots.theory.bounds import closed_bounds

    b = closed_bounds(knot.bridge_number, knot.braid_index)
    eps = b.upper if b.upper is not None else 4 * b.lower
    return V.beads_for_width(w_over_L, eps, rel_error)


#: A replica's search estimated to take at most this many CPU seconds runs in the calling
#: process (:meth:`AnnealPlan.quick`): a worker process costs more than that before its
#: first move (docs/benchmarks.md), and Ctrl-C still stops such a search within a second.
QUICK_SEARCH_SECONDS = 1.0
#: … and has at most this many beads (the final minimiser's steps, which Ctrl-C waits for in
#: this process, grow with N)
QUICK_BEADS = 1000
#: CPU seconds of the search, per Monte Carlo move and per Langevin bead-step (N = 150; the
#: moves/s of bench/moves_at_any_n.json and the Langevin replicas of the atlas: ≈ 4 CPU s
#: per 10⁶ steps at N = 150).
SECONDS_PER_MOVE = 0.67e-6
SECONDS_PER_BEAD_STEP = 4.0 / (1e6 * 150)


@dataclass(frozen=True)
class CoarseStart:
    """The start the coarse stage gives the fine run: the chain and what to report of it."""

    chain: Chain
    info: dict[str, Any]


@dataclass
class AnnealPlan:
    """A checked ``anneal`` request (:func:`plan_anneal`): everything the run needs.

    Attributes
    ----------
    knot : Knot
        The catalogue entry, resolved once.
    width : Width
        The exclusion model, its thickness, N and w/L.
    schedule : Schedule
        The cooling schedule (its ``kind`` the schedule that runs).
    chosen_by : str
        Why this schedule: ``"named"`` (given by name), ``"auto"`` (the default
        search) or ``"monte_carlo"`` (auto, and an option of the Monte Carlo was given: then
        :attr:`monte_carlo` names them).
    monte_carlo : list of str
        The parameters given that only the Monte Carlo has (``"exclusion"`` stands
        for the tube model), in the order of :func:`plan_anneal`'s signature.
    rounds : int
        The most rounds.
    params : MoveParams
        The moves and the exclusion model.
    coarse : int or None
        The bead count of the coarse stage, or None.
    initial : Chain or None
        The user's curve every replica starts from, or None.
    """

    knot: Knot
    width: Width
    schedule: Schedule
    chosen_by: str
    monte_carlo: list[str]
    rounds: int
    params: MoveParams
    moves: int | None
    replicas: int
    seed: int
    start: str | Sequence[str]
    polish: bool
    tube_route: bool
    checkpoint_dir: Path | None
    resume: bool
    coarse: int | None
    initial: Chain | None
    problem_kwargs: dict[str, Any] = field(default_factory=dict)

    @property
    def beads(self) -> int:
        return self.width.beads

    def quick(self) -> bool:
        """Whether the run is one short search at a time: one replica a round, no coarse
        stage, at most :data:`QUICK_BEADS` beads, its moves given and estimated at most
        :data:`QUICK_SEARCH_SECONDS` CPU seconds. Such a run is best done in the calling
        process (``solve(..., isolate=False)``): starting a worker process would cost more
        than the search."""
        if (self.moves is None or self.coarse is not None or self.replicas != 1
                or self.beads > QUICK_BEADS):
            return False
        per = (SECONDS_PER_BEAD_STEP * self.beads if self.schedule.kind == "langevin"
               else SECONDS_PER_MOVE)
        return self.moves * per <= QUICK_SEARCH_SECONDS

    def problem(self, initial: Chain | None = None) -> ClosedAnneal:
        """The fine run: from ``initial`` (the coarse stage's chain) or the plan's own curve or
        the built-in embeddings."""
        return ClosedAnneal(self.knot, beads=self.beads, moves=self.moves,
                            replicas=self.replicas, seed=self.seed, schedule=self.schedule,
                            params=self.params, checkpoint_dir=self.checkpoint_dir,
                            resume=self.resume, start=self.start, rounds=self.rounds,
                            initial=initial if initial is not None else self.initial,
                            polish=self.polish, tube_route=self.tube_route)

    def coarse_problem(self) -> ClosedAnneal:
        """The coarse stage (``coarse`` beads): the default moves and schedule of that N,
        :data:`COARSE_ROUNDS` rounds (every default start tried), the fine run's exclusion,
        diameter in bond units and δ with the default m_max of that N, the same seed."""
        if self.coarse is None:
            raise ValueError("this plan has no coarse stage")
        return ClosedAnneal(self.knot, beads=self.coarse, replicas=self.replicas,
                            seed=self.seed, params=replace(self.params, m_max=None),
                            start=self.start, rounds=COARSE_ROUNDS, polish=self.polish)

    def coarse_start(self, res) -> CoarseStart:
        """The fine run's start from the coarse stage's result ``res``: its lowest chain that
        resamples to the fine N with its knot type certified and the fine run's exclusion rule
        held. A bead-rule chain whose strands touch at a crossing (10⁻⁴ apart in some 4_1
        states) cannot be: the next lowest is taken, and ``info`` says so.

        Raises
        ------
        ParameterConflict
            No coarse chain resamples so.
        """
        from stiffknots.knots.resample import ResampleError, resample

        p = self.params
        for r in res.replicas:  # lowest first
            try:
                x = resample(Chain(r.coords, True), self.beads)
            except ResampleError:
                continue
            # new beads near a touching crossing come closer than d to the other strand
            if (x.min_bead_distance() >= p.d if p.exclusion == "bead"
                    else x.min_segment_distance() >= p.w):
                break
        else:
            raise ParameterConflict(
                f"{{}} {self.coarse}: none of the {len(res.replicas)} coarse chains of "
                f"{res.knot} resamples to {self.beads} beads with its knot type certified and "
                "the exclusion rule held (strands touch where they cross); run without {}",
                "coarse", "coarse")
        obs = r.observables
        info = {"beads": self.coarse, "epsilon": r.epsilon, "shape": obs["shape"],
                "lowest_epsilon": res.best.epsilon, "replica": r.replica,
                "converged": res.converged, "convergence": res.convergence,
                "width": res.width.as_dict(), "replicas": len(res.replicas),
                "wall_time": res.wall_time}
        return CoarseStart(Chain(r.coords, True), info)


def plan_anneal(knot: Knot | str, *, beads: int | None = None, moves: int | None = None,
                replicas: int = 2, seed: int = 0, exclusion: str = "bead",
                w: float | None = None, w_over_L: float | None = None,  # noqa: N803
                schedule: str = "auto", rounds: int | None = None,
                t_start: float | None = None, t_end: float | None = None,
                relax_fraction: float | None = None, delta: float | None = None,
                m_max: int | None = None, checkpoint_dir: str | Path | None = None,
                resume: bool = False, start: str | Sequence[str] = "all",
                polish: bool = True, tube_route: bool = False,
                initial: Chain | str | Path | None = None, coarse: int | None = None
                ) -> AnnealPlan:
    """Check an ``anneal`` request and decide what runs.

    Parameters
    ----------
    knot : Knot or str
        The knot (a catalogue entry or any usual spelling of its name).
    beads : int or None
        N; default 150, or with ``w_over_L`` the N rule (:func:`beads_for_knot`:
        discretisation error ε/(6N²) below 0.1 %).
    exclusion, w, w_over_L
        The width (:func:`~stiffknots.problems.validate.width`);
        ``w_over_L`` sets the tube model.
    schedule : str
        ``"auto"`` — the Langevin dynamics for the bead rule, the paper's Monte Carlo
        annealing (geometric cooling, §VII) when an option that only the Monte Carlo has is
        given (the tube model, ``tube_route``, ``checkpoint_dir``, ``relax_fraction``,
        ``delta``, ``m_max``, ``coarse``) — or a schedule by name
        (:data:`~stiffknots.engine.schedules.SCHEDULES`).
    rounds : int or None
        The most rounds (default :data:`~stiffknots.problems.closed.LANGEVIN_ROUNDS` for
        the Langevin schedule, :data:`~stiffknots.problems.closed.DEFAULT_ROUNDS` otherwise).
    t_start, t_end, relax_fraction : float or None
        The schedule's (None: its defaults at this N).
    delta, m_max
        The Monte Carlo moves' (None: defaults).
    initial : Chain or str or Path or None
        A closed curve every replica starts from (``knot`` is checked against it), or
        the file that holds it (:func:`read_curve`, read after every other check).
    coarse : int or None
        Anneal first at this many beads and start the fine run from the lowest chain
        (:meth:`AnnealPlan.coarse_start`).
    moves, replicas, seed, checkpoint_dir, resume, start, polish, tube_route
        The others: :class:`~stiffknots.problems.closed.ClosedAnneal`.

    Raises
    ------
    InvalidParameter, ParameterConflict, UnknownKnotError, UserInputError
        Before any work, for anything the run would refuse.
    """
    k = knot if isinstance(knot, Knot) else get_knot(knot)
    replicas, seed = V.replicas(replicas), V.seed(seed)
    if w_over_L is not None and w is None and beads is None:
        beads = beads_for_knot(k, w_over_L)
    width = V.width(150 if beads is None else beads, "tube" if w_over_L is not None
                    else exclusion, w=w, w_over_L=w_over_L)
    n = width.beads
    if moves is not None:
        moves = V.moves(moves)
    if isinstance(start, str):
        from stiffknots.knots.starts import STARTS

        V.choice("start", start, ("all", *STARTS))
    V.choice("schedule", schedule, SCHEDULE_CHOICES)
    monte_carlo = [name for name, given in (
        ("w_over_L" if w_over_L is not None else "exclusion", width.exclusion == "tube"),
        ("tube_route", tube_route), ("checkpoint_dir", checkpoint_dir is not None),
        ("relax_fraction", relax_fraction is not None), ("delta", delta is not None),
        ("m_max", m_max is not None), ("coarse", coarse is not None)) if given]
    if schedule != "auto":
        kind, chosen_by = schedule, "named"
    elif monte_carlo:
        kind, chosen_by = "geometric", "monte_carlo"
    else:
        kind, chosen_by = "langevin", "auto"
    if rounds is None:
        rounds = LANGEVIN_ROUNDS if kind == "langevin" else DEFAULT_ROUNDS
    rounds = V.integer("rounds", rounds, 1, V.MAX_ROUNDS)
    if kind in ("tempering", "langevin") and relax_fraction is not None:
        raise ParameterConflict(f"{{}} applies to the power and geometric schedules ({kind} "
                                "has no relaxation stage)", "relax_fraction")
    if kind == "langevin":
        if width.exclusion != "bead" or tube_route:
            raise ParameterConflict("{} langevin runs the bead rule (its dynamics holds beads "
                                    "apart, not tubes): drop {} tube, {}, {} and {}",
                                    "schedule", "exclusion", "w", "w_over_L", "tube_route")
        if checkpoint_dir is not None:
            raise ParameterConflict("{} applies to the Monte Carlo schedules (a langevin "
                                    "replica takes seconds)", "checkpoint_dir")
        if delta is not None or m_max is not None:
            raise ParameterConflict("{} and {} set the Monte Carlo moves; the langevin "
                                    "schedule has none (drop them, or give {} geometric)",
                                    "delta", "m_max", "schedule")
        if t_end is None:
            t_end = langevin_schedule(n).t_end
            if t_start is not None and t_end >= t_start:
                raise ParameterConflict(f"{{}} must lie above the langevin schedule's final "
                                        f"temperature {t_end:g} (or give {{}}), got "
                                        f"{t_start:g}", "t_start", "t_end")
    given = {"t_start": t_start, "t_end": t_end, "relax_fraction": relax_fraction}
    sch = replace(Schedule().for_beads(n), kind=kind,
                  **{key: v for key, v in given.items() if v is not None})
    params = MoveParams(**({} if delta is None else {"delta": delta}),
                        **({} if m_max is None else {"m_max": m_max})).at_width(width)
    if m_max is not None and not 1 <= m_max <= n - 3:
        raise InvalidParameter("m_max", m_max, f"an integer in [1, {n - 3}]",
                               f"N − 3 for {n} beads")
    if coarse is not None:
        coarse = V.beads(coarse, "coarse")
        if coarse >= n:
            raise ParameterConflict(f"{{}} must be fewer beads than {{}} ({n}), got {coarse}",
                                    "coarse", "beads")
        if initial is not None:
            raise ParameterConflict("{} and {} both give the starting chain; give one",
                                    "coarse", "initial")
        if w_over_L is not None:
            raise ParameterConflict("{} keeps the tube's diameter w in bond units (a thicker "
                                    "knot at fewer beads); give {}, not {}", "coarse", "w",
                                    "w_over_L")
    if isinstance(initial, str | Path):
        initial = read_curve(initial)
    return AnnealPlan(knot=k, width=width, schedule=sch, chosen_by=chosen_by,
                      monte_carlo=monte_carlo, rounds=rounds, params=params, moves=moves,
                      replicas=replicas, seed=seed, start=start, polish=bool(polish),
                      tube_route=bool(tube_route),
                      checkpoint_dir=None if checkpoint_dir is None else Path(checkpoint_dir),
                      resume=bool(resume), coarse=coarse, initial=initial)
