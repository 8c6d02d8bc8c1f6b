"""``stiffknots-dask``: Dask's own command line (``dask scheduler``, ``dask worker`` …) in an
environment that has SnapPy.

``distributed`` probes ``import snappy`` for the python-snappy compressor when it is imported,
and stops with an AttributeError on SnapPy's module of the same name (the knot invariants of
:mod:`stiffknots.knots.identify` need SnapPy). This command imports ``distributed`` with that
probe answered (:func:`stiffknots.sweeps.cluster.import_distributed`), has the nannies fork
their worker processes from it (a spawned process would import ``distributed`` afresh), and
then runs Dask's command line with the same arguments::

    stiffknots-dask scheduler                       # on one machine: tcp://host:8786
    stiffknots-dask worker tcp://host:8786          # on every machine with stiffknots
    stiffknots atlas --max-crossings 10 --scheduler tcp://host:8786
"""

from __future__ import annotations

import os
import sys


def main() -> None:
    """Run Dask's command line with the arguments given, ``distributed`` imported as the
    module docstring says."""
    os.environ.setdefault("DASK_DISTRIBUTED__WORKER__MULTIPROCESSING_METHOD", "fork")
    from stiffknots.sweeps.cluster import import_distributed

    import_distributed()
    from dask.__main__ import main as dask_main

    sys.argv[0] = "stiffknots-dask"
    sys.exit(dask_main())


if __name__ == "__main__":
    main()
