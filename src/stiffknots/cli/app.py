"""The command-line application object and what every command shares: consoles, the
``--json`` option, JSON output, number formatting."""

from __future__ import annotations

import sys
from typing import Annotated

import typer
from rich.console import Console

from stiffknots._json import dumps
from stiffknots.errors import UserInputError

app = typer.Typer(
    add_completion=False,
    no_args_is_help=True,
    help="Mechanics of stiff knots (Gallotti & Pierre-Louis, PRE 2007) for every knot in "
    "KnotInfo. Units: bond length 1, bending rigidity C = 1, k_B = 1; ε = E·L/C.",
)
out = Console()
err = Console(stderr=True)

JsonOpt = Annotated[bool, typer.Option("--json", help="Print a JSON object for scripts.")]


class UserError(UserInputError):
    """A mistake of the user found by the command line: one line on stderr, exit code 2."""


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
    """Comma-separated numbers of an option (``--excess-length 40,60,80``)."""
    try:
        vals = [float(v) for v in text.replace(";", ",").split(",") if v.strip()]
    except ValueError:
        raise UserError(f"{what} must be numbers separated by commas, got {text!r}") from None
    if not vals:
        raise UserError(f"{what}: give at least one value")
    return vals
