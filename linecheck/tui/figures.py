"""Plot data of the results tabs (plain Python, no Textual, no plotting library).

Each function returns a :class:`Figure`: titles, axis labels and the series to
draw.  :mod:`linecheck.tui.plotting` is the only module that turns a figure into
terminal graphics, so the plotting library can be swapped in one place.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np

from ..core.names import REACTIONS
from ..io.display import kn
from ..io.document import RunDocument

REACTION_NAMES = {"Rx": "longitudinal Rx", "Ry": "transverse Ry", "Rz": "vertical Rz"}


@dataclass(frozen=True)
class Series:
    """One curve (``x``, ``y`` arrays of equal length) or one bar group (``y`` per category)."""

    label: str
    x: np.ndarray
    y: np.ndarray


@dataclass(frozen=True)
class Figure:
    """What to draw.  ``kind``: "line", "bar" or "stacked_bar" (bars use ``categories``)."""

    title: str
    xlabel: str
    ylabel: str
    series: tuple[Series, ...]
    kind: str = "line"
    categories: tuple[str, ...] = ()
    xscale: str = "linear"
    yscale: str = "linear"
    notes: tuple[str, ...] = field(default_factory=tuple)


def reaction_history(doc: RunDocument, reaction: str) -> Figure:
    """M, M+B and M+B+R of one reaction at the tower of interest [kN] (paper Figs B1-B12).

    From the document's ``time_histories`` (realization 1, thinned keeping the peaks).
    """
    th = doc.time_histories
    if th is None:
        raise ValueError(f"{doc.case}: the result document has no time histories to plot")
    t = np.asarray(th.time, dtype=float)
    blk = th.series[reaction]

    def arr(key: str) -> np.ndarray:
        return kn(np.array([np.nan if v is None else v for v in blk[key]], dtype=float))

    M, B, R = arr("M"), arr("B"), arr("R")
    return Figure(
        title=f"{doc.case}: {REACTION_NAMES[reaction]} at tower {doc.tower_of_interest}, "
              f"realization {th.realization} (wind-induced)",
        xlabel="time (s)", ylabel="kN",
        series=(Series("M+B+R (dynamic)", t, M + B + R), Series("M+B (quasi-static)", t, M + B),
                Series("M (mean)", t, M)),
    )


def _record(result: Any) -> tuple[np.ndarray, bool]:
    """Instants of the mean states and whether they vary in time (downburst)."""
    m = result.static.mean
    t = np.asarray(m.time, dtype=float)
    if t.size == 1:  # synoptic: one state for the whole record
        return np.array([result.time[0], result.time[-1]]), False
    return t, True


def _span_right_of(result: Any) -> int:
    """0-based span to the right of the tower of interest (left of the last tower)."""
    j = result.tower_index
    return min(j, result.system.n_spans - 1)


def mean_tension(result: Any) -> Figure:
    """Running-mean tension of the span next to the tower of interest, T / T0 (paper Fig. 7b-c)."""
    m = result.static.mean
    t, varies = _record(result)
    n = _span_right_of(result)
    t0 = float(result.system.tension_nominal)
    h = np.asarray(m.tension, dtype=float)[:, n] / t0
    y = h if varies else np.repeat(h[:1], 2)
    notes = () if varies else ("synoptic wind: one mean state for the whole record",)
    return Figure(
        title=f"{result.case.name}: running-mean tension of span {n + 1} / T0 "
              f"(nominal still-air T0 = {kn(t0):.2f} kN)",
        xlabel="time (s)", ylabel="T / T0", series=(Series(f"span {n + 1}", t, y),), notes=notes,
    )


def mean_displacement(result: Any) -> Figure:
    """Running-mean displacements dy, dz of point r from its still-air position [m] (paper Fig. 8).

    Point r: mid-span of the span next to the tower of interest (paper Fig. 2);
    z is upward (a conductor swinging out under wind rises: dz > 0).
    """
    m = result.static.mean
    t, varies = _record(result)
    n = _span_right_of(result)
    ne = result.system.ne
    node = n * ne + ne // 2
    d = np.asarray(m.nodes, dtype=float)[:, node, :] - np.asarray(m.still_air.nodes, dtype=float)[node, :]
    if not varies:
        d = np.repeat(d[:1], 2, axis=0)
    return Figure(
        title=f"{result.case.name}: running-mean displacement of point r (mid-span {n + 1}) from still air",
        xlabel="time (s)", ylabel="m",
        series=(Series("dy (transverse)", t, d[:, 1]), Series("dz (vertical, up +)", t, d[:, 2])),
    )


def wind_at_p(w: Any) -> Figure:
    """Running-mean and total wind speed at point p [m/s] (paper Fig. 3)."""
    t = np.asarray(w.time, dtype=float)
    step = max(1, t.size // 4000)  # a terminal shows a few hundred columns
    return Figure(
        title=f"{w.case.name}: wind speed at point p (x = {w.x:.0f} m), realization {w.realization + 1}",
        xlabel="time (s)", ylabel="m/s",
        series=(Series("total", t[::step], np.asarray(w.total)[::step]),
                Series("running mean", t[::step], np.asarray(w.mean)[::step])),
    )


def contributions(docs: list[tuple[str, RunDocument]]) -> Figure:
    """Cont_M, Cont_BG, Cont_R of each reaction [%], stacked (paper Fig. 12).

    ``docs``: ``(label, doc)`` pairs; several give the bars side by side (compare).
    """
    cats: list[str] = []
    parts: dict[str, list[float]] = {"Cont_M": [], "Cont_BG": [], "Cont_R": []}
    for label, doc in docs:
        for r in REACTIONS:
            vals = {k: doc.reactions[r][k].mean for k in parts}
            for k in parts:
                parts[k].append(0.0 if vals[k] is None else 100.0 * vals[k])
            name = f"{label} {r}".strip()
            if len(docs) == 1:  # room for the numbers under each bar
                name += ": " + " / ".join("-" if vals[k] is None else f"{100 * vals[k]:.0f}" for k in parts) + " %"
            cats.append(name)
    x = np.arange(len(cats), dtype=float)
    names = {"Cont_M": "mean M", "Cont_BG": "background BG", "Cont_R": "resonant R"}
    notes = ("Cont_BG < 0: max|M+B| is below max|M| (B negative where M peaks)",) \
        if any(v < 0 for v in parts["Cont_BG"]) else ()
    if any(v < 0 for v in parts["Cont_R"]):
        notes += (("Cont_R < 0: max|M+B+R| is below max|M+B| (R against B at the peak: inertia and damping "
                   "lower the response)"),)
    return Figure(
        title="contributions to the peak dynamic reaction, Cont_M / Cont_BG / Cont_R (%), mean over realizations",
        xlabel="", ylabel="%", notes=notes,
        series=tuple(Series(names[k], x, np.array(v)) for k, v in parts.items()),
        kind="stacked_bar", categories=tuple(cats),
    )
