"""The warm-up runs every kernel whose cache tells a cold start from a warm one.

Before 2026-12-02 the warm-up's fixed-force problem was too short for an end move, so
``force_kernel.run_end_moves`` was never compiled: the cache always looked cold and every
engine command printed "first run: numba compiles the kernels once" on a warm machine; and
the warm-up itself said it was compiling when it only loaded the cache.
"""

from __future__ import annotations

import importlib

from stiffknots.studies.warmup import _MARKERS, cache_is_cold


def test_warmup_runs_every_marker_kernel_and_leaves_the_cache_warm(capsys):
    from stiffknots.cli import app

    was_cold = cache_is_cold()
    app(["warmup"], standalone_mode=False)  # the command, in this process
    said = [ln for ln in capsys.readouterr().out.splitlines() if ln.strip()]
    for pkg, name in _MARKERS:
        mod, fn = name.split(".")
        kernel = getattr(importlib.import_module(f"stiffknots.{pkg}.{mod}"), fn)
        # a signature exists once the kernel was called in this process (compiled or loaded)
        assert kernel.signatures, f"the warm-up never runs {pkg}.{name}"
    assert not cache_is_cold()
    if was_cold:
        assert said[0].startswith("compiling") and said[-1].startswith("kernels compiled")
    else:  # make ran the warm-up: it must not claim to compile
        assert "compiled already" in said[0] and said[-1].startswith("kernels loaded")
