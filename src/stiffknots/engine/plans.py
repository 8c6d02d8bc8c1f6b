"""Plans: a replica's run as a fixed list of chunks (moves, temperature), from its settings.

A plan depends on the settings (:class:`~stiffknots.engine.settings.AnnealSettings`) alone, so
a resumed run follows the same chunks as an uninterrupted one
(:mod:`stiffknots.engine.checkpoints`); the run loop (:mod:`stiffknots.engine.driver`) runs
them on one state.

``anneal`` (the default): two stages, each ending with a T = 0 quench (see
:mod:`stiffknots.engine.schedules`): a low-temperature relaxation of the starting chain, then
the annealing from a hot start; optionally followed by basin hops (``Schedule.hops``), each
restarting from the lowest chain so far. The result is the lowest candidate: the quenched
chain of each stage — with hops, the quenched chain taken to its local minimum by the final
minimiser, and the starting chain too, so that a run that continues a search never ends above
its start.

``tight`` (the restricted-curvature search of §IX D): a continuation in p of the energy
Σ((1 − cos θ)/s)^p — p = 1 is the bending energy annealed with the schedule, then each higher
p re-seeds the generator, takes s from the 90th percentile of the current turning angles and
anneals geometrically from 10⁻² to 10⁻⁵ times the energy per bead at its start — and a final
ratchet quench whose curvature limit θ_max follows the largest turning angle down after every
chunk.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from stiffknots.engine.params import MoveParams
from stiffknots.engine.prims import turning_cosines
from stiffknots.engine.settings import AnnealSettings

QUENCH_CHUNKS = 10
TIGHT_CHUNKS = 100  # chunks per power of the ``tight`` plan
RATCHET_CHUNKS = 20  # chunks of its final ratchet quench
TIGHT_SEED_STRIDE = 7919  # stage k of the ``tight`` plan re-seeds with seed + 7919·k


@dataclass(frozen=True)
class Step:
    """One chunk of a run's plan: ``moves`` attempted at ``temperature`` (0: quench).

    ``last`` marks the last chunk of a stage whose chain is a candidate result. ``setup``
    (``tight`` plan, a stage's first chunk): ``(energy, power, k)`` — switch to that energy
    (the power energy takes its scale from the current angles) and re-seed with
    seed + 7919·k. ``t_factor``: the temperature is ``e_ref·temperature·t_factor`` with
    ``e_ref`` the energy per bead at the stage's setup (None: absolute). ``ratchet``: after
    the chunk, lower the curvature limit θ_max to the largest turning angle.
    ``restore_best`` (a basin hop's first chunk): start the chunk from the lowest candidate
    chain found so far (``stiffknots.engine.driver._candidate()``) (the chain is replaced
    by it; the generator runs on).
    """

    moves: int
    temperature: float
    stage: str
    last: bool = False
    setup: tuple | None = None
    t_factor: float | None = None
    ratchet: bool = False
    restore_best: bool = False


def _split(total: int, parts: int) -> list[int]:
    """``total`` moves in ``parts`` chunks whose sizes differ by at most one."""
    parts = max(1, parts)
    q, r = divmod(total, parts)
    return [q + (1 if c < r else 0) for c in range(parts)]


def plan_steps(settings: AnnealSettings) -> list[Step]:
    """The chunks of a run: the ``anneal`` plan (relaxation stage if any, annealing stage,
    quenches; ``settings.n_chunks`` annealing chunks and 10 quench chunks in all, shared
    between the stages in proportion to their moves, adding up to ``settings.moves``) or the
    ``tight`` plan (module docstring)."""
    if settings.plan == "tight":
        return _tight_steps(settings)
    sch = settings.schedule
    total = int(settings.moves)
    stages = sch.stages
    if stages == ("tempering",):
        raise ValueError("a tempering schedule has no annealing plan (see engine.tempering)")
    if stages == ("langevin",):
        raise ValueError("a langevin schedule has no annealing plan (see engine.langevin)")
    fr = sch.stage_fractions()
    moves = {s: int(total * fr[s]) for s in stages}
    moves["anneal"] = total - sum(v for s, v in moves.items() if s != "anneal")
    nch = settings.n_chunks
    # the relaxation and the annealing share n_chunks chunks and QUENCH_CHUNKS quench chunks
    # in proportion to their moves; a hop gets its share of n_chunks (at least 2) and 1 quench
    ra = [s for s in stages if not s.startswith("hop")]
    hops = [s for s in stages if s.startswith("hop")]
    chunks = {s: max(2, round(nch * fr[s])) for s in hops}
    chunks["anneal"] = nch
    quench = {s: 1 for s in hops}
    quench["anneal"] = QUENCH_CHUNKS
    if "relax" in ra:
        share = fr["relax"] / (fr["relax"] + fr["anneal"])
        chunks["relax"] = min(max(1, round(nch * share)), max(1, nch - 1))
        chunks["anneal"] = max(1, nch - chunks["relax"])
        quench["relax"] = min(max(1, round(QUENCH_CHUNKS * share)), QUENCH_CHUNKS - 1)
        quench["anneal"] = QUENCH_CHUNKS - quench["relax"]
    temperature = {"relax": sch.relax_temperature, "anneal": sch.temperature}
    steps: list[Step] = []
    for s in stages:
        nq = int(moves[s] * settings.quench_fraction)
        na = moves[s] - nq
        k = chunks[s]
        sizes = _split(na, k)
        for c, m in enumerate(sizes):
            x = (c + 0.5) / k
            t = (temperature[s](x) if s in temperature
                 else sch.hop_temperature(x, int(s.removeprefix("hop"))))
            steps.append(Step(m, float(t), s, restore_best=(c == 0 and s in hops)))
        if nq > 0:
            for m in _split(nq, min(quench[s], nq)):
                steps.append(Step(m, 0.0, s))
        steps[-1] = replace(steps[-1], last=True)
    return steps


def _tight_steps(settings: AnnealSettings) -> list[Step]:
    """The ``tight`` plan: each power p of ``settings.powers`` gets an equal share of the
    moves in 100 chunks (p = 1: the schedule's annealing; p > 1: geometric from 10⁻² to 10⁻⁵
    of the energy per bead), then the ratchet quench gets one more share in 20 chunks."""
    powers = tuple(int(p) for p in settings.powers)
    per_stage = max(1000, int(settings.moves) // (len(powers) + 1))
    sch = settings.schedule
    steps: list[Step] = []
    for k, p in enumerate(powers):
        setup = ("bending" if p == 1 else "power", p, k)
        for c in range(TIGHT_CHUNKS):
            first = setup if c == 0 else None
            if p == 1:  # the paper's annealing of the bending energy: a smooth start
                steps.append(Step(per_stage // TIGHT_CHUNKS,
                                  float(sch.temperature((c + 0.5) / TIGHT_CHUNKS)), f"p{p}",
                                  setup=first))
            else:
                steps.append(Step(per_stage // TIGHT_CHUNKS, 1e-2, f"p{p}", setup=first,
                                  t_factor=1e-3 ** (c / TIGHT_CHUNKS)))
    for _ in range(RATCHET_CHUNKS):
        steps.append(Step(per_stage // RATCHET_CHUNKS, 0.0, "ratchet", ratchet=True))
    steps[-1] = replace(steps[-1], last=True)
    return steps


def stage_params(params: MoveParams, energy: str, power: int, pos: np.ndarray,
                 closed: bool = True) -> MoveParams:
    """The parameters of a ``tight`` stage: the bending energy, or the power energy with its
    scale s = 1 − cos θ₉₀ (θ₉₀ the 90th percentile of the current turning angles, so that the
    energies stay of order one)."""
    if energy == "bending":
        return replace(params, energy="bending")
    th90 = float(np.percentile(np.arccos(np.clip(turning_cosines(pos, not closed), -1, 1)), 90))
    return replace(params, energy="power", power=int(power),
                   energy_scale=float(1 - np.cos(max(th90, 1e-3))))
