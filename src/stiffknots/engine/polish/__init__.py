"""Precise final minimiser ("polish") of the constrained discrete problem (paper §VII, §VIII).

The Monte Carlo engine ends near a local minimum of the discrete bending energy (§VII) ::

    E_d = Σ_joints (1 − u_n·u_{n+1}),    |u_n| = |r_{n+1} − r_n| = 1        (C = 1)

but only to the resolution of its last moves. :func:`polish` finds that local minimum to
machine precision while holding the constraints *exactly*: every bond has unit length, and the
exclusion rule — ``bead`` (beads at index distance ≥ 2 at least ``d`` apart, the paper's rule)
or ``tube`` (segments that share no bead at least ``w`` apart, the tube of §II) — holds at
every accepted iterate. Contacts are inequality constraints with multipliers μ ≥ 0: the contact
forces of the variational analysis of §V.B. Open chains (§VIII) keep their clamped ends
(beads 0, 1, N−2, N−1 by default) bit-for-bit, so the excess length L_e is unchanged.

One idea per module:

* :mod:`~stiffknots.engine.polish.pieces`: the constraint pieces (candidate contacts, their
  values, gradients and exact Hessians, the clearances of the exclusion rule);
* :mod:`~stiffknots.engine.polish.problem`: the problem at fixed settings (the energy and its
  gradient, the free beads, the sparse Jacobian and Hessian of the Lagrangian);
* :mod:`~stiffknots.engine.polish.kkt`: the KKT algebra (sparse LU, the min-norm correction
  of the projection, the working set's Schur complement);
* :mod:`~stiffknots.engine.polish.sqp`: the feasible SQP iteration and when it stops;
* :mod:`~stiffknots.engine.polish.api`: :func:`polish` and :class:`PolishResult`;
* the strand-passage guard that certifies every step is :mod:`stiffknots.engine.guard`
  (shared with the Langevin search), re-exported here as :func:`passage_guard`.

The ``@njit`` kernels see arrays and numbers only; :func:`polish` validates its inputs and
composes them with scipy's sparse LU and LAPACK's Cholesky.
"""

from stiffknots.engine.guard import GUARD_FLOOR, passage_guard
from stiffknots.engine.polish.api import BOND_TOL_IN, PolishResult, polish
from stiffknots.engine.polish.pieces import TAU
from stiffknots.engine.polish.problem import EXCLUSIONS
from stiffknots.engine.polish.sqp import ACTIVE_TOL, BOND_TOL_OUT

__all__ = ["ACTIVE_TOL", "BOND_TOL_IN", "BOND_TOL_OUT", "EXCLUSIONS", "GUARD_FLOOR", "TAU",
           "PolishResult", "passage_guard", "polish"]
