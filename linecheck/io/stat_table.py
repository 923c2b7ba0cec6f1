"""The one statistics table every front end reads (labels, units, formats of each statistic of a
reaction) and the key lists of a result document's statistic blocks.

Forces in N inside; each statistic's display unit and scale (kN, %) are in its :class:`StatDef`.
"""

from __future__ import annotations

from dataclasses import dataclass

from ..core.names import REACTIONS

__all__ = ["FLAG_STATES", "GUMBEL_KEYS", "REACTIONS", "SPECTRAL_EXACT", "STAT_BY_NAME", "STAT_TABLE",
           "SUMMARY_KEYS", "StatDef", "stat_def"]

SUMMARY_KEYS = ("mean", "std", "se", "p05", "p50", "p95")
GUMBEL_KEYS = ("location", "scale", "ppcc", "design")
FLAG_STATES = ("recommended", "inconclusive")

@dataclass(frozen=True)
class StatDef:
    """One statistic: JSON key, label, short label (column headers), SI unit, kind, display unit,
    scale to it, format.

    kind: "force" [N], "ratio" [-] or "fraction" [-] (Cont_*, shown in %); ``peak``: has a
    Gumbel fit; ``ci``: has a 95 % interval (GF_Dy, GF_QS, Cont_R: a null GF is shown ``**``);
    ``summary``: shown in the summary tables; ``varies``: differs between realizations (the
    largest mean does not, so no ``± std`` column).
    """

    name: str
    label: str
    short: str
    unit: str
    kind: str
    display_unit: str
    scale: float
    fmt: str
    peak: bool = False
    ci: bool = False
    summary: bool = True
    meaning: str = ""
    varies: bool = True

    def header(self, unit_format: str = "\n({})") -> str:
        """Column header: the short label and, unless dimensionless, the shown unit."""
        return self.short + ("" if self.display_unit == "-" else unit_format.format(self.display_unit))


def _force(name, label, short, meaning, peak=False, summary=True, varies=True):
    return StatDef(name, label, short, "N", "force", "kN", 1e-3, "{:.3f}", peak=peak, summary=summary, meaning=meaning,
                   varies=varies)


def _ratio(name, label, short, meaning, **kw):
    return StatDef(name, label, short, "-", "ratio", "-", 1.0, "{:.3f}", meaning=meaning, **kw)


def _fraction(name, meaning, **kw):
    return StatDef(name, name, name, "-", "fraction", "%", 100.0, "{:.1f}", meaning=meaning, **kw)


STAT_TABLE: tuple[StatDef, ...] = (
    _force("mean_max", "mean max", "mean M", "largest wind-induced mean reaction max_t |M|", varies=False),
    _force("rms_background", "rms background B", "rms B", "r.m.s. of the background reaction B"),
    _force("rms_resonant", "rms resonant R", "rms R", "r.m.s. of the resonant reaction R = F - B"),
    _force("rms_fluctuating", "rms fluctuating B+R", "rms B+R", "r.m.s. of B + R", summary=False),
    _force("peak_quasi_static", "peak quasi-static M+B", "peak QS", "max_t |M + B| (wind-induced)", peak=True),
    _force("peak_dynamic", "peak dynamic M+B+R", "peak Dy", "max_t |M + B + R| (wind-induced)", peak=True),
    _force("peak_quasi_static_total", "peak quasi-static total", "peak QS total", "max_t |still air + M + B|",
           peak=True, summary=False),
    _force("peak_dynamic_total", "peak dynamic total", "peak Dy total", "max_t |still air + M + B + R|", peak=True,
           summary=False),
    _ratio("GF_Dy", "GF_Dy", "GF_Dy", "dynamic gust factor peak_dynamic / mean_max (Eq. 15)", ci=True),
    _ratio("GF_QS", "GF_QS", "GF_QS", "quasi-static gust factor peak_quasi_static / mean_max (Eq. 15)", ci=True),
    _fraction("Cont_M", "mean share mean_max / peak_dynamic (Eq. 16)"),
    _fraction("Cont_BG", "background share (peak_QS - mean_max) / peak_dynamic (Eq. 16)"),
    _fraction("Cont_R", "resonant share (peak_dynamic - peak_QS) / peak_dynamic (Eq. 16)", ci=True),
    _ratio("peak_normalised", "peak / g*_yp L", "peak / g*yp Lx", "peak_dynamic / (g*_yp L_x) (Eq. 17)", peak=True),
    _ratio("peak_normalised_total", "peak total / g*_yp L", "peak total / g*yp Lx", "peak_dynamic_total / (g*_yp L_x)",
           peak=True, summary=False),
)
STAT_BY_NAME = {s.name: s for s in STAT_TABLE}


def stat_def(name: str) -> StatDef:
    """The :class:`StatDef` of statistic ``name``."""
    return STAT_BY_NAME[name]


#: Keys of a spectral block's exact estimate (``spectral.exact[R][key]``), in JSON order, each
#: with the time-domain statistic of :data:`STAT_TABLE` it is compared with (its label, unit and
#: format), or None for a frequency-domain quantity only (a zero-crossing rate [Hz]).
SPECTRAL_EXACT: tuple[tuple[str, str | None], ...] = (
    ("mean", "mean_max"),
    ("rms_background", "rms_background"),
    ("rms_resonant", "rms_resonant"),
    ("rms_fluctuating", "rms_fluctuating"),
    ("peak_quasi_static", "peak_quasi_static"),
    ("peak_dynamic", "peak_dynamic"),
    ("GF_Dy", "GF_Dy"),
    ("GF_QS", "GF_QS"),
    ("Cont_R", "Cont_R"),
    ("nu_background", None),
    ("nu_fluctuating", None),
)
