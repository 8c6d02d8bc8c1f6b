"""The command-line application object and what every command shares: consoles, options,
JSON output, the results folder, checkpoint folders, live progress and interruption."""

from __future__ import annotations

import contextlib
import json
import math
import os
import shutil
import sys
from pathlib import Path
from typing import Annotated

import typer
from rich.console import Console
from rich.markup import escape
from rich.progress import BarColumn, Progress, TextColumn, TimeRemainingColumn

from stiffknots._json import dumps
from stiffknots.errors import UserInputError
from stiffknots.fileio import write_json

app = typer.Typer(
    add_completion=False,
    no_args_is_help=True,
    help="Mechanics of stiff knots (Gallotti & Pierre-Louis, PRE 2007) for every knot in "
    "KnotInfo. Units: bond length 1, bending rigidity C = 1, k_B = 1; ε = E·L/C.",
)
out = Console()
err = Console(stderr=True)

# -- options shared by several commands ---------------------------------------------------------
JsonOpt = Annotated[bool, typer.Option("--json", help="Print a JSON object for scripts.")]
ReplicasOpt = Annotated[int, typer.Option(help="Independent replicas (run on all cores).")]
SeedOpt = Annotated[int, typer.Option(help="Seed (replica seeds derive from it).")]
OutOpt = Annotated[str | None, typer.Option(
    "--out", help="Write the results into this folder (refused if it holds another run's "
                  "results, unless --overwrite).")]
OverwriteOpt = Annotated[bool, typer.Option(
    "--overwrite", help="Replace the results of an earlier run in --out.")]
StartOpt = Annotated[str, typer.Option(
    help="Starting embedding: all (braid and cage where they exist, shared among the "
         "replicas), braid (closure of KnotInfo's braid word), cage (4-fold cage of a two-box "
         "rational knot [ab]: 4_1, 5_2, 6_1, ...) or eighty (an 8 plus a circle).")]
CheckpointOpt = Annotated[str | None, typer.Option(
    "--checkpoint", help="Write a checkpoint of every replica to this folder.")]
PolishOpt = Annotated[bool, typer.Option(
    "--polish/--no-polish", help="Take every replica's best chain to its local minimum with "
                                 "the final minimiser (unit bonds and exclusion held exactly).")]
ResumeOpt = Annotated[bool, typer.Option(
    "--resume", help="Continue from the checkpoints in --checkpoint (same arguments).")]

MANIFEST = "manifest.json"
RESULT_FILES = ("manifest.json", "result.json", "summary.json", "report.md")


class UserError(UserInputError):
    """A mistake of the user found by the command line: one line on stderr, exit code 2."""


class Interrupted(Exception):  # noqa: N818 (a request of the user, not an error)
    """Ctrl-C: the command stops, says so, and exits with code 130."""


def dump(obj) -> None:
    """Print ``obj`` as JSON on stdout (numpy values converted)."""
    sys.stdout.write(dumps(obj, indent=2) + "\n")


def fmt(x, nd=4):
    if x is None:
        return "unknown"
    if isinstance(x, float):
        return f"{x:.{nd}f}"
    return str(x)


def floats(text: str, what: str) -> list[float]:
    """Comma-separated finite numbers of an option (``--excess-length 40,60,80``)."""
    try:
        vals = [float(v) for v in text.replace(";", ",").split(",") if v.strip()]
    except ValueError:
        raise UserError(f"{what} must be numbers separated by commas, got {text!r}") from None
    if not vals:
        raise UserError(f"{what}: give at least one value")
    bad = [v for v in vals if not math.isfinite(v)]
    if bad:
        raise UserError(f"{what} must be finite numbers, got {bad[0]}")
    return vals


def choice(option: str, value: str, allowed) -> str:
    if value not in allowed:
        raise UserError(f"{option} must be one of {', '.join(allowed)}, got {value!r}")
    return value


# -- the results folder -------------------------------------------------------------------------


def _writable_folder(path: str | Path, option: str) -> Path:
    """Create ``path`` (and its parents) and check that a file can be written in it."""
    if str(path).strip() == "":
        raise UserError(f"{option} must name a folder, got ''")
    path = Path(path)
    if path.exists() and not path.is_dir():
        raise UserError(f"{option} {path}: exists and is not a folder")
    try:
        path.mkdir(parents=True, exist_ok=True)
        probe = path / f".stiffknots-probe-{os.getpid()}"
        probe.write_bytes(b"")
        probe.unlink()
    except OSError as exc:
        raise UserError(f"{option} {path}: cannot write there "
                        f"({exc.strerror or type(exc).__name__})") from None
    return path


def prepare_out(path: str | Path | None, overwrite: bool = False, option: str = "--out"
                ) -> Path | None:
    """Check ``--out`` before any work (exit 2 if it cannot be written, or if it holds another
    run's results and ``overwrite`` is off); with ``overwrite``, remove the files the earlier
    run listed in its manifest."""
    if path is None:
        return None
    path = _writable_folder(path, option)
    old = [n for n in RESULT_FILES if (path / n).exists()]
    if old and not overwrite:
        raise UserError(f"{option} {path} holds the results of another run ({old[0]}); "
                        "choose another folder or add --overwrite")
    if old:
        _remove_previous(path)
    return path


