"""`wind` command: mean and total velocity at point p (paper Fig. 3)."""

from __future__ import annotations

import io
import math
from pathlib import Path
from typing import TYPE_CHECKING, Annotated, Any

import numpy as np
import typer
from rich.table import Table

from ..core.case import Case
from ..io.atomic import check_target, write_atomic, write_text_atomic
from ..io.outputs import case_inputs, check_outputs
from .common import CaseArg, JsonOpt, app, console, handle_errors, path_value, read_case

if TYPE_CHECKING:  # annotations only: the wind modules are imported where they are used (start-up time)
    from ..core.wind.point import PointSeries

CsvOpt = Annotated[Path | None, typer.Option("--csv", help="Write time, mean and total velocity at p as CSV to this file.",
                                             parser=path_value)]
FieldOpt = Annotated[
    Path | None,
    typer.Option("--field", help="Write the run's full wind (running mean and turbulence at every conductor node and "
                 "time step of the realization) to this NPZ file (layout: docs/wind.md).", parser=path_value),
]
RealizationOpt = Annotated[
    int, typer.Option("--realization", min=1, help="Turbulence realization to show, 1 to analysis.realizations.")
]

CSV_COLUMNS = (
    "time_s", "time_vref_over_lu", "mean_ms", "fluctuation_ms", "total_ms",
    "mean_over_vref", "total_over_vref", "mean_normal_ms", "mean_longitudinal_ms",
)


def _point_p_block(case: Any, s: Any) -> dict[str, Any]:
    """JSON of point p: x (the equal-span form's abscissa; a section's station-like coordinate),
    the nearest node; on a section also that node's plan position and height in the
    global frame (x along the first span, y to its left)."""
    block: dict[str, Any] = {"x": _f(s.point_p), "node": s.node + 1, "node_x": _f(s.node_x)}
    if case.line.is_section:
        from ..core.system import LineSystem

        system = LineSystem(case.line)
        xyz = system.node_xyz0[s.node]
        block.update(node_xy=[_f(xyz[0]), _f(xyz[1])], node_height=_f(system.node_height[s.node]))
    return block


def series_csv(s: PointSeries) -> str:
    """CSV text of the series: one row per instant, SI units (columns in :data:`CSV_COLUMNS`)."""
    cols = np.column_stack([
        s.time, s.time * s.v_ref / s.length_scale, s.mean_speed, s.fluctuation, s.total,
        s.mean_speed / s.v_ref, s.total / s.v_ref, s.mean_normal, s.mean_longitudinal,
    ])
    buf = io.StringIO()
    buf.write(",".join(CSV_COLUMNS) + "\n")
    np.savetxt(buf, cols, delimiter=",", fmt="%.6f")
    return buf.getvalue()


def _f(x: float) -> float | None:
    x = float(x)
    return x if math.isfinite(x) else None


def series_summary(case: Case, s: PointSeries) -> dict[str, Any]:
    """Summary statistics of the series as a JSON document (SI units)."""
    from ..core.wind.mean import downburst_field, event_window

    k_mean, k_tot = int(np.argmax(s.mean_speed)), int(np.argmax(s.total))
    mod = s.intensity * (s.mean_speed if case.wind.type == "downburst" else s.v_ref)
    doc: dict[str, Any] = {
        "case": case.name,
        "description": case.description,
        "wind": case.wind.type,
        "units": "SI",
        "realization": s.realization + 1,
        "seed": case.analysis.seed,
        "point_p": _point_p_block(case, s),
        "v_ref": _f(s.v_ref),
        "turbulence_intensity": _f(s.intensity),
        "length_scale": _f(s.length_scale),
        "coherence_decay": _f(case.wind.coherence_decay),
        "time_step": _f(case.analysis.time_step),
        "window": [_f(v) for v in event_window(case)],
        "n_steps": int(s.time.size),
        "mean": {
            "max": _f(s.mean_speed[k_mean]), "time_of_max": _f(s.time[k_mean]),
            "average": _f(s.mean_speed.mean()),
            "max_normal": _f(s.mean_normal.max()), "max_abs_longitudinal": _f(np.abs(s.mean_longitudinal).max()),
        },
        "total": {"max": _f(s.total[k_tot]), "time_of_max": _f(s.time[k_tot]), "min": _f(s.total.min())},
        "fluctuation": {
            "std": _f(s.fluctuation.std()),
            "unit_std": _f(s.unit.std()),
            "modulation_max": _f(np.max(mod)),
        },
        "gust_factor": _f(s.total[k_tot] / s.mean_speed[k_mean]) if s.mean_speed[k_mean] > 0 else None,
    }
    if case.wind.type == "downburst":
        db = case.wind.downburst
        fld = downburst_field(case)
        doc["downburst"] = {
            "jet_diameter": _f(db.jet_diameter), "distance": _f(db.distance), "angle": _f(db.angle),
            "preset": db.preset, "field": str(fld.table.path) if fld.table is not None else None,
            "v_max": _f(fld.v_max), "centre": [_f(fld.centre[0]), _f(fld.centre[1])], "t_ref": _f(fld.t_ref),
            "r_max": _f(fld.r_max), "radial_decay": _f(fld.radial_decay), "z_max": _f(fld.z_max),
            "delta": _f(fld.delta), "t1": _f(fld.t1), "t_f": _f(fld.t_f),
            "translation_speed": _f(db.translation_speed), "translation_direction": _f(db.translation_direction),
            "model": db.model_name,
            "jet_velocity": _f(fld.ring.jet_velocity) if fld.ring is not None else None,
        }
        from ..core.wind.line_peak import line_peak

        # the field's largest running mean anywhere on the line over the event, beside V_ref at p
        doc["downburst"]["line_peak"] = line_peak(case).to_dict()
    return doc


