"""The jobs of a sweep: one per (knot, model, replica), each with its store key known in advance.

A sweep over knots × models runs, for every (knot, model), the closed annealing problem of §VII
(:class:`~stiffknots.problems.closed.ClosedAnneal`: its validation, starting chains, start
polynomials and :class:`~stiffknots.problems.base.Job` objects) with ``budget.replicas``
replicas of ``budget.moves`` moves; the Dask workers build it (:func:`build_jobs`) and run
its jobs. Every replica is one :class:`SweepJob`, whose
:class:`~stiffknots.store.keys.ReplicaKey` — knot, exclusion, N, thickness, seed, replica,
settings hash — is computed *before* anything is built, from :func:`sweep_settings`, so that
a resumed sweep skips the stored replicas without building their problems (:func:`pending`).
The problem of a (knot, model) is built only when one of its replicas is to run
(:func:`build_jobs`), and its settings are then checked against the key's.

Starts. Every replica starts from one of the embeddings that exist for the knot among the
closure of its braid word, the 4-fold cage of a two-box rational knot and the 80 of
:mod:`stiffknots.knots.eighty_embedding` (tried only for the knots of
:data:`~stiffknots.knots.families.EIGHTY_FAMILY`, since a failed search costs seconds, and
not for the n = i knots, whose ground state is the circular braid (§VI C): an 80 start would
spend a replica on a state known to lie above it), shared round-robin among the replicas
(replica r gets start r mod k) — except the replicas added to a (knot, model) not converged
from replica :data:`FAVOUR_FROM` on (by then every start has had a replica): they start from
the embedding of the lowest replica stored before them (:func:`favoured_start`), the funnel
likeliest to hold the ground state a second time (measured in ``anneal``,
docs/methods/search.md). The settings record the policy
(``"start": "braid,cage,eighty;added:lowest"``), each stored row the start its replica got.
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

from stiffknots.engine.driver import AnnealSettings
from stiffknots.errors import InvalidParameter, UserInputError
from stiffknots.problems import validate as V
from stiffknots.problems.base import Job
from stiffknots.store import ReplicaKey, Store, canonical_json, settings_hash
from stiffknots.sweeps.budgets import Budget
from stiffknots.sweeps.models import params_of
from stiffknots.width import Width

__all__ = ["PROBLEM", "START_POLICY", "FAVOUR_FROM", "SweepJob", "sweep_settings",
           "resolve_knots", "plan_sweep", "pending", "sweep_starts", "favoured_start",
           "build_jobs", "build_problem"]

#: The problem every sweep solves (``settings["problem"]``).
PROBLEM = "anneal"
#: The starting embeddings a sweep draws from, in order, and the rule of the added replicas
#: (module docstring).
START_POLICY = "braid,cage,eighty;added:lowest"
#: The first replica that may take the favoured start instead of its round-robin one (there
#: are at most 3 starts: replicas 0, 1, 2 try each once).
FAVOUR_FROM = 3


def sweep_settings(model: Width, budget: Budget, problem: str = PROBLEM) -> dict[str, Any]:
    """The settings of every replica of ``model`` under ``budget`` (the input of the key's
    settings hash): ``AnnealSettings(moves, schedule, params=params_of(model)).as_dict()``, the
    moves and schedule of :meth:`Budget.search_of <stiffknots.sweeps.budgets.Budget.search_of>`
    (the annealing, or the Langevin dynamics of a Langevin bead ensemble) —
    built as ClosedAnneal builds them, which :func:`build_jobs` checks — plus
    ``problem`` and ``start`` (:func:`stiffknots.store.keys.settings_hash` says what belongs
    there). ``problem`` names what the replicas are for: :data:`PROBLEM` (``"anneal"``, a
    sweep's own ensembles) or :data:`~stiffknots.sweeps.audit.AUDIT_PROBLEM` (an audit's
    searches: another ensemble, never mixed into the one it checks)."""
    moves, schedule = budget.search_of(model)
    s = AnnealSettings(moves=moves, schedule=schedule, params=params_of(model))
    s.validate()
    # every replica is polished to its local minimum (problems.base.polish_run)
    out = {**s.as_dict(), "problem": problem, "start": START_POLICY, "polish": True}
    coarse = budget.coarse_of(model)
    if coarse is not None:  # absent otherwise: the keys of every stored replica unchanged
        out["coarse"] = coarse
    return out


@dataclass(frozen=True)
class SweepJob:
    """One replica of one (knot, model) of a sweep, identified by its store key.

    Attributes
    ----------
    knot : str
        Catalogue name.
    model : Width
    replica : int
    seed : int
        The sweep's seed (the replica's own seed derives from it and ``replica``).
    settings : dict
        :func:`sweep_settings` of the model and budget.
    key : ReplicaKey
    start : str or None
        The embedding it starts from when it is not its round-robin one (an added replica,
        :func:`favoured_start`); None: round-robin.
    parent : dict or None
        A continuation leg's parent replica (:mod:`stiffknots.sweeps.legs`,
        :func:`stiffknots.sweeps.legs.leg_job`): its store ``id``, ``replica``, ``search``,
        ``start``, ``epsilon`` and ``coords``; None for a replica that starts from an embedding.
    """

    knot: str
    model: Width
    replica: int
    seed: int
    settings: dict = field(compare=False, hash=False, repr=False)
    key: ReplicaKey = field(compare=False, hash=False, repr=False)
    start: str | None = field(default=None, compare=False, hash=False)
    parent: dict | None = field(default=None, compare=False, hash=False, repr=False)

    @property
    def id(self) -> str:
        """``knot/model/replica`` (for messages); a continuation leg's says which search it
        continues, e.g. ``7_4/tube/leg 1 of r3``."""
        if self.parent is not None:
            from stiffknots.sweeps.legs import LEG_REPLICA

            return (f"{self.knot}/{self.model.exclusion}/leg {self.replica - LEG_REPLICA + 1} of "
                    f"r{self.parent['search']}")
        return f"{self.knot}/{self.model.exclusion}/r{self.replica}"

    @property
    def task_key(self) -> str:
        """A Dask task key unique to the store key (a resubmitted job is the same task)."""
        k = self.key
        return (f"stiffknots-anneal-{k.knot}-{k.exclusion}-{k.thickness_key}-N{k.beads}-"
                f"s{k.seed}-r{k.replica}-{k.settings_hash}")

    @property
    def group(self) -> tuple[str, str]:
        """(knot, model name): the jobs of one problem."""
        return self.knot, self.model.exclusion


def resolve_knots(knots: Iterable[str] | None = None, max_crossings: int | None = None, *,
                  crossings: Iterable[int] | None = None, sample: int | None = None,
                  seed: int = 0) -> list[str]:
    """The catalogue names of a sweep, in table order, each once.

    Parameters
    ----------
    knots : iterable of str, optional
        Knot names in any usual spelling (``4_1``, ``4.1``, ``T(2,3)``).
    max_crossings : int, optional
        Every prime knot with 3 ≤ n_c ≤ ``max_crossings`` (3..13); with ``knots``, only those
        of them with n_c ≤ ``max_crossings``.
    crossings : iterable of int, optional
        Only the knots of these crossing numbers (without ``knots`` or ``max_crossings``:
        every prime knot of them).
    sample : int, optional
        A random sample of this many of the knots (all of them when there are fewer), drawn
        with ``seed``: the same arguments give the same sample, so a sampled sweep resumes.
    seed : int
        Seed of the sample.

    Raises
    ------
    UserInputError
        An unknown knot, the unknot, a knot above ``max_crossings``, a crossing number out of
        range, no knot at all.
    """
    import random

    from stiffknots.knots.catalogue import MAX_CROSSINGS, catalogue, get_knot
    from stiffknots.store import knot_sort_key

    if max_crossings is not None:
        max_crossings = V.integer("max_crossings", max_crossings, 3, MAX_CROSSINGS)
    want = None
    if crossings is not None:
        want = sorted({V.integer("crossings", c, 3, max_crossings or MAX_CROSSINGS)
                       for c in crossings})
        if not want:
            raise InvalidParameter("crossings", "", "at least one crossing number")
    if sample is not None:
        sample = V.integer("sample", sample, 1, 100_000)
    if knots is None:
        if max_crossings is None and want is None:
            raise InvalidParameter("knots", None, "a list of knot names, or max_crossings")
        top = max_crossings if max_crossings is not None else max(want)
        names = [k.name for k in catalogue(top) if k.crossing_number >= 3
                 and (want is None or k.crossing_number in want)]
    else:
        names = []
        for text in knots:
            k = get_knot(str(text).strip())
            if k.crossing_number < 3:
                raise UserInputError(f"{text}: the unknot has no knotted ground state to "
                                     "sweep (its minimum is the circle, ε = 2π²)")
            if max_crossings is not None and k.crossing_number > max_crossings:
                raise UserInputError(f"{k.name} has {k.crossing_number} crossings, more than "
                                     f"max_crossings = {max_crossings}")
            if want is None or k.crossing_number in want:
                names.append(k.name)
        names = list(dict.fromkeys(names))
    if not names:
        raise InvalidParameter("knots", "", "at least one knot name")
    if sample is not None and sample < len(names):
        names = random.Random(seed).sample(names, sample)
    return sorted(names, key=knot_sort_key)


def plan_sweep(knots: Sequence[str], models: Sequence[Width], budget: Budget,
               seed: int = 0, problem: str = PROBLEM) -> list[SweepJob]:
    """Every job of a sweep, knot-major (all replicas of a knot's models, then the next
    knot). Cheap: nothing is built, no embedding is made.

    Parameters
    ----------
    knots : sequence of str
        Catalogue names (:func:`resolve_knots`).
    models : sequence of Width
        The models (:func:`~stiffknots.sweeps.models.parse_models`).
    budget : Budget
        Replicas and moves (:mod:`stiffknots.sweeps.budgets`).
    seed : int
        The sweep's seed (0 ≤ seed < 2⁶³).
    problem : str
        What the replicas are for (:func:`sweep_settings`).
    """
    seed = V.seed(seed)
    budget.validate()
    settings = {m: sweep_settings(m, budget, problem) for m in models}
    hashes = {m: settings_hash(s) for m, s in settings.items()}
    return [SweepJob(k, m, r, seed, settings[m],
                     ReplicaKey(k, m.exclusion, m.beads, m.thickness, seed, r, hashes[m]))
            for k in knots for m in models for r in range(budget.replicas)]


def pending(jobs: Sequence[SweepJob], store: Store) -> list[SweepJob]:
    """The jobs whose key is not in ``store`` (in their order)."""
    if not jobs:
        return []
    hashes = sorted({j.key.settings_hash for j in jobs})
    seeds = sorted({j.seed for j in jobs})
    knots = sorted({j.knot for j in jobs})
    problems = sorted({j.settings["problem"] for j in jobs})
    stored = store.keys(settings_hash=hashes, seed=seeds, problem=problems,
                        knot=knots if len(knots) <= 100 else None)
    return [j for j in jobs if j.key not in stored]


def sweep_starts(knot: Any, beads: int, replicas: int) -> list[str]:
    """One start per replica (module docstring): the embeddings that exist for ``knot`` among
    braid, cage and (for the 80 family, n ≠ i) eighty, round-robin.

    Raises
    ------
    EmbeddingError
        No start fits in ``beads`` beads (the braid closure's message says how many it needs).
    """
    from stiffknots.knots.starts import default_starts, split_replicas

    found = default_starts(knot, beads)
    return split_replicas(found, replicas)


def favoured_start(store: Store, job: SweepJob, before: int) -> str | None:
    """The start of the lowest stored replica of ``job``'s (knot, model) ensemble among
    replicas 0 … ``before`` − 1 — the start an added replica ``job`` takes when
    ``job.replica`` ≥ :data:`FAVOUR_FROM` (module docstring); None otherwise or when none of
    them is stored. Deterministic: it reads only replicas that ended before ``job`` was
    planned, so a resumed sweep gives every replica the same start."""
    if job.replica < FAVOUR_FROM:
        return None
    k = job.key
    rows = [r for r in store.replicas(knot=k.knot, exclusion=k.exclusion, beads=k.beads,
                                      thickness=k.thickness, settings_hash=k.settings_hash,
                                      seed=k.seed)
            if r["replica"] < before]
    if not rows:
        return None
    return min(rows, key=lambda r: (r["epsilon"], r["replica"]))["start"]


def build_jobs(knot: str, model: Width, budget: Budget, seed: int,
               settings: Mapping[str, Any], start: str | None = None) -> dict[int, Job]:
    """The problem's jobs of one (knot, model): replica → :class:`~stiffknots.problems.base.Job`
    (:func:`build_problem`'s jobs)."""
    return {j.replica: j for j in build_problem(knot, model, budget, seed, settings,
                                                start).jobs()}


def build_problem(knot: str, model: Width, budget: Budget, seed: int,
                  settings: Mapping[str, Any], start: str | None = None) -> Any:
    """The problem of one (knot, model): a :class:`~stiffknots.problems.closed.ClosedAnneal`.

    Builds the :class:`~stiffknots.problems.closed.ClosedAnneal` problem (starts, their
    HOMFLY-PT polynomials) and checks that its settings are those of the key. ``start``: every
    replica starts from it (an added replica's favoured start, :func:`favoured_start`)
    instead of the round-robin starts; it must be one of the knot's starts.

    Raises
    ------
    UserInputError
        Through the problem's validation (e.g. an embedding that does not fit).
    RuntimeError
        The problem's settings differ from ``settings`` (a bug: the keys would lie).
    """
    from stiffknots.knots.catalogue import get_knot
    from stiffknots.problems.closed import ClosedAnneal

    k = get_knot(knot)
    starts = sweep_starts(k, model.beads, budget.replicas)
    if start is not None:
        from stiffknots.knots.starts import default_starts

        if start not in default_starts(k, model.beads):
            raise RuntimeError(f"{knot} has no start {start!r} in a sweep; this is a bug in "
                               "stiffknots, please report it")
        starts = [start] * budget.replicas
    moves, schedule = budget.search_of(model)
    problem = ClosedAnneal(k.name, beads=model.beads, moves=moves, schedule=schedule,
                           replicas=budget.replicas, seed=seed, params=params_of(model),
                           start=starts, rounds=1, polish=settings.get("polish", True),
                           tube_route=False,  # a sweep seeds its bead ensembles instead
                           coarse=settings.get("coarse"))
    mine = {key: v for key, v in settings.items()
            if key not in ("problem", "start", "polish", "coarse")}
    if canonical_json(problem.settings.as_dict()) != canonical_json(mine):
        raise RuntimeError(f"the settings of {knot}/{model.exclusion} differ from the sweep's key "
                           "settings; this is a bug in stiffknots, please report it")
    return problem
