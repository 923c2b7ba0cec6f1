"""``linecheck modes`` pairs each damped mode with its undamped counterpart by shape (MAC), not
by rank."""

from __future__ import annotations

import json

import numpy as np
from typer.testing import CliRunner

from linecheck import service
from linecheck.cli.app import app
from linecheck.core.case import load_case
from linecheck.core.model import build_model
from linecheck.core.modes import natural_modes, pair_by_shape
from linecheck.core.spectral import complex_modes

from ..conftest import CASES

runner = CliRunner()
PAPER = CASES / "paper" / "case01-single.toml"
SECTION = CASES / "examples" / "section-12span.toml"


def test_undamped_complex_modes_pair_with_themselves():
    """No damping: the complex modes are the undamped ones, MAC 1, frequencies equal."""
    case = load_case(PAPER)
    st = service.static_analysis(case)
    model = build_model(st.system, st.mean.still_air)
    modes = natural_modes(model, 8)
    cm = complex_modes(model, np.zeros_like(model.K_band), vectors=True)
    index, mac = pair_by_shape(modes, model, cm.right, cm.S)
    np.testing.assert_allclose(mac, 1.0, atol=1e-6)
    np.testing.assert_allclose(cm.frequencies_hz[index], modes.frequencies_hz, rtol=1e-8)


def test_modes_pairs_damped_with_undamped_by_shape(tmp_path):
    """Quasi-steady damping is aerodynamic, along the wind (y): on the 12-span section every y
    mode's damped counterpart is more damped than any z mode's, and the pairing is not the rank
    order (damping moves near-degenerate y and z modes past each other)."""
    res = service.modes_analysis(load_case(SECTION), n_modes=12)
    dm = res.mean.dominant_direction()
    assert np.all(np.isfinite(res.paired_hz)) and np.all(res.paired_mac > 0.5)
    np.testing.assert_allclose(res.paired_hz, res.mean.frequencies_hz, rtol=0.03)
    assert res.paired_ratio[dm == 1].min() > res.paired_ratio[dm == 2].max()
    assert np.any(res.paired_hz != np.sort(res.paired_hz))  # rank order would pair other shapes
    out = tmp_path / "m.json"
    cli = runner.invoke(app, ["modes", str(SECTION), "--count", "12", "--json", str(out)], terminal_width=200)
    assert cli.exit_code == 0, cli.output
    assert "MAC" in cli.output and "whose shape matches the row's mean-state mode" in cli.output
    doc = json.loads(out.read_text())
    np.testing.assert_allclose(doc["mean"]["paired_damped"]["damping_ratios"], res.paired_ratio)
    np.testing.assert_allclose(doc["mean"]["paired_damped"]["mac"], res.paired_mac)
    row = next(ln for ln in cli.output.splitlines() if ln.startswith("│    4 │"))
    assert f"{res.paired_hz[3]:.4f}" in row and f"{res.paired_mac[3]:.2f}" in row
