"""The local Dask cluster of a sweep leaves nothing in the temporary folder (#40 row 16: after
any atlas run /tmp/dask-scratch-space/global.lock and purge.lock stayed behind)."""

from __future__ import annotations

import os
import subprocess
import sys

_SCRIPT = """
from stiffknots.sweeps.cluster import connect
with connect(workers=1) as client:
    assert client.submit(sum, [1, 2]).result() == 3
"""


def test_a_local_cluster_leaves_no_scratch_space(tmp_path):
    tmp = tmp_path / "tmp"
    tmp.mkdir()
    # TMPDIR: where Dask puts its scratch space by default, in a fresh process
    p = subprocess.run([sys.executable, "-c", _SCRIPT], env={**os.environ, "TMPDIR": str(tmp)},
                       capture_output=True, text=True, timeout=300)
    assert p.returncode == 0, p.stderr[-3000:]
    assert sorted(str(q.relative_to(tmp)) for q in tmp.rglob("*")) == []
