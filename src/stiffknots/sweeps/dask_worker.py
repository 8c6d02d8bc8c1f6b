"""``python -m stiffknots.sweeps.dask_worker SCHEDULER [OPTIONS]``: ``stiffknots-dask worker``
for launchers that start a worker as ``python -m MODULE SCHEDULER --name … --nthreads …``.

dask-jobqueue (SLURM, PBS, SGE, LSF) writes each job's worker line that way from its
``worker_command`` option; its default, ``distributed.cli.dask_worker``, imports
``distributed`` without the care SnapPy needs (:mod:`stiffknots.sweeps.dask_cli`), so a
cluster for stiffknots names this module instead::

    SLURMCluster(cores=16, processes=16, memory="32GB", walltime="04:00:00",
                 worker_command="stiffknots.sweeps.dask_worker",
                 worker_extra_args=["--nworkers", "16"])

(with another ``worker_command`` dask-jobqueue leaves ``--nworkers`` to
``worker_extra_args``; docs/atlas.md gives the whole recipe).
"""

from __future__ import annotations

import sys

from stiffknots.sweeps.dask_cli import main

if __name__ == "__main__":
    sys.argv[1:1] = ["worker"]
    main()
