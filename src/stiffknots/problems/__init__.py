"""The problems of the paper, each a thin module over one template (:mod:`.base`):

* :func:`anneal` — closed knots, the minimum-energy chain (§VII);
* :func:`anneal_open`, :func:`tension_scan` — open knots at fixed excess length (§VIII);
* :func:`anneal_open_force` — open knots at fixed force (§VIII);
* :func:`tightest` — the restricted-curvature problem (§IX D).

To add a problem: subclass :class:`~stiffknots.problems.base.Problem` (validate the inputs in
``__init__``, make one :class:`~stiffknots.problems.base.Job` per replica in ``jobs``), give it a
:class:`~stiffknots.problems.base.ReplicaSet` subclass with its ``physics()``, and call
:func:`~stiffknots.problems.base.solve`.
"""

from stiffknots.problems.base import Job, Problem, Replica, ReplicaSet, solve
from stiffknots.problems.closed import AnnealResult, ClosedAnneal, anneal
from stiffknots.problems.open_extension import (
    OpenExtension,
    OpenResult,
    TensionScan,
    anneal_open,
    excess_length_for_force,
    tension_scan,
)
from stiffknots.problems.open_force import ForceResult, OpenForce, anneal_open_force
from stiffknots.problems.tightest import Tightest, TightResult, tightest

__all__ = [
    "AnnealResult",
    "ClosedAnneal",
    "ForceResult",
    "Job",
    "OpenExtension",
    "OpenForce",
    "OpenResult",
    "Problem",
    "Replica",
    "ReplicaSet",
    "TensionScan",
    "TightResult",
    "Tightest",
    "anneal",
    "anneal_open",
    "anneal_open_force",
    "excess_length_for_force",
    "solve",
    "tension_scan",
    "tightest",
]
