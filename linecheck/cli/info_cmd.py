"""`info` command: versions, the BLAS in use and the compiled kernel's state, piece by piece."""

from __future__ import annotations

import json
from typing import Annotated

import typer
from rich.markup import escape
from rich.table import Table

from .common import app, console, handle_errors


def info_table(prov) -> Table:
    """The :class:`~linecheck.io.provenance.Provenance` as a two-column table."""
    t = Table(title="linecheck installation", title_justify="left", show_header=False)
    t.add_column("", no_wrap=True)
    t.add_column("")
    for label, value in (("linecheck", prov.linecheck), ("Python", prov.python), ("numpy", prov.numpy),
                         ("scipy", prov.scipy), ("numba", prov.numba)):
        t.add_row(label, escape(value))
    t.add_row("BLAS (numpy)", escape(prov.blas.text()) + (f"\n[dim]{escape(prov.blas.path)}[/]" if prov.blas.path else ""))
    if prov.scipy_blas is not None:
        sb = prov.scipy_blas
        t.add_row("BLAS (scipy)", escape(sb.text()) + (f"\n[dim]{escape(sb.path)}[/]" if sb.path else ""))
    k = prov.kernel
    n_on = sum(p.on for p in k.pieces)
    t.add_row("compiled kernel", f"Numba {'installed' if k.installed else 'not installed'}, "
                                 f"LINECHECK_KERNEL={k.mode}: {n_on} of {len(k.pieces)} pieces on")
    for p in k.pieces:
        state = "[green]on[/]" if p.on else f"[yellow]off[/]: {escape(p.reason)}"
        t.add_row(f"  {p.name}", f"{state}  [dim]{escape(p.description)}[/]")
    return t


@app.command()
@handle_errors
def info(
    as_json: Annotated[bool, typer.Option("--json", help="Print one JSON object instead of the table.")] = False,
) -> None:
    """Versions (linecheck, Python, numpy, scipy, Numba), the BLAS library and its core type, and the compiled
    kernel's state piece by piece (on, or off and why)."""
    from ..io.provenance import provenance

    prov = provenance()
    if as_json:
        typer.echo(json.dumps(prov.to_json(), indent=2))
        return
    console.print(info_table(prov))
