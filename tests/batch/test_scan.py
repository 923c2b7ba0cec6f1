"""Critical-downburst scan: grid parsing, executors, the paper's Db_x / Db_y."""

from __future__ import annotations

import csv
import dataclasses
import io
import math
import re
import shutil
from pathlib import Path

import numpy as np
import pytest
from typer.testing import CliRunner

from linecheck.batch import ScanGrid, SequentialExecutor, parse_values, run_scan, scan_csv_text
from linecheck.batch.tasks import fixed_jet_case, scan_point
from linecheck.cli.app import app
from linecheck.core.case import load_case
from linecheck.core.errors import CaseError
from linecheck.core.wind.mean import downburst_field

from ..conftest import CASES
from .test_batch import pool, write_short_case  # noqa: F401  (pool: shared session fixture)

runner = CliRunner(env={"COLUMNS": "250"})


def paper_line_case(tmp_path: Path, spans: str = "six", mean_states: int = 40) -> Path:
    """The paper's line (L = 300 m, D_j = 2 L = 600 m, Db_x preset) with fewer step-1 instants."""
    text = (CASES / "paper" / f"case01-{spans}.toml").read_text(encoding="utf-8")
    text = text.replace("[analysis]", f"[analysis]\nmean_states = {mean_states}", 1)
    p = tmp_path / f"paper-line-{spans}.toml"
    p.write_text(text, encoding="utf-8")
    return p


# --------------------------------------------------------------------------- grid
def test_parse_values_ranges_lists_and_dj():
    assert parse_values("0:90:30", "--angle") == ((0.0, 30.0, 60.0, 90.0), False)
    assert parse_values("1.0:1.6:0.2Dj", "--distance", LENGTH) == ((1.0, 1.2, 1.4, 1.6), True)
    assert parse_values("600, 900 m", "--jet-diameter", ("m",)) == ((600.0, 900.0), False)
    assert parse_values("1.2 Dj", "--distance", LENGTH) == ((1.2,), True)
    assert parse_values("90:0:-45", "--angle")[0] == (90.0, 45.0, 0.0)
    for bad in ("", "1:2m", "a:b:cm", "0:10:0m", "0:10:-1m", "nan m"):
        with pytest.raises(CaseError):
            parse_values(bad, "--distance", LENGTH)


LENGTH = ("m", "Dj")


@pytest.mark.parametrize("text, values, relative", [
    ("720m", (720.0,), False),
    ("1.2Dj", (1.2,), True),
    ("1.2 * D_j", (1.2,), True),
    ("1.2Dj,1.6Dj", (1.2, 1.6), True),  # a unit after every number
    ("1.2,1.6Dj", (1.2, 1.6), True),  # or once after the last, for all of them
    ("720m, 960m", (720.0, 960.0), False),
    ("600:900:100m", (600.0, 700.0, 800.0, 900.0), False),  # a range: one unit for the range
    ("600m:900m:100m", (600.0, 700.0, 800.0, 900.0), False),  # or one per number
    ("0.5:1.5:0.5dj", (0.5, 1.0, 1.5), True),
])
def test_scan_lengths_accepted_with_their_unit(text, values, relative):
    assert parse_values(text, "--distance", LENGTH) == (values, relative)


@pytest.mark.parametrize("option, text, why", [
    ("--distance", "1.2,1.6", "a length needs its unit, m (metres) or Dj (multiples of the jet diameter)"),
    ("--distance", "720", "a length needs its unit"),
    ("--distance", "0.5:2.5:0.1", "a length needs its unit"),
    ("--distance", "1.2Dj,720m", "one unit for every number (Dj and m given"),
    ("--distance", "1.2Dj,1.6", "a unit after every number, or once after the last for all of them"),
    ("--distance", "600:900m:100", "a unit after every number, or once after the last"),
    ("--jet-diameter", "600,900", "a length needs its unit, m (metres)"),
    ("--jet-diameter", "1.2Dj", "--jet-diameter takes m (metres), not Dj"),
    ("--angle", "0:1:1Dj", "(no unit)"),
])
def test_scan_refuses_a_length_without_its_unit_in_one_line(option, text, why):
    """A bare number is refused (``--distance 1.2,1.6`` used to scan 1.2 m and 1.6 m, a storm on
    the tower), exit 2, one line naming the option, the value and what is allowed."""
    path = CASES / "paper" / "case01-single.toml"
    r = runner.invoke(app, ["scan", str(path), option, text, "--jobs", "1"])
    assert r.exit_code == 2, r.output
    out = " ".join(r.output.split())
    assert f"{option}: value {text!r} is not allowed: " in out and why in out, out
    if option != "--angle":
        assert "e.g." in out
    assert len([ln for ln in r.output.splitlines() if ln.strip()]) == 1, r.output


