"""`tui` command: the interactive terminal UI (Textual is imported only here, lazily)."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer

from .common import app, error_line, path_value

PathsArg = Annotated[
    list[Path] | None,
    typer.Argument(help="Case files or folders to browse (default: ./cases).", show_default=False, parser=path_value),
]


@app.command()
def tui(paths: PathsArg = None) -> None:
    """Interactive terminal UI: browse cases, edit, run, plot, compare, export (press ? for help)."""
    missing = [p for p in paths or [] if not p.exists()]
    if paths and len(missing) == len(paths):
        error_line(f"not found: {', '.join(map(str, missing))}")
        raise typer.Exit(2)
    from ..tui.app import LinecheckApp  # lazy: other commands do not pay for Textual

    LinecheckApp(list(paths or [])).run()
