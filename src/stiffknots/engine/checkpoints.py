"""Checkpoints: a replica's whole state in one ``.npz`` file, resumed bit for bit.

A long run can write its whole state to one ``.npz`` file every K chunks and/or every S
seconds (positions, generator state, counters, incremental energies, chunk index, traces, best
chain so far, the current energy parameters and curvature limit, settings, seed, version) and
be resumed from it. The plan depends on the settings only (:mod:`stiffknots.engine.plans`) and
the kernels' results do not depend on the order of their cell lists, so a resumed run ends
with *exactly* the chain and energy of an uninterrupted run with the same seed (only the
wall-clock traces differ). A checkpoint is only resumed by a run with the same settings, seed,
replica index, starting chain and package version; anything else, and any corrupt file,
raises :class:`~stiffknots.errors.CheckpointError`. The run loop
(:mod:`stiffknots.engine.driver`) and replica exchange (:mod:`stiffknots.engine.tempering`)
write and resume them.
"""

from __future__ import annotations

import hashlib
import json
import time
import zipfile
from pathlib import Path

import numpy as np

from stiffknots._version import __version__
from stiffknots.engine.params import MoveParams
from stiffknots.engine.settings import AnnealSettings
from stiffknots.engine.state import ChainState
from stiffknots.errors import CheckpointError
from stiffknots.fileio import atomic_path

CHECKPOINT_FORMAT = 2


def start_digest(coords: np.ndarray) -> str:
    """SHA-256 of the starting chain (float64, C order): ties a checkpoint to its start."""
    return hashlib.sha256(np.ascontiguousarray(coords, dtype=np.float64).tobytes()).hexdigest()


def save_checkpoint(path: str | Path, arrays: dict[str, np.ndarray], meta: dict) -> Path:
    """Write ``arrays`` and the JSON ``meta`` to ``path`` (``.npz``) atomically (a temporary
    file of a unique name, then one rename: concurrent writers never share it)."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    payload = dict(arrays)
    payload["meta"] = np.array(json.dumps(meta))
    with atomic_path(path) as tmp, open(tmp, "wb") as f:
        np.savez(f, **payload)
    return path


def load_checkpoint(path: str | Path) -> tuple[dict[str, np.ndarray], dict]:
    """Read a checkpoint written by :func:`save_checkpoint`: (arrays, meta).

    Raises
    ------
    CheckpointError
        If the file is not a readable stiffknots checkpoint (empty, truncated, junk, a folder,
        another format version).
    """
    path = Path(path)
    try:
        with np.load(path, allow_pickle=False) as z:
            arrays = {k: z[k] for k in z.files if k != "meta"}
            meta = json.loads(str(z["meta"]))
    except (OSError, ValueError, KeyError, EOFError, zipfile.BadZipFile,
            json.JSONDecodeError) as exc:
        why = exc.strerror if isinstance(exc, OSError) and exc.strerror else type(exc).__name__
        raise CheckpointError(f"corrupt checkpoint {path} ({why}); delete it to start afresh"
                              ) from None
    if not isinstance(meta, dict) or meta.get("format") != CHECKPOINT_FORMAT:
        raise CheckpointError(f"{path}: not a stiffknots checkpoint of format "
                              f"{CHECKPOINT_FORMAT}; delete it to start afresh")
    return arrays, meta


def run_meta(kind: str, settings: AnnealSettings, seed: int, replica: int,
             coords: np.ndarray) -> dict:
    """What identifies a run: a checkpoint is resumed only if all of it matches."""
    return {
        "format": CHECKPOINT_FORMAT,
        "kind": kind,
        "version": __version__,
        "seed": int(seed),
        "replica": int(replica),
        "settings": json.loads(json.dumps(settings.as_dict())),
        "start": start_digest(coords),
    }


def check_resumable(meta: dict, expected: dict, path: Path) -> None:
    """Raise CheckpointError naming the first field in which a checkpoint differs from the
    run."""
    for key in ("kind", "version", "seed", "replica", "start", "settings"):
        if meta.get(key) != expected[key]:
            what = "starting chain" if key == "start" else key
            raise CheckpointError(
                f"checkpoint {path} was written by a different run ({what} differs: "
                f"{meta.get(key)!r} ≠ {expected[key]!r}); delete it or drop resume"
            )


def restore_state(arrays: dict, settings: AnnealSettings, params: MoveParams | None = None,
                  prefix: str = "") -> ChainState:
    """A ChainState exactly as it was checkpointed (generator, counters, incremental energies).

    The cell list is rebuilt from the positions; the kernels' decisions do not depend on the
    order of their lists, so the continuation is bit-for-bit the uninterrupted one.
    """
    st = ChainState(arrays[prefix + "pos"], params or settings.params, seed=0,
                    ensemble=settings.ensemble)
    st.rng[:] = np.asarray(arrays[prefix + "rng"], dtype=np.uint64)
    st.counters[:] = np.asarray(arrays[prefix + "counters"], dtype=np.int64)
    if prefix + "end_counters" in arrays:
        st.end_counters[:] = np.asarray(arrays[prefix + "end_counters"], dtype=np.int64)
        st.slide_counters[:] = np.asarray(arrays[prefix + "slide_counters"], dtype=np.int64)
    st.energy = float(arrays[prefix + "energy"])
    st.total_energy = float(arrays[prefix + "total_energy"])
    return st


def state_arrays(state: ChainState) -> dict[str, np.ndarray]:
    """The arrays that :func:`restore_state` needs."""
    return {"pos": state.pos, "rng": state.rng, "counters": state.counters,
            "end_counters": state.end_counters, "slide_counters": state.slide_counters,
            "energy": np.float64(state.energy), "total_energy": np.float64(state.total_energy)}


class Checkpointer:
    """When to write a checkpoint: every ``every`` chunks and/or every ``seconds`` seconds."""

    def __init__(self, path: str | Path | None, every: int | None = None,
                 seconds: float | None = None):
        self.path = Path(path) if path is not None else None
        if every is not None and every < 1:
            raise ValueError(f"checkpoint_every must be ≥ 1 chunk, got {every}")
        if seconds is not None and not seconds > 0:
            raise ValueError(f"checkpoint_seconds must be > 0, got {seconds}")
        if self.path is not None and every is None and seconds is None:
            every = 10
        self.every = every
        self.seconds = seconds
        self._since = 0
        self._last = time.perf_counter()

    def due(self) -> bool:
        """Count one chunk; True when a checkpoint should be written now."""
        if self.path is None:
            return False
        self._since += 1
        if self.every is not None and self._since >= self.every:
            return True
        return self.seconds is not None and time.perf_counter() - self._last >= self.seconds

    def written(self) -> None:
        self._since = 0
        self._last = time.perf_counter()
