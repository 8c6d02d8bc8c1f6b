"""Parallel tempering (replica exchange) for the closed bead chain of paper §VII.

K copies of the chain (:class:`~stiffknots.engine.state.ChainState`) sit at the fixed
temperatures of a ladder T_0 < T_1 < … < T_{K−1} (:meth:`.Schedule.ladder`, geometric from
``t_end`` to ``t_start``). A *round* runs every copy for the same number of moves at its own
temperature, then attempts to exchange the configurations of neighbouring temperatures: the
pairs (0, 1), (2, 3), … on even rounds and (1, 2), (3, 4), … on odd rounds (the deterministic
even/odd scheme). An exchange of the chains at T_k and T_{k+1}, with energies E_k and E_{k+1}
(units of C), is accepted with the Metropolis probability

    p = min(1, exp[(1/T_k − 1/T_{k+1}) (E_k − E_{k+1})]),

which keeps the product of the Boltzmann distributions exp(−E/T_k) of the copies invariant
(detailed balance in the extended ensemble): a colder copy always accepts a lower energy, and
equal temperatures or equal energies always swap. Hot copies cross barriers (they reshape the
chain), cold ones relax, and exchanges carry good shapes down the ladder. After the last round
the copy of lowest energy is quenched at T = 0 (``quench_fraction`` of the moves) and returned.

The move budget ``settings.moves`` is shared by the K copies (each gets about 1/K of it), so a
tempering run costs the CPU time of one annealing run of the same ``moves`` and the two can be
compared per CPU-second (docs/methods/search.md). Swap attempts and acceptances are counted per
neighbour pair; the random numbers of the swaps come from their own xoshiro256+ stream, so a
run is reproducible from its seed and can be checkpointed and resumed exactly like an
annealing run (:mod:`stiffknots.engine.checkpoints`).
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from stiffknots.engine import checkpoints
from stiffknots.engine import prims as K
from stiffknots.engine.driver import (
    TRACE_KEYS,
    Clock,
    ReplicaResult,
    check_chain,
    make_result,
    resync,
)
from stiffknots.engine.settings import AnnealSettings
from stiffknots.engine.state import ChainState
from stiffknots.errors import RunStopped

_STATE_KEYS = ("pos", "rng", "counters", "end_counters", "slide_counters", "energy",
               "total_energy")


def swap_probability(t_cold: float, t_hot: float, e_cold: float, e_hot: float) -> float:
    """Metropolis probability of exchanging the chains at ``t_cold`` and ``t_hot``.

    min(1, exp[(1/t_cold − 1/t_hot)(e_cold − e_hot)]): 1 when the colder chain has the higher
    energy, when the temperatures are equal or when the energies are equal.
    """
    x = (1.0 / t_cold - 1.0 / t_hot) * (e_cold - e_hot)
    if x >= 0.0:
        return 1.0
    return math.exp(x) if x > -700.0 else 0.0


def attempt_swaps(states: list[ChainState], temps: np.ndarray, parity: int, rng: np.ndarray,
                  tried: np.ndarray, accepted: np.ndarray, order: np.ndarray) -> None:
    """Attempt the exchanges (k, k+1) for k = parity, parity + 2, … (in place).

    ``states[k]`` is the chain at ``temps[k]``; an accepted exchange swaps ``states[k]`` and
    ``states[k+1]`` (the chains, with their generators and counters) and ``order`` (which
    starting copy sits at each temperature). ``rng`` is a xoshiro256+ state (kernel).
    """
    for k in range(parity, len(states) - 1, 2):
        p = swap_probability(temps[k], temps[k + 1], states[k].energy, states[k + 1].energy)
        tried[k] += 1
        u = float(K.uniforms(rng, 1)[0])
        if u < p:
            accepted[k] += 1
            states[k], states[k + 1] = states[k + 1], states[k]
            order[k], order[k + 1] = order[k + 1], order[k]


def copy_seeds(seed: int, n: int) -> list[int]:
    """Seeds of the K copies and of the swap stream (index n), derived from ``seed``."""
    ss = np.random.SeedSequence([int(seed) & (2**63 - 1), 0x7E3])
    return [int(s.generate_state(1, dtype=np.uint64)[0] >> np.uint64(1))
            for s in ss.spawn(n + 1)]


def tempering_plan(settings: AnnealSettings) -> tuple[int, int, list[int]]:
    """(rounds, moves per copy per round, quench chunk sizes) of a tempering run."""
    kk = settings.schedule.n_temps
    total = int(settings.moves)
    nq = int(total * settings.quench_fraction)
    rounds = settings.n_chunks
    per = max(1, (total - nq) // (kk * rounds))
    q = [nq // 10] * 10 if nq >= 10 else ([nq] if nq > 0 else [])
    return rounds, per, q


def run_tempering(coords: np.ndarray, settings: AnnealSettings, seed: int, replica: int = 0,
                  *, checkpoint: str | Path | None = None, checkpoint_every: int | None = None,
                  checkpoint_seconds: float | None = None, resume: bool = False,
                  stop_after: int | None = None) -> ReplicaResult:
    """Replica exchange on ``settings.schedule.ladder()``, then a quench of the best copy.

    Same arguments, checkpoints and result as :func:`stiffknots.engine.driver.run_replica`
    (one chunk = one round of moves and exchanges). The traces follow the coldest temperature
    (moves counted over all copies); ``result.tempering`` holds the ladder, the swap
    acceptance of each neighbour pair and the number of rounds.
    """
    settings.validate()
    sch = settings.schedule
    temps = sch.ladder()
    kk = len(temps)
    rounds, per, quench = tempering_plan(settings)
    n_steps = rounds + len(quench)
    ck = checkpoints.Checkpointer(checkpoint, checkpoint_every, checkpoint_seconds)
    expected = checkpoints.run_meta("tempering", settings, seed, replica, coords)
    seeds = copy_seeds(seed, kk)
    traces: dict[str, list] = {k: [] for k in TRACE_KEYS}
    tried = np.zeros(kk - 1, dtype=np.int64)
    accepted = np.zeros(kk - 1, dtype=np.int64)
    order = np.arange(kk, dtype=np.int64)
    swap_rng = K.new_rng_state(seeds[kk])
    step0 = 0
    done = 0
    hit = (None, None)
    clock = Clock()
    resumed = None
    chosen = -1  # index of the copy being quenched (after the rounds)
    if resume and ck.path is not None and ck.path.exists():
        arrays, meta = checkpoints.load_checkpoint(ck.path)
        checkpoints.check_resumable(meta, expected, ck.path)
        states = [checkpoints.restore_state({key: v[k] for key, v in arrays.items()
                                             if key in _STATE_KEYS}, settings) for k in range(kk)]
        swap_rng = np.asarray(arrays["swap_rng"], dtype=np.uint64).copy()
        tried = arrays["swap_tried"].astype(np.int64)
        accepted = arrays["swap_accepted"].astype(np.int64)
        order = arrays["order"].astype(np.int64)
        traces = {k: list(arrays[f"trace_{k}"]) for k in TRACE_KEYS}
        step0, done, chosen = int(meta["step"]), int(meta["done"]), int(meta["chosen"])
        hit = (meta["seconds_to_target"], meta["cpu_seconds_to_target"])
        clock = Clock(meta["wall"], meta["cpu"])
        resumed = step0
    else:
        states = [ChainState(coords, settings.params, seed=seeds[k], ensemble=settings.ensemble)
                  for k in range(kk)]
    target = settings.target_epsilon

    def save(step: int) -> Path:
        per_copy = [checkpoints.state_arrays(s) for s in states]
        arrays = {key: np.stack([a[key] for a in per_copy]) for key in _STATE_KEYS}
        arrays.update({"swap_rng": swap_rng, "swap_tried": tried, "swap_accepted": accepted,
                       "order": order})
        arrays.update({f"trace_{k}": np.asarray(v) for k, v in traces.items()})
        meta = dict(expected, step=step, n_steps=n_steps, done=done, chosen=chosen,
                    wall=clock.wall(), cpu=clock.cpu(), seconds_to_target=hit[0],
                    cpu_seconds_to_target=hit[1])
        p = checkpoints.save_checkpoint(ck.path, arrays, meta)
        ck.written()
        return p

    def record(temperature: float, eps: float) -> None:
        nonlocal hit
        traces["moves"].append(done)
        traces["temperature"].append(temperature)
        traces["epsilon"].append(eps)
        traces["seconds"].append(clock.wall())
        if target is not None and hit[0] is None and eps <= target:
            hit = (clock.wall(), clock.cpu())

    ran = 0
    for i in range(step0, n_steps):
        if i < rounds:
            for k in range(kk):
                peak = abs(states[k].energy)
                states[k].run(per, float(temps[k]))
                resync(states[k], max(peak, abs(states[k].energy)))
            done += per * kk
            attempt_swaps(states, temps, i % 2, swap_rng, tried, accepted, order)
            record(float(temps[0]), min(s.epsilon for s in states))
        else:
            if chosen < 0:
                chosen = int(np.argmin([s.energy for s in states]))
            s = states[chosen]
            peak = abs(s.energy)
            s.run(quench[i - rounds], 0.0)
            resync(s, max(peak, abs(s.energy)))
            done += quench[i - rounds]
            record(0.0, s.epsilon)
        ran += 1
        if i + 1 < n_steps:
            if stop_after is not None and ran >= stop_after:
                raise RunStopped(save(i + 1), i + 1, n_steps)
            if ck.due():
                save(i + 1)
    for s in states:
        check_chain(s)
    if chosen < 0:
        chosen = int(np.argmin([s.energy for s in states]))
    if ck.path is not None:
        save(n_steps)
    best = states[chosen]
    acc = {}
    for name in ("single", "multi"):
        t = sum(s.acceptance()[name]["tried"] for s in states)
        a = sum(s.acceptance()[name]["accepted"] for s in states)
        acc[name] = {"tried": t, "accepted": a, "rate": a / t if t else 0.0}
    info = {
        "ladder": [float(t) for t in temps],
        "rounds": rounds,
        "moves_per_copy_per_round": per,
        "swap_tried": [int(x) for x in tried],
        "swap_accepted": [int(x) for x in accepted],
        "swap_rate": [float(a / t) if t else 0.0 for a, t in zip(accepted, tried, strict=True)],
        "quenched_copy_started_as": int(order[chosen]),
    }
    return make_result(replica, seed, settings, best, acc, traces, clock, hit,
                       stage_epsilon={"tempering": best.epsilon}, best_stage="tempering",
                       tempering=info, resumed_from_step=resumed)
