"""The Monte Carlo engine (paper §VII): arrays and numbers only.

:mod:`.prims` (shared numba primitives) → :mod:`.kernel` (crankshaft moves),
:mod:`.force_kernel` (end moves at fixed force) → :mod:`.params` (move, exclusion, energy and
ensemble parameters) → :mod:`.state` (one state, any ensemble) → :mod:`.schedules` →
:mod:`.settings` (what a run is made of) → :mod:`.plans` (its chunks) and
:mod:`.checkpoints` → :mod:`.driver` (the one run loop, verification) → :mod:`.tempering`
(replica exchange, built on the driver). :mod:`.guard` (the strand-passage guard of
straight-line motions) serves :mod:`.polish` (the final minimiser) and :mod:`.langevin`
(guarded Langevin dynamics, :mod:`.langevin_kernel`). Nothing here knows knot names, files of
results or the catalogue.
"""
