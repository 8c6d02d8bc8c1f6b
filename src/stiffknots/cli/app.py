"""The command-line application object and what every command shares: consoles, options,
JSON output, the results folder, checkpoint folders, live progress and interruption."""

from __future__ import annotations

import contextlib
import errno
import fnmatch
import json
import math
import os
import shutil
import sys
from decimal import Decimal, InvalidOperation
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

def count(text: str) -> int | float:
    """Parser of a count option (``--moves 2e7``, ``--beads 1_000``): an integer written in any
    of Python's ways or in scientific notation. A number that is not an integer is returned as
    it is, so that the range check names the option and its limits; text that is no number is
    a usage error (one line, exit 2)."""
    try:
        return int(text)
    except ValueError:
        pass
    try:
        d = Decimal(text.strip().replace("_", ""))
    except InvalidOperation:
        raise typer.BadParameter(f"{text!r} is not a number") from None
    if d.is_finite() and d == d.to_integral_value():
        return int(d)
    return float(d)


# -- options shared by several commands ---------------------------------------------------------
JsonOpt = Annotated[bool, typer.Option("--json", help="Print a JSON object for scripts.")]
ReplicasOpt = Annotated[int, typer.Option(help="Independent replicas (run on all cores).",
                                          parser=count)]
SeedOpt = Annotated[int, typer.Option(help="Seed (replica seeds derive from it).")]
MovesOpt = Annotated[int, typer.Option(help="Attempted moves per replica.", parser=count)]
OutOpt = Annotated[str | None, typer.Option(
    "--out", help="Write the results into this folder (refused if it holds another run's "
                  "results, unless --overwrite).")]
OverwriteOpt = Annotated[bool, typer.Option(
    "--overwrite", help="Replace the results of an earlier run in --out.")]
StartOpt = Annotated[str, typer.Option(
    help="Starting embedding: all (braid, cage where it exists, eighty for the 80 family; "
         "the replicas take them in turn), braid (closure of KnotInfo's braid "
         "word), cage (4-fold cage of a two-box rational knot [ab]: 4_1, 5_2, 6_1, ...) or "
         "eighty (an 8 plus a circle).")]
CheckpointOpt = Annotated[str | None, typer.Option(
    "--checkpoint", help="Write a checkpoint of every replica to this folder.")]
PolishOpt = Annotated[bool, typer.Option(
    "--polish/--no-polish", help="Take every replica's best chain to its local minimum with "
                                 "the final minimiser (unit bonds and exclusion held exactly).")]
ResumeOpt = Annotated[bool, typer.Option(
    "--resume", help="Continue from the checkpoints in --checkpoint (same arguments).")]

MANIFEST = "manifest.json"
RESULT_FILES = ("manifest.json", "result.json", "summary.json", "report.md")
#: what a run writes into its folder: a folder holding any of these (without a manifest: a run
#: killed while writing, maybe in the middle of a temporary file) holds another run's files;
#: ``--overwrite`` removes them
RUN_FILES = (*RESULT_FILES, "report.html", "best.xyz", "best.json", "best.png", "traces.npz",
             "replica_*.xyz", "tension.png", "Le_*", "F_*", ".*.tmp", ".*.previous-*")


class UserError(UserInputError):
    """A mistake of the user found by the command line: one line on stderr, exit code 2."""


class Interrupted(Exception):  # noqa: N818 (a request of the user, not an error)
    """Ctrl-C: the command stops, says so, and exits with code 130."""


#: API parameter → command-line option, where the names differ
OPTION_NAMES = {"n_beads": "--beads", "checkpoint_dir": "--checkpoint", "initial": "--from"}


def option_name(param: str) -> str:
    """The command-line option of an API parameter (``w_over_L`` → ``--w-over-L``)."""
    return OPTION_NAMES.get(param, "--" + param.replace("_", "-"))


def dump(obj) -> None:
    """Print ``obj`` as JSON on stdout (numpy values converted)."""
    sys.stdout.write(dumps(obj, indent=2) + "\n")


def fmt(x, nd=4):
    """``x`` as text: a float with ``nd`` decimals, None as ``unknown``."""
    if x is None:
        return "unknown"
    if isinstance(x, float):
        return f"{x:.{nd}f}"
    return str(x)


def reflow(doc: str | None) -> str | None:
    """A docstring as help text: its lines joined within each paragraph (rich's help keeps
    every newline, so a docstring wrapped at 96 columns came out as ragged half-lines)."""
    if doc is None:
        return None
    import inspect

    paras = [" ".join(line.strip() for line in p.splitlines())
             for p in inspect.cleandoc(doc).split("\n\n")]
    return "\n\n".join(p for p in paras if p)


