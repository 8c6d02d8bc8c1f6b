"""The Monte Carlo engine (paper §VII): arrays and numbers only.

:mod:`.prims` (shared numba primitives) → :mod:`.kernel` (crankshaft moves),
:mod:`.force_kernel` (end moves at fixed force) → :mod:`.params` (move, exclusion, energy and
ensemble parameters) → :mod:`.state` (one state, any ensemble) → :mod:`.schedules` →
:mod:`.driver` (the one run loop, checkpoints, verification) → :mod:`.tempering` (replica
exchange, built on the driver). Nothing here knows knot names, files of results or the
catalogue.
"""
