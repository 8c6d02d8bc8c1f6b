"""The ``stiffknots`` script. It loads the command line inside a handler, so that Ctrl-C while
the command line loads (about a second on a busy machine) is an interruption like any other —
the line "interrupted" and exit code 130 — and not a traceback."""

from __future__ import annotations

import sys


def main() -> None:
    try:
        from stiffknots.cli.main import main as run
    except KeyboardInterrupt:
        sys.stderr.write("interrupted\n")
        raise SystemExit(130) from None
    run()
