"""The ``stiffknots`` command line (typer + rich), one module per command group. It only
composes library calls: nothing below it imports it."""

from stiffknots.cli.main import app, main

__all__ = ["app", "main"]
