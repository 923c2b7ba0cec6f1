"""`spectral` command: the frequency-domain check of a synoptic case."""

from __future__ import annotations

from typing import Any

from rich.table import Table

from ..io.atomic import check_target
from ..io.display import kn
from ..io.outputs import case_inputs, check_outputs
from .common import CaseArg, JsonOpt, app, console, handle_errors, read_case
from .limits import warn as limits_warn


def spectral_table(doc: dict, title: str) -> Table:
    t = Table(title=title, title_justify="left")
    for c in ("reaction", "mean kN", "rms B kN", "rms R kN", "rms F kN", "peak QS kN", "peak Dy kN",
              "GF_Dy", "GF_QS", "Cont_R %"):
        t.add_column(c, justify="right")
    for r, v in doc["exact"].items():
        def f(x, s=1e-3, fmt="{:.3f}"):
            return "**" if x is None else fmt.format(x * s)
        t.add_row(r, f(v["mean"]), f(v["rms_background"]), f(v["rms_resonant"]), f(v["rms_fluctuating"]),
                  f(v["peak_quasi_static"]), f(v["peak_dynamic"]), f(v["GF_Dy"], 1), f(v["GF_QS"], 1),
                  f(v["Cont_R"], 100, "{:.1f}"))
    return t


def davenport_line(doc: dict) -> str:
    d = doc["davenport"]
    if d["applicable"]:
        return (f"closed form (Davenport/Castanheta), Ry: GF_Dy {d['GF_Dy']:.3f}, GF_QS {d['GF_QS']:.3f}, "
                f"Cont_R {100 * d['Cont_R']:.1f} % (B {d['background_factor']:.3f}, R {d['resonant_factor']:.3f}, "
                f"g {d['peak_factor']:.2f}, zeta_a {d['zeta_a']:.3f}); {d['note']}; "
                f"ASCE 74 wire GRF {d['GF_ASCE74']:.3f}. Rx, Rz: not applicable (closed form ignores their influence lines).")
    # a section of unequal spans: no closed form, hence no ASCE 74 wire factor either
    grf = "n/a" if d["GF_ASCE74"] is None else f"{d['GF_ASCE74']:.3f}"
    return f"closed form (Davenport/Castanheta): not shown: {d['note']}. ASCE 74 wire GRF {grf}."


@app.command()
@handle_errors
def spectral(case_file: CaseArg, json_out: JsonOpt = None) -> None:
    """Frequency-domain estimates (exact random vibration and closed form) for a synoptic case."""
    from .. import service  # here, not at import: the service loads the numerical core (start-up time)
    from ..io.jsonout import spectral_document, spectral_to_dict, with_provenance, write_json

    case = read_case(case_file)
    check_outputs([("--json", json_out)], case_inputs(case))
    if json_out is not None:
        check_target(json_out, what="JSON")
    res = service.spectral_analysis(case, warn=limits_warn)
    doc = {"case": case.name, "units": "SI", "tower_of_interest": case.line.tower_of_interest,
           **spectral_to_dict(res)}
    console.print(spectral_table(doc, f"{case.name}: frequency-domain estimate 1 (exact linear random vibration), "
                                      f"tower {case.line.tower_of_interest}"))
    console.print(davenport_line(doc), highlight=False)
    text = spectral_document(res).window_text()
    if text:
        console.print(text, highlight=False)
    if json_out is not None:
        write_json(json_out, with_provenance(doc))
        console.print(f"wrote {json_out}")


def print_sanity(doc: Any, *, explained: bool = False) -> None:
    """The run's "sanity check" line(s): time vs frequency domain.

    ``explained``: the burn-in note (a record that is not stationary) was printed, which is
    the usual reason of a flag; the hint is then not repeated.
    """
    sp = doc.spectral
    if sp is None:
        return
    items = sp.sanity_check or ()
    bad = [i for i in items if not i.ok]
    parts = []
    for i in items:
        tag = "" if i.ok else " [bold red]FLAG[/]"
        parts.append(f"{i.reaction} {i.quantity.replace('rms_', 'rms ')}: time {kn(i.time_domain):.3f} "
                     f"vs freq {kn(i.frequency_domain):.3f} kN{tag}")
    head = "[green]sanity check ok[/]" if not bad else (
        f"[bold red]sanity check: {len(bad)} difference(s) larger than sampling error explains[/]")
    console.print(head + ": " + "; ".join(parts), highlight=False)
    if sp.window is not None:
        console.print(sp.window_text(), highlight=False)
    if bad and not explained:
        console.print("[dim]A flagged resonant component usually means a lightly damped mode that the record "
                      "does not reach stationarity for (see docs/validation.md, damping).[/]")
