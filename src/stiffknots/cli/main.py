"""Entry point of the ``stiffknots`` command: user mistakes → one line on stderr and exit
code 2, Ctrl-C → exit 130, ``kill PID`` (SIGTERM) → the same stop as Ctrl-C with exit code
143, never a traceback for any of them."""

from __future__ import annotations

import errno
import os
import signal
import sys

import typer

from stiffknots.cli import (
    anneal,
    atlas,
    audit,
    catalogue,
    census,
    curves,
    db,
    open,
    studies,
    thin_limit,
    tightest,
)
from stiffknots.cli.app import (
    Interrupted,
    app,
    err,
    option_name,
    reflow,
    release_folders,
    work_starts_note,
)
from stiffknots.errors import (
    InvalidParameter,
    ParameterConflict,
    UserInputError,
    WorkerError,
)

#: errors of the machine's storage (not of stiffknots): one line and exit code 1
_STORAGE_ERRNOS = {errno.ENOSPC, errno.EDQUOT, errno.EROFS, errno.EFBIG, errno.EIO}

# the commands, in the order `stiffknots --help` lists them
for _name, _command in (
        ("knot", catalogue.knot),
        ("elastica", catalogue.elastica),
        ("families", catalogue.families),
        ("starts", catalogue.starts),
        ("identify", curves.identify),
        ("resample", curves.resample),
        ("relax", curves.relax),
        ("anneal", anneal.anneal),
        ("open", open.open_knot),
        ("tightest", tightest.tightest),
        ("thin-limit", thin_limit.thin_limit),
        ("paper", studies.paper),
        ("atlas", atlas.atlas),
        ("audit", audit.audit),
        ("census", census.census),
        ("bench", studies.bench),
        ("warmup", studies.warmup),
        ("version", catalogue.version)):
    app.command(_name, help=reflow(_command.__doc__))(_command)
for _info in db.db_app.registered_commands:
    _info.help = _info.help or reflow(_info.callback.__doc__)
app.add_typer(db.db_app, name="db")  # the results database: states, grounds

def _say(text: str) -> None:
    err.print(text, highlight=False, markup=False, soft_wrap=True)


def _usage_line(e) -> str:
    """A click usage error (bad value, unknown option, missing argument) as one line."""
    msg = " ".join(str(e.format_message()).split())
    ctx = getattr(e, "ctx", None)
    where = getattr(ctx, "command_path", None) or "stiffknots"
    return f"error: {msg} (see {where} --help)"


# commands that run the numba kernels: on a cold cache they say first what takes time
_ENGINE_COMMANDS = {"anneal", "open", "tightest", "paper", "bench", "relax", "thin-limit"}


def _note_cold_cache() -> None:
    """On a cold cache, an engine command says what takes the time — when its work starts
    (:func:`~stiffknots.cli.app.work_starts_note`), so that a mistake stays one line."""
    import sys

    from stiffknots.studies.warmup import cache_is_cold

    args = [a for a in sys.argv[1:] if not a.startswith("-")]
    if args and args[0] in _ENGINE_COMMANDS and cache_is_cold():
        work_starts_note("first run: numba compiles the kernels once (about a minute; "
                         "`stiffknots warmup` does it ahead) ...")


#: commands whose first argument is a knot name
_KNOT_COMMANDS = {"anneal", "open", "tightest", "thin-limit"}


def _note_mirror() -> None:
    """A knot named by its mirror image (``anneal m3_1``) is run as the catalogue's knot: say
    so when the work starts (a misspelt name stays a one-line error)."""
    args = [a for a in sys.argv[1:] if not a.startswith("-")]
    if len(args) < 2 or args[0] not in _KNOT_COMMANDS:
        return
    from stiffknots.errors import UnknownKnotError
    from stiffknots.knots.catalogue import mirror_note

    try:
        note = mirror_note(args[1])
    except UnknownKnotError:
        return  # the command says it
    if note:
        work_starts_note(note)


def _json_stdout_only() -> None:
    """With --json, standard output carries the JSON document and nothing else: file
    descriptor 1 is pointed at standard error for the whole command — compiled libraries
    (BLAS, SuperLU, topoly) and worker processes print there — and Python's ``sys.stdout``
    keeps the real standard output."""
    if "--json" not in sys.argv[1:]:
        return
    sys.stdout.flush()
    try:
        real = os.dup(1)
        os.dup2(2, 1)
    except OSError:
        return
    sys.stdout = os.fdopen(real, "w", encoding="utf-8", buffering=1)


