"""Sweeps: knots × models × replicas on Dask, resumable through the results store.

Layer: above :mod:`stiffknots.store` and :mod:`stiffknots.report`, below the studies and the
command line. A *job* is one replica of one (knot, model): the closed search of §VII
(:class:`~stiffknots.problems.closed.ClosedAnneal`: the annealing, or for the bead rule in the
default and full budgets the Langevin dynamics) at N = 150 under the paper's bead rule
(d = 1/√2) or the tube model (w = 1/√2 unless set), with a *budget* of replicas and moves.
Every job's store key is known before it runs, so a sweep skips what is stored and resumes
after Ctrl-C, ``kill -9`` or a lost worker with nothing run or stored twice.

Public API
----------
:func:`run_sweep`, :class:`SweepResult`, :class:`SweepListener`
    Run the missing jobs on a local Dask cluster (or ``scheduler=``) and store each result
    (:mod:`stiffknots.sweeps.run`).
:data:`BUDGETS`, :func:`budget_of`, :class:`Budget`, :data:`BEAD_SEARCHES`
    tiny / small / default / full, and how the bead rule searches
    (:mod:`stiffknots.sweeps.budgets`).
:func:`parse_models`, :func:`params_of`
    The models: bead / tube at a width and N, each a :class:`~stiffknots.width.Width`
    (:mod:`stiffknots.sweeps.models`).
:func:`resolve_knots`, :func:`plan_sweep`, :func:`pending`, :func:`sweep_settings`
    The jobs and their keys (:mod:`stiffknots.sweeps.plan`).
:func:`is_converged`, :func:`ensemble_converged`
    The convergence rule of a ground state, and of a stored ensemble (the rule, after a
    replica from every default start) (:mod:`stiffknots.sweeps.convergence`).
"""

from stiffknots.sweeps.budgets import BEAD_SEARCHES, BUDGETS, Budget, budget_of
from stiffknots.sweeps.convergence import RULE as CONVERGENCE_RULE
from stiffknots.sweeps.convergence import ensemble_converged, is_converged
from stiffknots.sweeps.models import MODELS, params_of, parse_models
from stiffknots.sweeps.plan import (
    SweepJob,
    pending,
    plan_sweep,
    resolve_knots,
    sweep_settings,
)
from stiffknots.sweeps.run import SweepListener, SweepResult, run_sweep, store_replica

__all__ = ["BEAD_SEARCHES", "BUDGETS", "Budget", "budget_of", "CONVERGENCE_RULE",
           "ensemble_converged", "is_converged", "MODELS",
           "params_of", "parse_models", "SweepJob", "pending", "plan_sweep", "resolve_knots",
           "sweep_settings", "SweepListener", "SweepResult", "run_sweep", "store_replica"]