@app.command()
@handle_errors
def wind(
    case_file: CaseArg,
    csv_out: CsvOpt = None,
    json_out: JsonOpt = None,
    realization: RealizationOpt = 1,
    field_out: FieldOpt = None,
) -> None:
    """Wind at point p: running mean and mean + turbulence over the record (paper Fig. 3)."""
    case = read_case(case_file)
    check_outputs([("--csv", csv_out), ("--json", json_out), ("--field", field_out)], case_inputs(case))
    if csv_out is not None:
        check_target(csv_out, what="CSV")
    if json_out is not None:
        check_target(json_out, what="JSON")
    from .. import service
    from ..core.wind.point import point_series
    from ..io.jsonout import with_provenance, write_json
    from .limits import warn as limits_warn

    service.check_budget(case, "wind", warn=limits_warn)  # resource guard
    if field_out is not None:
        check_target(field_out, what="NPZ")
    s = point_series(case, realization - 1)
    doc = series_summary(case, s)
    console.print(_wind_table(case, s, doc, realization))
    if csv_out is not None:
        write_text_atomic(csv_out, series_csv(s), what="CSV")
        console.print(f"wrote {csv_out}")
    if json_out is not None:
        write_json(json_out, with_provenance(doc))
        console.print(f"wrote {json_out}")
    if field_out is not None:
        _write_field(case, realization, field_out)


def _wind_table(case: Case, s: PointSeries, doc: dict[str, Any], realization: int) -> Table:
    """The console table of the wind at point p (``doc``: :func:`series_summary` of ``s``)."""
    table = Table(title=f"{case.name}: wind at point p (x = {s.point_p:.1f} m), realization {realization}",
                  title_justify="left")
    table.add_column("quantity")
    table.add_column("value", justify="right")
    rows = [
        ("V_ref (m/s)", f"{s.v_ref:.2f}"),
        ("peak running mean (m/s)", f"{doc['mean']['max']:.2f} at t = {doc['mean']['time_of_max']:.1f} s"),
        ("peak total (m/s)", f"{doc['total']['max']:.2f} at t = {doc['total']['time_of_max']:.1f} s"),
        ("fluctuation std (m/s)", f"{doc['fluctuation']['std']:.3f}"),
        ("L_u (m)", f"{s.length_scale:.1f}"),
        ("record (s)", f"{s.time[0]:.1f} to {s.time[-1]:.1f}, {s.time.size} steps"),
    ]
    if case.wind.type == "downburst":
        rows.insert(1, ("V_max scale (m/s)", f"{s.v_max:.2f}"))
        lp = doc["downburst"]["line_peak"]
        rows.insert(2, ("largest running mean on the line (m/s)",
                        f"{lp['speed']:.2f} = {lp['over_v_ref']:.3f} V_ref at {lp['station']:.0f} m, t = {lp['time']:.1f} s"))
    for q, v in rows:
        table.add_row(q, v)
    return table


def _write_field(case: Case, realization: int, field_out: Path) -> None:
    """--field: the run's full wind of the realization as an NPZ file, written atomically."""
    from .. import service

    fld = service.wind_field(case, realization=realization - 1)
    arrays = fld.to_npz_dict()

    def save(tmp: Path) -> None:
        with open(tmp, "wb") as fh:  # a file object: numpy would append ".npz" to a name
            np.savez(fh, **arrays)

    write_atomic(field_out, save, what="NPZ")
    console.print(f"wrote {field_out} ({fld.t.size} steps incl. {fld.burn_in:g} s burn-in, "
                  f"{fld.x_node.shape[0]} nodes)")