def floats(text: str, what: str) -> list[float]:
    """Comma-separated finite numbers of an option (``--excess-length 40,60,80``)."""
    items = text.replace(";", ",").split(",")
    if len(items) > 1 and any(not v.strip() for v in items):
        raise UserError(f"{what} has an empty value between commas: {text!r} (e.g. 40,60,80)")
    try:
        vals = [float(v) for v in items if v.strip()]
    except ValueError:
        raise UserError(f"{what} must be numbers separated by commas, got {text!r}") from None
    if not vals:
        raise UserError(f"{what}: give at least one value")
    bad = [v for v in vals if not math.isfinite(v)]
    if bad:
        raise UserError(f"{what} must be finite numbers, got {bad[0]}")
    return vals


def tube_only(w: float | None, exclusion: str) -> None:
    """``--w`` is the tube's diameter: given with the bead rule it would be ignored."""
    if w is not None and exclusion != "tube":
        raise UserError("--w applies to --exclusion tube only (the bead rule's distance is "
                        "d = 1/√2); add --exclusion tube or drop --w")


def choice(option: str, value: str, allowed) -> str:
    """``value`` if it is one of ``allowed``, else a :class:`UserError` naming ``option``."""
    if value not in allowed:
        raise UserError(f"{option} must be one of {', '.join(allowed)}, got {value!r}")
    return value


# -- the results folder -------------------------------------------------------------------------
#
# A results folder is checked, created and locked before any work (prepare_out). The run writes
# into it inside ResultsFolder: each file atomically, manifest.json last, so a folder with a
# manifest holds a complete set; on Ctrl-C or an error the files of the run are removed again.
# An earlier run's files (--overwrite) stay in place while the run computes; ResultsFolder sets
# them aside under hidden names, removes them once the new set is complete and puts them back
# if it is not (a full disk, Ctrl-C).
# A folder this process created and left empty is removed when the command fails
# (release_folders, called by main).

_CREATED: list[Path] = []  # folders created by this process, deepest first
_LOCKED: dict[str, int] = {}  # real path → open descriptor of a folder locked by this process


def _writable_folder(path: str | Path, option: str) -> Path:
    """Create ``path`` (and its parents) and check that a file can be written in it."""
    if str(path).strip() == "":
        raise UserError(f"{option} must name a folder, got ''")
    path = Path(path)
    missing: list[Path] = []
    try:
        if path.exists() and not path.is_dir():
            raise UserError(f"{option} {path}: exists and is not a folder")
        missing = [p for p in (path, *path.parents) if not p.exists()]
        path.mkdir(parents=True, exist_ok=True)
        probe = path / f".stiffknots-probe-{os.getpid()}"
        probe.write_bytes(b"")
        probe.unlink()
    except OSError as exc:
        _remove_empty(missing)
        raise UserError(f"{option} {path}: cannot write there "
                        f"({exc.strerror or type(exc).__name__})") from None
    _CREATED.extend(missing)
    return path


def _remove_empty(folders) -> None:
    for p in folders:  # deepest first
        with contextlib.suppress(OSError):
            p.rmdir()


def release_folders() -> None:
    """Remove the folders this process created and left empty (after a failed command)."""
    _remove_empty(_CREATED)
    _CREATED.clear()


def _lock(path: Path, option: str) -> None:
    """Lock the folder ``path`` until this process ends: a second run that claims it gets one
    line and exit code 2. Where the file system cannot lock, the run goes on without."""
    import fcntl

    key = os.path.realpath(path)
    if key in _LOCKED:
        return  # --out and --checkpoint may be the same folder
    try:
        fd = os.open(path, os.O_RDONLY | os.O_DIRECTORY)  # not inherited by the workers
    except OSError:
        return
    try:
        fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
    except OSError as exc:
        os.close(fd)
        if exc.errno in (errno.EWOULDBLOCK, errno.EAGAIN, errno.EACCES):
            raise UserError(f"{option} {path} is in use by another run") from None
        return
    _LOCKED[key] = fd


def prepare_folder(path: str | Path | None, option: str = "--out") -> Path | None:
    """Check (and create) a folder that a command writes a file into (``elastica --out``)."""
    return None if path is None else _writable_folder(path, option)


def claim_folder(path: str | Path | None, option: str = "--out") -> Path | None:
    """:func:`prepare_folder`, and the folder locked until this process ends: a second run
    that claims it gets one line and exit code 2 (``atlas --out``: two atlases writing one
    folder ended mixed)."""
    folder = prepare_folder(path, option)
    if folder is not None:
        _lock(folder, option)
    return folder