def test_grid_points_relative_distance_and_defaults():
    case = load_case(CASES / "paper" / "case01-single.toml")
    g = ScanGrid.from_options(case, "1.2:1.6:0.4Dj", "0,30", "600,900m")
    pts = g.points()
    assert pts.shape == (8, 3) and g.size == 8
    np.testing.assert_allclose(pts[:4], [[720, 0, 600], [720, 30, 600], [960, 0, 600], [960, 30, 600]])
    np.testing.assert_allclose(pts[4], [1080, 0, 900])
    d = ScanGrid.from_options(case)  # defaults: 0.5..2.5 D_j, -80..80 deg, the case's D_j
    assert d.distance_relative and len(d.distances) == 21 and d.angles[0] == -80 and d.jet_diameters == (600.0,)
    synoptic = load_case(CASES / "paper" / "case09-single.toml")
    with pytest.raises(CaseError, match="downburst"):
        ScanGrid.from_options(synoptic)
    with pytest.raises(CaseError, match="no unit"):
        ScanGrid.from_options(case, angle="0:1:1Dj")


def test_fixed_jet_case_holds_the_storm_strength():
    case = load_case(CASES / "paper" / "case01-single.toml")  # Db_x, V_ref = 40 m/s at p
    vmax = downburst_field(case).v_max
    assert math.isclose(fixed_jet_case(case, vmax).wind.v_ref, 40.0, rel_tol=1e-12)
    peak, _, v_ref = scan_point(case, 960.0, 30.0, 600.0, vmax)  # the preset's own geometry
    assert math.isclose(v_ref, 40.0, rel_tol=1e-9)
    peak_vref, _, v_ref2 = scan_point(case, 960.0, 30.0, 600.0, None)
    assert v_ref2 == 40.0 and np.allclose(peak, peak_vref, rtol=1e-9)


# --------------------------------------------------------------------------- the paper's line
def test_scan_finds_paper_critical_configurations(tmp_path):
    """Six spans, L = 300 m, D_j = 600 m: Ry critical at Db_y (1.2 D_j, 0 deg); Rx at Theta = 30 deg
    (R = 1.4 D_j here against the paper's 1.6 D_j: see docs/validation.md)."""
    path = paper_line_case(tmp_path)
    case = load_case(path)
    grid = ScanGrid.from_options(case, "1.0:1.6:0.2Dj", "0,30,60")
    res = run_scan(path, grid)
    assert res.n_failed == 0 and res.hold == "jet"
    ry, rx = res.critical("Ry"), res.critical("Rx")
    assert (ry.distance_over_dj, ry.angle, ry.jet_diameter) == pytest.approx((1.2, 0.0, 600.0))
    assert (rx.distance_over_dj, rx.angle) == pytest.approx((1.4, 30.0))
    assert ry.value > 0 and abs(ry.value) > 4 * abs(rx.value)
    # the transverse reaction falls off away from the critical distance, the longitudinal one
    # vanishes at Theta = 0 (symmetric loading of the spans next to the middle tower)
    theta0 = res.points[:, 1] == 0.0
    assert np.all(np.abs(res.peak[theta0, 0]) < 1e-3 * abs(rx.value))


