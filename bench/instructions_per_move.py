"""Instructions per attempted single-bead move, counted by valgrind's callgrind.

    python bench/instructions_per_move.py [N ...] [--moves M] [--states DIR]

The move and the chain are those of ``make bench`` (the paper's move ±π/100, bead exclusion,
guard on, a compact annealed 4_1 from :func:`stiffknots.studies.benchmark.compact_state`,
T = 1e-4). Unlike a rate, the count does not depend on what else the machine is doing, so two
versions of the kernel compare on a shared machine. It is no time: cache misses and the cost
of each instruction are not in it.

Method: a child process runs under ``valgrind --tool=callgrind --instr-atstart=no``, builds
the state, warms the kernel (compilation, neighbour lists: 1,000 moves), then switches the
instrumentation on around ``state.run(n)`` with callgrind's client requests (a three-line C
helper, compiled here with ``cc``); this for n = 10 and n = M (default 2,000,000), and
(I(M) − I(10)) / (M − 10) is the count per move. Under valgrind numba compiles for the CPU that
valgrind emulates (no AVX-512 on an AVX-512 machine), so the count is that of this code, not
of the code a native run executes. Needs valgrind, and a C compiler that finds
``valgrind/callgrind.h``. States are cached in ``--states`` (default: a temporary folder).
"""

from __future__ import annotations

import argparse
import ctypes
import glob
import subprocess
import sys
import tempfile
from pathlib import Path

HELPER = r"""
#include <valgrind/callgrind.h>
void cg_start(void) { CALLGRIND_ZERO_STATS; CALLGRIND_START_INSTRUMENTATION; }
void cg_stop(void) { CALLGRIND_STOP_INSTRUMENTATION; CALLGRIND_DUMP_STATS_AT("measured"); }
"""


def _child(state: str, n: int, lib: str) -> None:
    import numpy as np

    from stiffknots.engine.params import MoveParams
    from stiffknots.engine.state import ChainState

    cg = ctypes.CDLL(lib)
    st = ChainState(np.load(state), MoveParams(m_max=1, p_single=1.0), seed=1)
    st.run(1000, 1e-4)
    cg.cg_start()
    st.run(n, 1e-4)
    cg.cg_stop()


def _instructions(state: Path, n: int, lib: Path, work: Path) -> int:
    out = work / f"cg.{state.stem}.{n}"
    subprocess.run(["valgrind", "--tool=callgrind", "--instr-atstart=no",
                    f"--callgrind-out-file={out}.%p", sys.executable, __file__, "--child",
                    str(state), str(n), str(lib)], check=True, capture_output=True)
    files = sorted(glob.glob(f"{out}.*.*")) or sorted(glob.glob(f"{out}.*"))
    for line in Path(files[0]).read_text().splitlines():
        if line.startswith("totals:") or line.startswith("summary:"):
            value = int(line.split()[1])
            if value:
                return value
    raise RuntimeError(f"no instruction count in {files[0]}")


def main(argv: list[str] | None = None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("sizes", nargs="*", type=int, default=[150, 10_000])
    ap.add_argument("--moves", type=int, default=2_000_000)
    ap.add_argument("--states", type=Path, default=None)
    a = ap.parse_args(argv)
    with tempfile.TemporaryDirectory() as tmp:
        work = Path(tmp)
        states = a.states or work
        states.mkdir(parents=True, exist_ok=True)
        lib = work / "libcgctl.so"
        (work / "cgctl.c").write_text(HELPER)
        subprocess.run(["cc", "-O2", "-shared", "-fPIC", "-o", str(lib), str(work / "cgctl.c")],
                       check=True)
        for n_beads in a.sizes:
            state = states / f"compact_4_1_{n_beads}.npy"
            if not state.exists():
                import numpy as np

                from stiffknots.studies.benchmark import compact_state

                np.save(state, compact_state("4_1", n_beads).pos)
            small = _instructions(state, 10, lib, work)
            big = _instructions(state, a.moves, lib, work)
            per_move = (big - small) / (a.moves - 10)
            print(f"N = {n_beads}: {per_move:.1f} instructions per attempted move "
                  f"({big:,} for {a.moves:,} moves, {small:,} for 10)", flush=True)


if __name__ == "__main__":
    if len(sys.argv) > 1 and sys.argv[1] == "--child":
        _child(sys.argv[2], int(sys.argv[3]), sys.argv[4])
    else:
        main()