def prepare_file(path: str | Path | None, option: str) -> Path | None:
    """Check before any work that a file can be written at ``path`` (``resample DEST``,
    ``atlas --db``): not '', not a folder, its folder creatable and writable (created now,
    removed again if the command fails)."""
    if path is None:
        return None
    if str(path).strip() == "":
        raise UserError(f"{option} must name a file, got ''")
    path = Path(path)
    if path.is_dir():
        raise UserError(f"{option} {path} is a folder; give the path of a file")
    try:
        _writable_folder(path.parent, option)
    except UserError as exc:
        why = str(exc).rsplit("(", 1)[-1] if str(exc).endswith(")") else "not a folder)"
        raise UserError(f"{option} {path}: cannot write there ({why}") from None
    if path.is_file():  # an existing file (a database to add to): writable itself?
        try:
            with open(path, "r+b"):
                pass
        except OSError as exc:  # read-only, immutable (chattr +i), a read-only mount
            raise UserError(f"{option} {path}: cannot write it "
                            f"({exc.strerror or type(exc).__name__})") from None
    return path


def prepare_out(path: str | Path | None, overwrite: bool = False, option: str = "--out"
                ) -> Path | None:
    """Check ``--out`` before any work and claim it: exit 2 if it cannot be written, if another
    run is writing there, or if it holds another run's files and ``overwrite`` is off; with
    ``overwrite``, what the earlier run wrote is replaced when the new results are complete
    (:class:`ResultsFolder`): until then it stays."""
    if path is None:
        return None
    path = _writable_folder(path, option)
    _lock(path, option)
    old = _run_files(path)
    if old and not overwrite:
        what = ("the results of another run" if (path / MANIFEST).exists()
                else "the files of an unfinished run (no manifest.json)")
        raise UserError(f"{option} {path} holds {what} ({old[0]}); choose another folder "
                        "or add --overwrite")
    return path


def _run_files(path: Path) -> list[str]:
    """The names in ``path`` that a run writes (the manifest first)."""
    try:
        names = sorted(os.listdir(path), key=lambda n: (n != MANIFEST, n))
    except OSError:
        return []
    return [n for n in names if any(fnmatch.fnmatchcase(n, pat) for pat in RUN_FILES)]


def _remove(p: Path) -> None:
    with contextlib.suppress(OSError):
        if p.is_dir() and not p.is_symlink():
            shutil.rmtree(p)
        else:
            p.unlink()


def _set_aside(path: Path) -> list[tuple[Path, Path]]:
    """Rename what an earlier run wrote into ``path`` — the entries its manifest lists (their
    first path component) and the names a run writes (a run killed while writing left no
    manifest) — to hidden names; returns the (name, hidden name) pairs. Renames in one
    folder need no space on the disk."""
    names: list[str] = []
    with contextlib.suppress(OSError, ValueError, TypeError, AttributeError):
        names = [str(n) for n in json.loads((path / MANIFEST).read_text()).get("files", [])]
    root = path.resolve()
    top = []
    for name in [*names, *_run_files(path)]:
        p = (path / name).resolve()
        if root not in p.parents:
            continue  # never outside the folder
        top.append(p.relative_to(root).parts[0])
    moved: list[tuple[Path, Path]] = []
    try:
        for name in dict.fromkeys(top):
            src = path / name
            if os.path.lexists(src):
                dst = path / f".{name}.previous-{os.getpid()}"
                os.replace(src, dst)
                moved.append((src, dst))
    except BaseException:
        _put_back(moved)
        raise
    return moved


def _put_back(moved: list[tuple[Path, Path]]) -> None:
    for src, dst in reversed(moved):
        with contextlib.suppress(OSError):
            os.replace(dst, src)


def write_manifest(path: Path, files, command: str) -> None:
    """List the files a run wrote into ``path`` (written last: a folder with a manifest holds
    a complete set of results). ``files``: paths, or nested dicts/lists of them."""
    from stiffknots._version import __version__

    rel = sorted({os.path.relpath(str(v), path) for v in _flat(files)})
    write_json(path / MANIFEST, {"command": command, "version": __version__, "files": rel})


def _flat(files) -> list:
    if isinstance(files, dict):
        return [x for v in files.values() for x in _flat(v)]
    if isinstance(files, list | tuple):
        return [x for v in files for x in _flat(v)]
    return [files]