def test_scan_pool_equals_sequential_and_csv(tmp_path, pool):  # noqa: F811
    path = tmp_path / "case01-single.toml"
    path.write_bytes((CASES / "paper" / "case01-single.toml").read_bytes())
    case = load_case(path)
    grid = ScanGrid.from_options(case, "0.8:1.6:0.4Dj", "-30:30:30")
    seq = run_scan(path, grid, executor=SequentialExecutor())
    par = run_scan(path, grid, executor=pool, chunk_size=2)
    assert np.array_equal(seq.peak, par.peak, equal_nan=True)
    assert np.array_equal(seq.time, par.time, equal_nan=True)
    rows = list(csv.DictReader(io.StringIO(scan_csv_text(par))))
    assert len(rows) == grid.size
    assert float(rows[0]["distance_over_dj"]) == pytest.approx(0.8) and float(rows[0]["angle_deg"]) == -30.0
    crit = par.critical("Ry")
    assert float(rows[crit.index]["Ry_N"]) == crit.value


def test_scan_hold_vref_keeps_v_ref_at_p(tmp_path):
    path = CASES / "paper" / "case01-single.toml"
    case = load_case(path)
    res = run_scan(path, ScanGrid.from_options(case, "1.2Dj", "0,30"), hold="vref")
    assert np.all(res.v_ref == case.wind.v_ref) and res.v_max is None
    with pytest.raises(CaseError, match="--hold"):
        run_scan(path, ScanGrid.from_options(case, "1.2Dj", "0"), hold="storm")


def test_scan_reports_points_that_cannot_be_analysed():
    path = CASES / "paper" / "case01-single.toml"
    case = load_case(path)
    res = run_scan(path, ScanGrid.from_options(case, "1.2Dj", "0,90"))  # 90 deg: centre on the line
    assert res.n_failed == 1 and res.errors[1] and "point p" in res.errors[1]
    assert np.all(np.isnan(res.peak[1])) and res.critical("Ry").index == 0


# --------------------------------------------------------------------------- CLI
def test_cli_scan_table_csv_and_dynamic(tmp_path):
    path = write_short_case(CASES / "paper" / "case01-single.toml", tmp_path, realizations=2, duration=30.0)
    out = tmp_path / "scan.csv"
    r = runner.invoke(app, ["scan", str(path), "--distance", "1.2:1.6:0.4Dj", "--angle", "0,30", "--csv", str(out),
                            "--dynamic", "--jobs", "1", "--json-dir", str(tmp_path / "dyn")])
    assert r.exit_code == 0, r.output
    assert "critical downburst configurations" in r.output and "Db_x: R = 1.6 D_j" in r.output
    assert "full analysis at the critical configurations" in r.output
    assert "by the expected dynamic peak" in r.output and "same position" in r.output
    # one table says which number to design for: the full analysis at the case's V_ref at p,
    # beside the scan's expected peak and the V_ref at p it was ranked at
    flat = " ".join(r.output.replace("│", " ").split())
    assert "design values: full analysis at the critical configurations at the case's V_ref = 40 m/s at point p" in flat
    assert 'design for the "design peak" columns' in flat and "a ranking, not a design value" in flat
    assert re.search(r"done Rx \d+\.\d{3}, Ry", flat), flat  # the scan peak of the run's reactions
    assert len(out.read_text().splitlines()) == 1 + 4
    assert list((tmp_path / "dyn").glob("*.json"))


def test_scan_ranks_by_the_expected_dynamic_peak(tmp_path):
    """With dynamic_realizations the scan runs steps 1-3 at every position; the value
    ranked is the realization mean of the dynamic peak |M+B+R| at the tower of interest, equal
    to run_case's own statistics there (same seeds).  (It is not bounded below by the point's
    largest |mean|: a downburst's mean peak is brief, and a realization whose gust is negative
    through it peaks lower -- case01-six at R = 1.1 D_j: 6.46 kN against a 7.23 kN mean.)"""
    from linecheck.batch.tasks import apply_changes, scan_changes
    from linecheck.service import run_case

    path = write_short_case(CASES / "paper" / "case01-single.toml", tmp_path, realizations=2, duration=30.0)
    grid = ScanGrid.from_options(load_case(path), "1.2,1.6Dj", "30", None)
    res = run_scan(path, grid, hold="vref", dynamic_realizations=2)
    assert res.dynamic is not None and res.dynamic.shape == (2, 3)
    assert np.all(np.isfinite(res.dynamic)) and np.all(res.dynamic > 0)
    crit = res.critical("Ry", "peak")
    r, th, dj = res.points[crit.index]
    again = run_case(apply_changes(load_case(path), scan_changes(r, th, dj)), realizations=[0, 1], spectral_check=False)
    assert crit.value == again.stats.peak_dynamic[:, 0, 1].mean()  # bit-identical: same case and seeds
    assert res.critical("Ry", "mean") is not None
    assert "Ry_peak_N" in scan_csv_text(res).splitlines()[0]


