"""`validate` command: the built-in verification set."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Annotated

import typer
from rich.table import Table

from ..io.atomic import check_target, write_text_atomic
from ..io.outputs import check_outputs
from .common import JsonOpt, app, console, handle_errors, path_value
from .progress import progress_bar


@app.command()
@handle_errors
def validate(
    json_out: JsonOpt = None,
    markdown: Annotated[Path | None, typer.Option("--markdown", help="Also write the table as Markdown.",
                                                  parser=path_value)] = None,
    quick: Annotated[bool, typer.Option("--quick", help="Skip the six-span time-vs-frequency runs and Table 5.")] = False,
) -> None:
    """Run the verification set: closed forms, Matheson & Holmes, time vs frequency domain, Table 5."""
    from .. import validation  # here, not at import: it loads the numerical core (start-up time)

    check_outputs([("--json", json_out), ("--markdown", markdown)])
    for out in (json_out, markdown):
        if out is not None:
            check_target(out)
    with progress_bar() as cb:
        checks = validation.run_validation(quick=quick, progress=cb)
    t = Table(title="linecheck verification", title_justify="left")
    for c in ("group", "check", "reference", "linecheck", "difference", "tolerance", "result"):
        t.add_column(c)
    for c in checks:
        res = "" if c.passed is None else ("[green]pass[/]" if c.passed else "[bold red]FAIL[/]")
        t.add_row(c.group, c.name, c.reference, c.measured, c.difference, c.tolerance, res)
    console.print(t)
    failed = [c for c in checks if c.passed is False]
    n_pass = sum(1 for c in checks if c.passed)
    console.print(f"{n_pass} passed, {len(failed)} failed, {sum(1 for c in checks if c.passed is None)} shown side by side")
    if json_out is not None:
        write_text_atomic(json_out, json.dumps([c.__dict__ for c in checks], indent=2) + "\n")
    if markdown is not None:
        write_text_atomic(markdown, validation.to_markdown(checks))
    if failed:
        raise typer.Exit(1)
