"""Command-line front end (Typer).  Commands parse, call one service function, print.

This module gathers the commands: importing a command module registers its commands on the Typer
app of :mod:`linecheck.cli.common` (in this order, which is the order of ``linecheck --help``).
:func:`main` is the console-script entry point.
"""

from __future__ import annotations

import sys

# Importing a command module registers its commands on the app; the order of registration is the
# order of ``linecheck --help``: check and static first.
from . import commands  # noqa: F401

# isort: split
from . import (  # noqa: F401  (batch_cmd imports export_cmd: export, then batch and scan)
    batch_cmd,
    codes_cmd,
    export_cmd,
    info_cmd,
    run_cmd,
    spectral_cmd,
    tui_cmd,
    validate_cmd,
    wind_cmd,
)
from .common import app

__all__ = ["app", "main"]


def main() -> None:
    """Console-script entry point."""
    app(prog_name="linecheck")


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