def test_cli_scan_usage_errors(tmp_path):
    path = CASES / "paper" / "case01-single.toml"
    r = runner.invoke(app, ["scan", str(path), "--distance", "1:2m"])
    assert r.exit_code == 2 and "START:STOP:STEP" in r.output
    r = runner.invoke(app, ["scan", str(CASES / "paper" / "case09-single.toml")])
    assert r.exit_code == 2 and "downburst" in r.output


@pytest.mark.slow
def test_scan_paper_line_full_grid(tmp_path):
    """R = 0.8..2.0 D_j by 0.2, Theta = 0..90 deg by 15 on the paper's six-span line (all step-1 instants)."""
    from linecheck.batch import ProcessPool

    path = paper_line_case(tmp_path, mean_states=250)
    case = load_case(path)
    with ProcessPool(2) as ex:
        res = run_scan(path, ScanGrid.from_options(case, "0.8:2.0:0.2Dj", "0:90:15"), executor=ex)
    ry, rx = res.critical("Ry"), res.critical("Rx")
    assert (ry.distance_over_dj, ry.angle) == pytest.approx((1.2, 0.0))
    assert (rx.distance_over_dj, rx.angle) == pytest.approx((1.4, 30.0))


def test_scan_positions_share_the_unit_turbulence_bit_for_bit(monkeypatch):
    """The unit turbulence depends on the nodes, V_ref, L_u, the seed and the record, not on where
    the downburst is: a scan's positions reuse it from the per-process memo (scans with dynamic peaks), and the
    velocity is the same bits as computed afresh with the memo off."""
    from linecheck.batch.tasks import apply_changes, scan_changes
    from linecheck.core.system import LineSystem
    from linecheck.core.wind import turbulence as tb
    from linecheck.service import record_time

    case = load_case(CASES / "paper" / "case05-six.toml")
    system = LineSystem(case.line)
    t = record_time(case)
    tb._memo.clear()
    a = tb.fluctuating_velocity(case, system, t, [0, 1])
    assert len(tb._memo) == 2
    moved = apply_changes(case, scan_changes(900.0, 20.0, case.wind.downburst.jet_diameter))
    b = tb.fluctuating_velocity(moved, system, t, [1])
    assert len(tb._memo) == 2  # reused, not recomputed
    assert not next(iter(tb._memo.values())).flags.writeable
    monkeypatch.setattr(tb, "UNIT_FIELD_MEMO_BYTES", 0.0)
    tb._memo.clear()
    assert np.array_equal(a, tb.fluctuating_velocity(case, system, t, [0, 1]))
    assert np.array_equal(b, tb.fluctuating_velocity(moved, system, t, [1]))
    assert not np.array_equal(a[1], b[0])  # the running mean (the modulation) differs
    assert len(tb._memo) == 0