class ResultsFolder:
    """Write a run's results into a folder claimed by :func:`prepare_out`.

    On success the manifest, written last, lists every file the run added; on Ctrl-C or an
    error every file and folder the run added is removed again, so that the folder never holds
    part of a set (``kill -9`` cannot be caught: each file is still complete, being written
    atomically, and the missing manifest marks the set unfinished). Ctrl-C then raises
    :class:`Interrupted` saying so. An earlier run's files (``--overwrite``) are set aside
    first and removed once the new set is complete, or put back when it is not (a full disk,
    Ctrl-C): nothing is lost.
    """

    def __init__(self, path: Path | None, command: str, doing: str = "writing the results"):
        self.path, self.command, self.doing = path, command, doing
        self.before: set[str] = set()
        self.aside: list[tuple[Path, Path]] = []

    def _names(self) -> set[str]:
        return set(os.listdir(self.path))

    def __enter__(self):
        if self.path is not None:
            self.aside = _set_aside(self.path)
            self.before = self._names()
        return self

    def _undo(self, new: list[str]) -> None:
        for n in new:  # hidden ones too: a Ctrl-C inside an atomic write can leave its .tmp
            _remove(self.path / n)
        _put_back(self.aside)

    def __exit__(self, kind, exc, tb):
        if self.path is None:
            return False
        new = sorted(self._names() - self.before)
        if kind is None:
            try:
                shown = [n for n in new if not n.startswith(".")]  # a probe, a temporary file
                files = [q for n in shown
                         for q in ([self.path / n] if not (self.path / n).is_dir()
                                   else sorted(self.path.joinpath(n).rglob("*")))
                         if not q.is_dir()]
                write_manifest(self.path, files, self.command)
            except BaseException:  # the manifest did not fit: the set is not complete
                self._undo(new)
                raise
            for _, hidden in self.aside:  # the new set is complete: the earlier one goes
                _remove(hidden)
            return False
        self._undo(new)
        if isinstance(exc, OSError) and not exc.filename:
            exc.filename = str(self.path)  # a write that failed names no file: the folder
        if issubclass(kind, KeyboardInterrupt):
            kept = "; the earlier results were kept" if self.aside else ""
            raise Interrupted(f"interrupted while {self.doing}; the files of this run were "
                              f"removed from {self.path}{kept}") from None
        return False


# -- checkpoint folders -------------------------------------------------------------------------


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
    _lock(path, "--checkpoint")
    return path


# -- live progress ------------------------------------------------------------------------------

_NOTES: list[str] = []  # said once, when the work starts


def work_starts_note(text: str | None = None) -> None:
    """With ``text``: keep a note to say when the work starts. Without: the work starts — say
    the kept notes (after every input was checked: a mistake stays a single line)."""
    if text is not None:
        _NOTES.append(text)
        return
    while _NOTES:
        err.print(_NOTES.pop(0), markup=False, highlight=False)



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
        work_starts_note()
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
        """A replica finished: its bar full, and a line that stays (also in a log file, where
        the bars are not drawn)."""
        r = getattr(replica, "replica", None)
        task = self.tasks.get(r)
        if task is not None:
            t = self.progress.tasks[task].total or 1
            self.progress.update(task, total=t, completed=t)
        if not self.progress.disable:
            wall = getattr(replica, "wall_time", None)
            self.progress.console.print(
                f"{self.title}: replica {r} finished"
                + (f" in {wall:.1f} s" if isinstance(wall, float) else ""),
                markup=False, highlight=False)


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


def save_results(res, out_dir: Path, title: str, command: str) -> dict:
    """``res.save`` plus a picture of the best chain, the manifest written last; on Ctrl-C or
    an error none of it stays (:class:`ResultsFolder`)."""
    from stiffknots.report.render import save_chain_png

    with ResultsFolder(out_dir, command):
        paths = res.save(out_dir)
        png = save_chain_png(res.best.coords, out_dir / "best.png", closed=res.closed,
                             title=title)
    return {k: str(v) for k, v in paths.items()} | {"png": str(png)}


def emit(res, d: dict, out_dir: Path | None, title: str, command: str, json_: bool,
         total: int | None = None, resume_hint: str | None = None) -> bool:
    """The end of a solver command: the results written into ``out_dir`` (when given, their
    paths in ``d["files"]``) and, with --json, ``d`` printed and the command finished. True
    when the command is done (--json); False when it goes on to print its tables."""
    if out_dir is not None:
        d["files"] = save_results(res, out_dir, title, command)
    if json_:
        dump(d)
        finish(res, total, resume_hint)
        return True
    return False