#: set when SIGTERM stopped the command (:func:`_sigterm_as_interrupt`)
_TERMINATED = [False]


def _sigterm_as_interrupt() -> None:
    """``kill PID`` (SIGTERM) stops the command as Ctrl-C does — the finished replicas shown
    and written, marked partial; a sweep's results stored, its cluster closed, the same
    command to resume — and it exits with code 143 (128 + 15) instead of 130.

    SIGTERM is how a batch system (Slurm's ``scancel``, a job's time limit) stops a job, and
    the only polite stop of a command started in the background by a script, whose shell
    sets Ctrl-C's SIGINT to ignored. The handler acts
    once (a second SIGTERM kills at once) and only in this process: a process forked from it
    (a Dask nanny of the local cluster, its worker) gets the default, so that its cluster can
    still end it with SIGTERM."""
    main_pid = os.getpid()

    def handler(signum, frame):
        signal.signal(signal.SIGTERM, signal.SIG_DFL)
        if os.getpid() != main_pid:  # a forked child: die as it would have
            os.kill(os.getpid(), signal.SIGTERM)
            return
        _TERMINATED[0] = True
        raise KeyboardInterrupt

    try:
        signal.signal(signal.SIGTERM, handler)
    except (ValueError, OSError):  # not the main thread (an embedding application): leave it
        pass


def _plain_warnings() -> None:
    """A warning of stiffknots that reaches the command line (the analysis warns a user of
    the Python API about a chain it reads) is one plain line, said once: not Python's two
    lines naming a file of a library (typer's, where the command was called)."""
    import warnings

    from stiffknots.errors import StiffKnotsWarning

    shown = warnings.showwarning
    said: set[str] = set()

    def show(message, category, filename, lineno, file=None, line=None):
        if not issubclass(category, StiffKnotsWarning):
            return shown(message, category, filename, lineno, file, line)
        text = " ".join(str(message).split())
        if text not in said:
            said.add(text)
            _say(f"warning: {text}")

    warnings.showwarning = show


def main() -> None:
    """Run the command line (the ``stiffknots`` script)."""
    _sigterm_as_interrupt()
    _plain_warnings()
    _note_cold_cache()
    _note_mirror()
    _json_stdout_only()
    try:
        _main()
    except SystemExit as e:
        if e.code not in (0, None):
            release_folders()  # a folder the failed command created and left empty
        if e.code == 130 and _TERMINATED[0]:
            raise SystemExit(143) from None
        raise


def _main() -> None:
    try:
        rc = app(standalone_mode=False)
    except InvalidParameter as e:
        _say(f"error: {e.for_option(option_name(e.param))}")
        raise SystemExit(2) from None
    except ParameterConflict as e:
        _say(f"error: {e.message(option_name)}")
        raise SystemExit(2) from None
    except (UserInputError, ValueError) as e:
        # ValueError: parameter validation of the engine; one line whatever the width
        _say(f"error: {' '.join(str(e).split())}")
        raise SystemExit(2) from None
    except Interrupted as e:
        _say(str(e))
        raise SystemExit(130) from None
    except WorkerError as e:  # the machine's doing (out of memory, a kill), not a bug: one line
        _say(f"error: {e}")
        raise SystemExit(1) from None
    except (typer.Abort, KeyboardInterrupt):
        _say("interrupted")
        raise SystemExit(130) from None
    except OSError as e:  # a full disk, a read-only medium met while writing the results
        if e.errno not in _STORAGE_ERRNOS:
            raise
        why = e.strerror or os.strerror(e.errno)
        _say(f"error: cannot write {e.filename or 'the results'}: {why[:1].lower()}{why[1:]}")
        raise SystemExit(1) from None
    except Exception as e:  # click usage errors (typer vendors click: no import of it here)
        if callable(getattr(e, "show", None)) and isinstance(getattr(e, "exit_code", None), int):
            if type(e).__name__ == "NoArgsIsHelpError" or not callable(
                    getattr(e, "format_message", None)):
                e.show()  # `stiffknots` alone: the help
            else:
                _say(_usage_line(e))
            raise SystemExit(e.exit_code) from None
        raise
    if isinstance(rc, int) and rc != 0:
        if rc == 130:
            _say("interrupted")
        raise SystemExit(rc)