def test_one_storm_scan_positions_share_the_phases_bit_for_bit(monkeypatch):
    """A one-storm scan (``--hold jet``) gives each position its own V_ref at p, hence its own unit
    field; the random phases and their compiled phasors are shared (turbulence.unit_phases,
    for scans with dynamic peaks), and the fields are the same bits as computed with every memo off."""
    from linecheck.batch.tasks import apply_changes, fixed_jet_case, scan_changes
    from linecheck.core import kernel
    from linecheck.core.system import LineSystem
    from linecheck.core.wind import turbulence as tb
    from linecheck.core.wind.mean import downburst_field
    from linecheck.service import record_time

    compiled = kernel.available()  # the phasors are the compiled kernel's (else only the fields are shared)
    if compiled:
        monkeypatch.setenv("LINECHECK_KERNEL", "numba")
    case = load_case(CASES / "paper" / "case05-six.toml")
    system = LineSystem(case.line)
    t = record_time(case)[:2001]
    v_max = float(downburst_field(case).v_max)
    moved = [fixed_jet_case(apply_changes(case, scan_changes(d, 20.0, case.wind.downburst.jet_diameter)), v_max)
             for d in (700.0, 900.0)]
    assert moved[0].wind.v_ref != moved[1].wind.v_ref  # one storm: V_ref at p differs
    tb._memo.clear()
    tb._phase_memo.clear()
    calls = []
    real = tb.random_phases
    monkeypatch.setattr(tb, "random_phases", lambda *a: calls.append(a) or real(*a))
    got = [tb.fluctuating_velocity(c, system, t, [0, 1]) for c in moved]
    assert len(tb._memo) == 4  # a unit field per position and realization
    if compiled:
        assert len(calls) == 2 and len(tb._phase_memo) == 2  # the phases drawn once per realization
        assert not tb._phase_memo[next(iter(tb._phase_memo))].phasors[0].flags.writeable
    monkeypatch.setattr(tb, "UNIT_FIELD_MEMO_BYTES", 0.0)
    tb._memo.clear()
    tb._phase_memo.clear()
    for c, g in zip(moved, got):
        assert np.array_equal(g, tb.fluctuating_velocity(c, system, t, [0, 1]))
    assert len(tb._memo) == 0 and len(tb._phase_memo) == 0
    assert not np.array_equal(tb.unit_field(moved[0], system, t.size, 0.05, 0),
                              tb.unit_field(moved[1], system, t.size, 0.05, 0))  # the spectra differ


@pytest.mark.parametrize("name, toi, options", [
    ("paper/case01-six", 4, 'drag = "linear"\ntension = "linear"\n'),  # a downburst's 40 mean states
    ("paper/case01-six", 1, 'drag = "quadratic"\ntension = "second-order"\n'),  # a strain tower: direct loads
    ("examples/section-12span", 5, 'drag = "quadratic"\ntension = "second-order"\n'),  # an 18 deg angle-strain tower
])
def test_run_tower_equals_run_case_at_the_tower_of_interest(tmp_path, name, toi, options):
    """A scan's steps 1-3 compute the tower of interest's reactions alone (service.run_tower:
    its rows of G, of the direct loads and of the second-order forms; its own frame); every
    statistic there is the same bits as run_case's, the gust factors' definedness included (it is
    decided against the whole section's largest mean)."""
    from linecheck.service import run_case, run_tower

    src = CASES / f"{name}.toml"
    if (CASES / f"{name}.csv").exists():
        shutil.copy(CASES / f"{name}.csv", tmp_path)
    path = write_short_case(src, tmp_path, realizations=2, duration=30.0)
    text = re.sub(r'(?m)^\s*(tower_of_interest\s*=\s*\d+|(drag|tension)\s*=\s*").*$', "", path.read_text(encoding="utf-8"))
    text = text.replace("[analysis]", f"[analysis]\nmean_states = 40\n{options}", 1)
    text = text.replace("[line]", f"[line]\ntower_of_interest = {toi}", 1)
    path.write_text(text, encoding="utf-8")
    case = load_case(path)
    assert case.line.tower_of_interest == toi and (case.analysis.tension == "second-order") == ("second" in options)
    full = run_case(case, realizations=[0, 1], spectral_check=False)
    one = run_tower(case, realizations=[0, 1])
    for f in dataclasses.fields(one.stats):
        a, b = getattr(full.stats, f.name)[:, toi - 1], getattr(one.stats, f.name)
        assert b.shape == (2, 1, 3)
        assert np.array_equal(a, b[:, 0], equal_nan=True), f.name
    assert np.isfinite(one.stats.peak_dynamic).all() and not np.isnan(one.stats.GF_Dy[:, 0, 1]).any()