def _remove_previous(path: Path) -> None:
    """Delete what an earlier run wrote into ``path`` (its manifest lists it)."""
    names: list[str] = []
    with contextlib.suppress(OSError, ValueError, TypeError, AttributeError):
        names = list(json.loads((path / MANIFEST).read_text()).get("files", []))
    for name in [*names, *RESULT_FILES]:
        p = (path / name).resolve()
        if path.resolve() not in p.parents:
            continue  # never outside the folder
        with contextlib.suppress(OSError):
            if p.is_dir():
                shutil.rmtree(p)
            else:
                p.unlink()


def write_manifest(path: Path, files: dict, command: str) -> None:
    """List the files a run wrote into ``path`` (written last: a folder with a manifest holds
    a complete set of results)."""
    from stiffknots._version import __version__

    rel = sorted({os.path.relpath(str(v), path) for v in _flat(files)})
    write_json(path / MANIFEST, {"command": command, "version": __version__, "files": rel})


def _flat(files) -> list:
    if isinstance(files, dict):
        return [x for v in files.values() for x in _flat(v)]
    if isinstance(files, list | tuple):
        return [x for v in files for x in _flat(v)]
    return [files]


# -- checkpoint folders -------------------------------------------------------------------------

_LOCKS: list = []  # open lock files, held while the process runs


def claim_checkpoint(path: str | Path | None, resume: bool) -> Path | None:
    """Check ``--checkpoint``/``--resume`` before any work and lock the folder so that no
    second run uses it at the same time."""
    if path is None:
        if resume:
            raise UserError("--resume needs --checkpoint DIR (the folder of the checkpoints)")
        return None
    if resume and str(path).strip() and not Path(path).is_dir():
        raise UserError(f"--resume: there is no checkpoint folder {path}")
    path = _writable_folder(path, "--checkpoint")
    import fcntl

    fh = open(path / ".lock", "a+")  # noqa: SIM115 (held open until the process ends)
    try:
        fcntl.flock(fh, fcntl.LOCK_EX | fcntl.LOCK_NB)
    except OSError:
        fh.close()
        raise UserError(f"--checkpoint {path} is in use by another run") from None
    _LOCKS.append(fh)
    return path


# -- live progress ------------------------------------------------------------------------------


class ReplicaProgress:
    """One live bar per replica on stderr: moves done, time left and the lowest ε so far.

    Pass the instance as ``on_progress`` (records of the workers) and its :meth:`done` as
    ``on_replica_done``. Nothing is shown with ``--json``.
    """

    def __init__(self, title: str, replicas: int, disable: bool = False, unit: str = "ε"):
        self.unit = unit
        self.progress = Progress(
            TextColumn("{task.description}"), BarColumn(), TextColumn("{task.percentage:>3.0f}%"),
            TextColumn("{task.fields[best]}"), TimeRemainingColumn(), console=err,
            transient=True, disable=disable)
        self.title = title
        self.tasks = {r: self.progress.add_task(f"{escape(title)} replica {r}", total=None,
                                                best="") for r in range(replicas)}

    def __enter__(self):
        self.progress.__enter__()
        return self

    def __exit__(self, *exc):
        return self.progress.__exit__(*exc)

    def __call__(self, info: dict) -> None:
        task = self.tasks.get(info.get("replica"))
        if task is None:
            return
        best = info.get("best")
        self.progress.update(task, total=info["total"], completed=info["done"],
                             best=f"best {self.unit} {best:.4f}" if best is not None else "")

    def done(self, replica) -> None:
        task = self.tasks.get(getattr(replica, "replica", None))
        if task is not None:
            t = self.progress.tasks[task].total or 1
            self.progress.update(task, total=t, completed=t)


def check_interrupted(res, resume_hint: str | None = None) -> None:
    """After Ctrl-C before any replica finished: nothing to report — raise
    :class:`Interrupted` (exit code 130, one line on stderr)."""
    if getattr(res, "interrupted", False) and not res.replicas:
        raise Interrupted("interrupted before any replica finished; nothing to report"
                          + (f"; resume with {resume_hint}" if resume_hint else ""))


def finish(res, total: int | None = None, resume_hint: str | None = None) -> None:
    """At the end of a command whose run was stopped by Ctrl-C (``res.interrupted``): the
    partial results have been shown (and written, marked ``interrupted``); say so and exit
    with code 130."""
    if getattr(res, "interrupted", False):
        done = f"{len(res.replicas)} of {total} replicas" if total else "part of the run"
        raise Interrupted(f"interrupted: {done} finished; the results above are partial"
                          + (f"; resume with {resume_hint}" if resume_hint else ""))


def width_of(params, beads: int) -> dict:
    """The width a number was computed at: the exclusion model, its distance and w/L."""
    if params.exclusion == "tube":
        return {"exclusion": "tube", "w": params.w, "beads": beads, "w_over_L": params.w / beads,
                "text": f"tube w = {params.w:g}, N = {beads} (w/L = {params.w / beads:.2g})"}
    return {"exclusion": "bead", "d": params.d, "beads": beads, "w_over_L": params.d / beads,
            "text": f"bead rule d = {params.d:.4g}, N = {beads} (w/L ≈ {params.d / beads:.2g})"}
