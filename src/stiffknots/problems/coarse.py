"""Coarse-to-fine replicas: each search first anneals its start at fewer beads.

A replica with ``Job.coarse = N0`` (N0 < N) runs, before its own search, one annealing of its
starting embedding built at N0 beads — the same exclusion rule and diameter in bond units (a
tube N/N0 times thicker relative to the length, w/L = w/N0), the same moves per bead, the
same cooling scaled to N0 (:meth:`~stiffknots.engine.schedules.Schedule.for_beads`) — then
polishes that chain, resamples it to N unit bonds with its knot type certified
(:func:`~stiffknots.knots.resample.resample`: every Δ-move of the isotopy tested, the HOMFLY-PT
polynomials compared) and starts the fine search from it. Each replica has its own coarse
search, seeded from its own seed, so replicas stay independent and a verdict's agreeing
searches are still independent searches.

Why: at 9–10 crossings the tube's searches from the braid closure fall into funnels 1–20 %
above the lowest states that a search of several times the moves finds now and then; single
coarse-to-fine searches (`anneal --coarse 100`) reached those states on the knots whose
verdicts the audit beat far more often per CPU second than searches of twice the moves
(bench/search_schedules.json; docs/methods/verdicts.md).

A start that does not exist or is not admissible for the rule at N0 (a braid closure laid out
in few beads can bring two strands closer than w where they cross: 10_101's at N0 = 100) is
built at N0 + 5, N0 + 10, … instead, the first N0' < N where it is (:data:`STEP`;
``info["beads"]`` is the N0' used, ``info["asked"]`` the N0 asked). When the stage cannot be
run — no such N0', or the coarse chain does not resample to N admissibly — the replica starts
from its own embedding at N, and says why (``info["used"] = False``, ``info["reason"]``): the
search is then the plain one, never a silent other search.
"""

from __future__ import annotations

import time
from dataclasses import replace

import numpy as np

from stiffknots.engine.driver import AnnealSettings

__all__ = ["STEP", "coarse_settings", "coarse_seed", "coarse_start"]

#: the beads added to N0 while the start is not admissible there (module docstring)
STEP = 5


def coarse_settings(settings: AnnealSettings, beads: int, coarse: int) -> AnnealSettings:
    """The fine replica's ``settings`` at ``coarse`` beads: moves × N0/N (the same moves per
    bead, ≥ 1,000), every temperature × (N/N0)² (the same thermal excess δε ≈ N²T of each
    stage), m_max = N0/2; the exclusion, d and w (bond units) unchanged."""
    p = settings.params
    return replace(settings, moves=max(1000, round(settings.moves * coarse / beads)),
                   schedule=settings.schedule.for_beads(coarse, reference=beads),
                   params=replace(p, m_max=None).for_beads(coarse))


def coarse_seed(seed: int, coarse: int) -> int:
    """The coarse stage's seed, derived from the replica's (another stream than the fine
    search's own)."""
    ss = np.random.SeedSequence([int(seed) % 2**64, 0x5EED_C0A5, int(coarse)])
    return int(ss.generate_state(1, np.uint64)[0] % 2**63)


def coarse_start(knot: str, start: str, settings: AnnealSettings, beads: int, coarse: int,
                 seed: int, replica: int = 0) -> tuple[np.ndarray | None, dict]:
    """The fine search's start from a coarse search (module docstring).

    Returns
    -------
    (coords, info)
        ``coords``: the N-bead chain (unit bonds, admissible, knot type certified), or None
        when the stage could not be run (``info["reason"]`` says why). ``info``: ``asked``
        (N0), ``beads`` (the N0' used), ``used``, and when used ``epsilon`` (the polished
        coarse chain's ε, at w/L = w/N0'), ``seed``, ``moves``, ``wall_seconds`` and
        ``cpu_seconds`` of the stage.
    """
    from stiffknots.chain import Chain
    from stiffknots.engine.driver import run_replica
    from stiffknots.engine.polish import polish
    from stiffknots.engine.prims import energy_chain
    from stiffknots.errors import EmbeddingError
    from stiffknots.knots.catalogue import get_knot
    from stiffknots.knots.resample import ResampleError, resample
    from stiffknots.knots.starts import start_chain

    info: dict = {"asked": int(coarse), "beads": int(coarse), "used": False}
    if not 3 <= coarse < beads:
        raise ValueError(f"the coarse stage needs 3 ≤ N0 < N = {beads}, got {coarse}")
    if settings.schedule.kind in ("tempering", "langevin") or not settings.closed:
        raise ValueError("the coarse stage runs the annealing schedules of closed chains")
    wall0, cpu0 = time.perf_counter(), time.process_time()
    p = settings.params
    x0 = None
    for n0 in range(int(coarse), beads, STEP):
        try:
            x = start_chain(get_knot(knot), start, n0)
        except EmbeddingError:
            continue
        if p.violation(x) <= 1e-12:
            x0, coarse = x, n0
            break
    if x0 is None:
        return None, {**info, "reason": f"no admissible {start} embedding for the "
                                        f"{p.exclusion} rule at N0 = {info['asked']} … "
                                        f"{beads - 1} (in steps of {STEP})"}
    info["beads"] = coarse
    s0 = coarse_settings(settings, beads, coarse)
    seed0 = coarse_seed(seed, coarse)
    raw = run_replica(x0, s0, seed0, replica)
    # the final minimiser of every replica (problems.base.polish_run), at N0
    x = polish(raw.coords, closed=True, exclusion=p.exclusion, d=p.d, w=p.w).pos
    eps = float(energy_chain(x, False)) * len(x)
    try:
        y = resample(Chain(x, True), beads).coords
    except ResampleError as exc:
        return None, {**info, "reason": f"the coarse chain does not resample to {beads}: {exc}"}
    if p.violation(y) > 1e-12:
        return None, {**info, "reason": f"the coarse chain resampled to {beads} beads is not "
                                        f"admissible for the {p.exclusion} rule"}
    return y, {**info, "used": True, "epsilon": eps, "seed": seed0,
               "moves": s0.moves, "wall_seconds": time.perf_counter() - wall0,
               "cpu_seconds": time.process_time() - cpu0}
