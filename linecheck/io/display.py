"""Display of result statistics shared by the CLI table and the TUI (plain Python).

Forces in kN with 3 decimals, Cont_* in % with 1 decimal, ratios with 3 decimals,
``± std`` over realizations when there are several, ``**`` where a gust factor is
undefined (mean zero by symmetry).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any


@dataclass(frozen=True)
class Stat:
    """One summary row: JSON key, label, unit, scale to the shown unit, format."""

    key: str
    label: str
    unit: str
    scale: float
    fmt: str


SUMMARY_STATS: tuple[Stat, ...] = (
    Stat("mean_max", "mean max", "kN", 1e-3, "{:.3f}"),
    Stat("rms_background", "rms background B", "kN", 1e-3, "{:.3f}"),
    Stat("rms_resonant", "rms resonant R", "kN", 1e-3, "{:.3f}"),
    Stat("peak_quasi_static", "peak quasi-static M+B", "kN", 1e-3, "{:.3f}"),
    Stat("peak_dynamic", "peak dynamic M+B+R", "kN", 1e-3, "{:.3f}"),
    Stat("GF_Dy", "GF_Dy", "-", 1.0, "{:.3f}"),
    Stat("GF_QS", "GF_QS", "-", 1.0, "{:.3f}"),
    Stat("Cont_M", "Cont_M", "%", 100.0, "{:.1f}"),
    Stat("Cont_BG", "Cont_BG", "%", 100.0, "{:.1f}"),
    Stat("Cont_R", "Cont_R", "%", 100.0, "{:.1f}"),
    Stat("peak_normalised", "peak / g*_yp L", "-", 1.0, "{:.3f}"),
)


def stat_text(entry: dict[str, Any], stat: Stat, n_real: int) -> str:
    """``mean`` (``± std`` when ``n_real`` > 1) of one ``{"mean", "std"}`` entry, ``**`` when null."""
    m, s = entry.get("mean"), entry.get("std")
    if m is None:
        return "**"
    text = stat.fmt.format(m * stat.scale)
    if n_real > 1 and s is not None:
        text += " ± " + stat.fmt.format(s * stat.scale)
    return text


