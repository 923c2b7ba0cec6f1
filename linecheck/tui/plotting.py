"""The one plotting adapter of the TUI: draws a :class:`~linecheck.tui.figures.Figure`.

Everything else in the TUI builds figures as plain data; only this module knows
the plotting library (textual-plotext 1.0.1, which pins plotext < 6).  To swap the
library, re-implement :class:`PlotView` here.
"""

from __future__ import annotations

import numpy as np
from rich.text import Text
from textual.app import ComposeResult
from textual.containers import Vertical
from textual.widgets import Static

from .figures import Figure

try:
    from textual_plotext import PlotextPlot
except ImportError:  # pragma: no cover - the TUI still works, without the pictures
    PlotextPlot = None  # type: ignore[assignment,misc]

MISSING = "(plots need textual-plotext: pip install 'textual-plotext>=1.0.1')"

# RGB so that the legend (drawn in the caption, where it never hides data) matches the curves
COLORS = ((230, 80, 80), (90, 150, 250), (120, 200, 90), (240, 170, 50), (200, 110, 220), (80, 200, 200))
BAR_COLORS = ((150, 110, 240), (120, 200, 90), (240, 150, 40))  # mean, background, resonant (Fig. 12)


class PlotView(Vertical):
    """A plot with a one-line caption; shows ``empty_text`` until a figure is given.

    ``figure`` holds the data last shown (tests assert on it, not on pixels).
    """

    def __init__(self, empty_text: str = "Nothing to plot yet.", **kwargs) -> None:
        super().__init__(**kwargs)
        self.empty_text = empty_text
        self.figure: Figure | None = None

    def compose(self) -> ComposeResult:
        yield Static(self.empty_text, classes="plot-caption")
        if PlotextPlot is not None:
            yield PlotextPlot(classes="plot-canvas")

    def on_mount(self) -> None:
        if PlotextPlot is not None:
            self.query_one(PlotextPlot).display = False

    def show(self, figure: Figure | None, empty_text: str | None = None) -> None:
        """Draw ``figure`` (``None``: clear and show ``empty_text``)."""
        self.figure = figure
        caption = self.query_one(".plot-caption", Static)
        if PlotextPlot is None:
            if figure is None:
                caption.update(empty_text if empty_text is not None else self.empty_text)
            else:
                caption.update(_caption(figure).append("\n" + MISSING, style="yellow"))
            return
        canvas = self.query_one(PlotextPlot)
        if figure is None:
            caption.update(empty_text if empty_text is not None else self.empty_text)
            canvas.display = False
            return
        caption.update(_caption(figure))
        canvas.display = True
        _draw(canvas, figure)
        canvas.refresh()


def _colors(fig: Figure) -> tuple[tuple[int, int, int], ...]:
    return BAR_COLORS if fig.kind == "stacked_bar" else COLORS


def _caption(fig: Figure) -> Text:
    """Title, notes and the legend (coloured like the curves)."""
    text = Text(" · ".join((fig.title,) + fig.notes))
    text.append("\n")
    colors = _colors(fig)
    for i, s in enumerate(fig.series):
        r, g, b = colors[i % len(colors)]
        text.append("  ██ " if fig.kind != "line" else "  ━━ ", style=f"bold rgb({r},{g},{b})")
        text.append(s.label)
    return text


def _finite(x: np.ndarray, y: np.ndarray) -> tuple[list[float], list[float]]:
    ok = np.isfinite(x) & np.isfinite(y)
    return x[ok].tolist(), y[ok].tolist()


def _draw(canvas: PlotextPlot, fig: Figure) -> None:
    plt = canvas.plt
    plt.clear_figure()
    plt.xlabel(fig.xlabel)
    plt.ylabel(fig.ylabel)
    colors = _colors(fig)
    if fig.kind == "stacked_bar":
        plt.stacked_bar(list(fig.categories), [s.y.tolist() for s in fig.series],
                        color=[colors[i % len(colors)] for i in range(len(fig.series))], width=0.6)
        return
    if fig.kind == "bar":
        plt.multiple_bar(list(fig.categories), [s.y.tolist() for s in fig.series],
                         color=[colors[i % len(colors)] for i in range(len(fig.series))])
        return
    plt.xscale(fig.xscale)
    plt.yscale(fig.yscale)
    for i, s in enumerate(fig.series):
        x, y = _finite(np.asarray(s.x, dtype=float), np.asarray(s.y, dtype=float))
        if x:
            plt.plot(x, y, marker="braille", color=colors[i % len(colors)])
