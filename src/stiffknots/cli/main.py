"""Entry point of the ``stiffknots`` command: user mistakes → one line on stderr and exit
code 2, Ctrl-C → exit 130, never a traceback for either."""

from __future__ import annotations

import typer

from stiffknots.cli import anneal, atlas, catalogue, curves, db, open, studies, tightest
from stiffknots.cli.app import Interrupted, app, err
from stiffknots.errors import InvalidParameter, UserInputError

# the commands, in the order `stiffknots --help` lists them
for _name, _command in (
        ("knot", catalogue.knot),
        ("elastica", catalogue.elastica),
        ("families", catalogue.families),
        ("identify", curves.identify),
        ("resample", curves.resample),
        ("relax", curves.relax),
        ("anneal", anneal.anneal),
        ("open", open.open_knot),
        ("tightest", tightest.tightest),
        ("paper", studies.paper),
        ("atlas", atlas.atlas),
        ("bench", studies.bench),
        ("warmup", studies.warmup),
        ("version", catalogue.version)):
    app.command(_name)(_command)
app.add_typer(db.db_app, name="db")  # the results database: states, grounds

# API parameter → command-line option, where the names differ
OPTION_NAMES = {"n_beads": "--beads", "checkpoint_dir": "--checkpoint"}


def option_name(param: str) -> str:
    return OPTION_NAMES.get(param, "--" + param.replace("_", "-"))


# commands that run the numba kernels: on a cold cache they say first what takes time
_ENGINE_COMMANDS = {"anneal", "open", "tightest", "paper", "bench", "relax"}


def _note_cold_cache() -> None:
    import sys

    from stiffknots.studies.warmup import cache_is_cold

    args = [a for a in sys.argv[1:] if not a.startswith("-")]
    if args and args[0] in _ENGINE_COMMANDS and cache_is_cold():
        err.print("first run: numba compiles the kernels once (about a minute; "
                  "`stiffknots warmup` does it ahead) ...", markup=False, highlight=False)


def main() -> None:
    """Run the command line (the ``stiffknots`` script)."""
    _note_cold_cache()
    try:
        rc = app(standalone_mode=False)
    except InvalidParameter as e:
        err.print(f"error: {e.for_option(option_name(e.param))}", highlight=False, markup=False,
                  soft_wrap=True)
        raise SystemExit(2) from None
    except (UserInputError, ValueError) as e:
        # ValueError: parameter validation of the engine; one line whatever the width
        err.print(f"error: {e}", highlight=False, markup=False, soft_wrap=True)
        raise SystemExit(2) from None
    except Interrupted as e:
        err.print(str(e), highlight=False, markup=False, soft_wrap=True)
        raise SystemExit(130) from None
    except typer.Abort:
        err.print("interrupted", highlight=False, markup=False)
        raise SystemExit(130) from None
    except KeyboardInterrupt:
        err.print("interrupted", highlight=False, markup=False)
        raise SystemExit(130) from None
    except Exception as e:  # click usage errors (typer vendors click: no import of it here)
        if callable(getattr(e, "show", None)) and isinstance(getattr(e, "exit_code", None), int):
            e.show()
            raise SystemExit(e.exit_code) from None
        raise
    if isinstance(rc, int) and rc != 0:
        if rc == 130:
            err.print("interrupted", highlight=False, markup=False)
        raise SystemExit(rc)
