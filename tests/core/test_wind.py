"""Wind fields: downburst running mean, user field tables, turbulence synthesis.

Statistical checks use fixed seeds; each tolerance is justified next to it from the
sampling error of the estimator for the number of records, bins and nodes used.
"""

from __future__ import annotations

import hashlib
import math
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from scipy.integrate import quad

from linecheck.core.case import case_from_dict, load_case, replace
from linecheck.core.errors import CaseError
from linecheck.core.system import LineSystem
from linecheck.core.wind import mean as wm
from linecheck.core.wind import turbulence as tb

from ..conftest import CASES

# --------------------------------------------------------------------------- helpers
LINE6 = dict(
    spans=6, span_length=300.0, sag=10.0, weight=17.92, diameter=0.022, drag_coefficient=1.0, area=0.7e-4,
    elastic_modulus=5.2e10, height=43.0, insulator_length=4.0,
    supports=["strain"] + ["suspension"] * 5 + ["strain"], tower_of_interest=4, elements_per_span=10,
)


def make_case(downburst: dict | None = None, *, analysis: dict | None = None, wind: dict | None = None,
              line: dict | None = None, base_dir: Path | None = None):
    """A six-span paper line (Table 1) with the given wind (downburst when ``downburst`` is given)."""
    w = {"type": "downburst" if downburst is not None else "synoptic", "v_ref": 40.0}
    w.update(wind or {})
    if downburst is not None:
        w["downburst"] = downburst
    doc = {"name": "t", "line": {**LINE6, **(line or {})}, "wind": w, "analysis": analysis or {}}
    return case_from_dict(doc, base_dir=base_dir)


DB_Y = {"preset": "Db_y"}
DB_X = {"preset": "Db_x"}


def write_table_csv(path: Path, r, z, t, v, vertical=None) -> Path:
    """A field table in the documented CSV layout (repr floats: exact round trip)."""
    head = "r_over_dj,z_over_dj,t,v_radial" + (",v_vertical" if vertical is not None else "")
    rows = ["# test table", head]
    for i, ri in enumerate(r):
        for j, zj in enumerate(z):
            for k, tk in enumerate(t):
                extra = f",{float(vertical[i, j, k])!r}" if vertical is not None else ""
                rows.append(f"{float(ri)!r},{float(zj)!r},{float(tk)!r},{float(v[i, j, k])!r}{extra}")
    path.write_text("\n".join(rows) + "\n")
    return path


def analytic_table(r, z, t, dj=600.0):
    """The analytic model (defaults) tabulated on (r/D_j, z/D_j, t)."""
    fr = wm.radial_profile(np.asarray(r) * dj, wm.R_MAX_OVER_DJ * dj, wm.RADIAL_DECAY_OVER_DJ * dj)
    fz = wm.vertical_profile(np.asarray(z) * dj, wm.wood_delta(wm.Z_MAX_OVER_DJ * dj))
    pi = wm.intensity(np.asarray(t), wm.T1_DEFAULT, wm.T_F_DEFAULT)
    return fr[:, None, None] * fz[None, :, None] * pi[None, None, :]


# --------------------------------------------------------------------------- profiles
def test_profiles_match_their_published_definitions():
    # Holmes & Oliver (2000): peak 1 at r_max, e^-1 one decay length beyond
    assert wm.radial_profile(720.0, 720.0, 300.0) == pytest.approx(1.0, rel=1e-15)
    assert wm.radial_profile(360.0, 720.0, 300.0) == pytest.approx(0.5, rel=1e-15)
    assert wm.radial_profile(1020.0, 720.0, 300.0) == pytest.approx(math.exp(-1.0), rel=1e-14)
    # Wood et al. (2001): delta is where the speed is half the peak; the peak sits at z_max
    z_max = 15.0
    delta = wm.wood_delta(z_max)
    zs = np.linspace(0.1, 100.0, 200001)
    assert zs[np.argmax(wm.vertical_profile(zs, delta))] == pytest.approx(z_max, abs=1e-3)
    assert wm.vertical_profile(delta, delta) == pytest.approx(0.5, abs=1e-3)  # 1.55 (1 - erf 0.7) = 0.4994
    assert wm.vertical_profile(z_max, delta) == pytest.approx(1.0, abs=1e-4)
    # Chay et al. (2006): linear rise to 1 at T1, 0.1 at T_f
    assert wm.intensity([0.0, 60.0, 120.0, 600.0], 120.0, 600.0) == pytest.approx([0.0, 0.5, 1.0, 0.1], rel=1e-14)


def test_von_karman_closed_form_cumulative_and_spectrum():
    L, V = 173.3, 40.0
    for f in (1e-3, 0.02, 0.3, 4.0):
        q = quad(lambda s: float(tb.von_karman_psd(s, L, V)), 0.0, f, limit=200)[0]
        assert tb.von_karman_cumulative(f, L, V) == pytest.approx(q, rel=1e-10)
    # n S(n)/sigma^2 = 4 x / (1 + 70.8 x^2)^(5/6) at x = 1
    f1 = V / L
    assert f1 * tb.von_karman_psd(f1, L, V) == pytest.approx(4.0 / 71.8 ** (5 / 6), rel=1e-14)
    assert tb.von_karman_cumulative(np.inf, L, V) == pytest.approx(1.0, abs=2e-4)  # 70.8 rounds the exact constant


def test_length_scale_defaults_and_override():
    assert tb.length_scale(make_case()) == pytest.approx(52.0 / 0.3)
    assert tb.length_scale(make_case(DB_X)) == 600.0  # D_j = 2 L_x
    assert tb.length_scale(make_case(DB_X, wind={"length_scale": 250.0})) == 250.0


# --------------------------------------------------------------------------- downburst running mean
@pytest.mark.parametrize("preset", ["Db_x", "Db_y"])
def test_running_mean_at_p_peaks_at_exactly_vref(preset):
    case = make_case({"preset": preset})
    fld = wm.downburst_field(case)
    t = np.linspace(0.0, 600.0, 6001)  # contains T1 = 120 s
    vx, vy = wm.mean_velocity_at(case, [fld.point_p], t)
    speed = np.hypot(vx, vy)[:, 0]
    assert speed.max() == pytest.approx(40.0, rel=1e-13)
    assert t[np.argmax(speed)] == wm.T1_DEFAULT
    # at p the outflow is normal to the line (p is the foot of the perpendicular)
    assert vx[:, 0] == pytest.approx(0.0, abs=1e-12)
    # Fig. 2 geometry: p is R sin(Theta) from the tower of interest (x = 900 m)
    theta = math.radians(case.wind.downburst.angle)
    assert fld.point_p == pytest.approx(900.0 + case.wind.downburst.distance * math.sin(theta))
    # Db_x and Db_y: no line point is closer to the centre than r_max, so p carries the peak
    vmax_line = wm.mean_normal_at_nodes(case, LineSystem(case.line), t)
    assert vmax_line.max() <= 40.0 * (1 + 1e-12)


def test_translation_peak_at_p_matches_vref():
    case = make_case({"preset": "Db_y", "translation_speed": 8.0, "translation_direction": 60.0})
    fld = wm.downburst_field(case)
    t = np.linspace(0.0, 600.0, 60001)
    vx, vy = fld.velocity(np.array([fld.point_p]), t)
    speed = np.hypot(vx, vy)[:, 0]
    # V_max found by root finding on the continuous-time maximum (xtol 1e-13 V_ref); the 0.01 s
    # grid resolves the peak of a field varying on the 120 s rise time to ~1e-7 relative.
    assert speed.max() == pytest.approx(40.0, rel=1e-6)
    assert speed.max() <= 40.0 * (1 + 1e-9)
    # Holmes & Oliver (2000) vector sum: at t = 0 (Pi = 0) only the translation velocity remains
    assert (vx[0, 0], vy[0, 0]) == pytest.approx((8.0 * 0.5, 8.0 * math.sin(math.radians(60.0))), abs=1e-12)


def test_theta_zero_field_is_symmetric_about_the_tower_of_interest():
    case = make_case(DB_Y)
    system = LineSystem(case.line)
    t = np.linspace(0.0, 600.0, 121)
    vx, vy = wm.downburst_field(case).velocity(system.node_x0, t)
    k = system.tower_nodes[3]  # tower of interest (node 30)
    left, right = slice(k, None, -1), slice(k, None)
    np.testing.assert_allclose(vy[:, left], vy[:, right], rtol=1e-13, atol=1e-12)
    np.testing.assert_allclose(vx[:, left], -vx[:, right], rtol=1e-13, atol=1e-12)
    assert np.all(vy >= 0.0)  # outflow toward +y everywhere at Theta = 0
    # MeanWind contract: span-local nodes, (n_t, n_spans, ne+1), equal to the global nodes
    mw = wm.mean_wind(case, system, t)
    assert mw.normal.shape == (121, 6, 11) and mw.longitudinal.shape == (121, 6, 11)
    np.testing.assert_array_equal(mw.normal[:, 2, :], vy[:, 20:31])
    np.testing.assert_array_equal(mw.longitudinal[:, 3, :], vx[:, 30:41])


def test_event_window_defaults():
    assert wm.event_window(make_case(DB_X)) == (0.0, wm.T_F_DEFAULT)
    assert wm.event_window(make_case({**DB_X, "t1": 60.0, "t_f": 300.0})) == (0.0, 300.0)
    assert wm.event_window(make_case(DB_X, analysis={"duration": 450.0})) == (0.0, 450.0)
    assert wm.event_window(make_case()) == (0.0, wm.SYNOPTIC_DURATION_DEFAULT)
    case = make_case(DB_X)
    mw = wm.mean_wind(case, LineSystem(case.line))  # default: analysis.mean_states instants over the window
    assert mw.time.size == 250 and mw.time[0] == 0.0 and mw.time[-1] == 600.0


def test_impossible_downburst_geometry_is_a_case_error():
    with pytest.raises(CaseError, match="centre lies on the line"):
        wm.downburst_field(make_case({"jet_diameter": 600.0, "distance": 720.0, "angle": 90.0}))
    with pytest.raises(CaseError, match="translation_speed"):
        wm.downburst_field(make_case({**DB_Y, "translation_speed": 45.0}))


def test_synoptic_node_speeds_average_shared_towers():
    case = make_case(wind={"span_speeds": [10.0, 20.0, 30.0, 30.0, 20.0, 10.0]})
    system = LineSystem(case.line)
    v = tb.mean_normal_at_nodes(case, system, np.arange(3) * 0.1)
    assert v.shape == (3, 61)
    assert v[0, 0] == 10.0 and v[0, 5] == 10.0 and v[0, 10] == 15.0 and v[0, 30] == 30.0 and v[0, 60] == 10.0
    assert v[0, 20] == 25.0 and v[0, 15] == 20.0


# --------------------------------------------------------------------------- user field tables
def test_csv_table_reproduces_the_analytic_field(tmp_path):
    """Fed its own table (grid through the node radii, the conductor height and the
    requested instants), the interpolated field equals the analytic one to round-off."""
    analytic = make_case(DB_Y)
    system = LineSystem(analytic.line)
    dj, h = 600.0, 43.0
    c = wm.downburst_field(analytic).centre
    r = np.unique(np.hypot(system.node_x0 - c[0], c[1]) / dj)
    r = np.concatenate([[0.0], r, [r[-1] + 0.5]])
    z = np.array([0.5 * h / dj, h / dj, 2 * h / dj])
    t = np.linspace(0.0, 600.0, 61)
    vert = 0.1 * analytic_table(r, z, t)
    path = write_table_csv(tmp_path / "own.csv", r, z, t, analytic_table(r, z, t), vertical=vert)
    user = make_case({**DB_Y, "field": "own.csv"}, base_dir=tmp_path)
    a = wm.mean_wind(analytic, system, t)
    u = wm.mean_wind(user, system, t)
    np.testing.assert_allclose(u.normal, a.normal, rtol=1e-12, atol=1e-12)
    np.testing.assert_allclose(u.longitudinal, a.longitudinal, rtol=1e-12, atol=1e-12)
    assert wm.downburst_field(user).v_max == pytest.approx(wm.downburst_field(analytic).v_max, rel=1e-13)
    assert wm.event_window(user) == (0.0, 600.0)
    # the optional vertical column is read and scaled like the radial one
    w = wm.downburst_field(user).vertical_velocity(system.node_x0, t)
    vx, vy = wm.downburst_field(analytic).velocity(system.node_x0, t)
    np.testing.assert_allclose(w, 0.1 * np.hypot(vx, vy), rtol=1e-12, atol=1e-12)
    # the same table as NPZ gives the same field
    np.savez(tmp_path / "own.npz", r_over_dj=r, z_over_dj=z, t=t, v_radial=analytic_table(r, z, t))
    npz = make_case({**DB_Y, "field": "own.npz"}, base_dir=tmp_path)
    np.testing.assert_allclose(wm.mean_wind(npz, system, t).normal, a.normal, rtol=1e-12, atol=1e-12)
    assert path.exists()


def test_shipped_example_field_is_close_to_the_analytic_model():
    case = load_case(CASES / "examples" / "downburst-user-field.toml")
    db = replace(case.wind.downburst, field=None, field_path=None)
    analytic = replace(case, wind=replace(case.wind, downburst=db))
    system = LineSystem(case.line)
    t = np.linspace(0.0, 600.0, 601)
    diff = wm.mean_normal_at_nodes(case, system, t) - wm.mean_normal_at_nodes(analytic, system, t)
    # the example tabulates the analytic model on a coarse grid (dr = 0.2 D_j, dt = 30 s);
    # linear interpolation of the Pi(t) kink at T1 and of f_r costs at most ~3.2 % of V_ref
    assert np.abs(diff).max() < 0.04 * 40.0
    vx, vy = wm.mean_velocity_at(case, [900.0], t)
    assert np.hypot(vx, vy).max() == pytest.approx(40.0, rel=1e-12)


BAD_FILES = [
    ("bad-column.csv", "r_over_dj,z,t,v_radial\n0,0,0,1\n", r'bad-column.csv:1: header column 2 "z" is not allowed'),
    ("no-v.csv", "r_over_dj,z_over_dj,t\n0,0,0\n", 'no column "v_radial"'),
    ("text.csv", "r_over_dj,z_over_dj,t,v_radial\n0,0,0,fast\n", r'text.csv:2: column "v_radial": value "fast" is not a number'),
    ("nan.csv", "r_over_dj,z_over_dj,t,v_radial\n0,0,0,nan\n", "expected a finite number"),
    ("short.csv", "r_over_dj,z_over_dj,t,v_radial\n0,0,0\n", r"short.csv:2: row has 3 values: expected 4"),
    ("neg.csv", "r_over_dj,z_over_dj,t,v_radial\n-1,0,0,1\n", "expected r_over_dj >= 0"),
    ("hole.csv", "r_over_dj,z_over_dj,t,v_radial\n0,0,0,1\n1,0,0,1\n0,0,1,1\n", r"\(1, 0, 1\) is missing"),
    ("dup.csv", "r_over_dj,z_over_dj,t,v_radial\n0,0,0,1\n1,0,0,1\n0,0,1,1\n1,0,1,1\n0,0,0,2\n",
     r"dup.csv:6: row repeats the grid point .* of line 2"),
    ("one-r.csv", "r_over_dj,z_over_dj,t,v_radial\n0,0,0,1\n0,0,1,1\n", "column r_over_dj has 1 distinct value"),
    ("empty.csv", "# nothing\n", "no header line"),
    ("field.txt", "r_over_dj,z_over_dj,t,v_radial\n", r'file type ".txt" is not allowed: expected a .csv or .npz'),
]


@pytest.mark.parametrize(("name", "text", "expect"), BAD_FILES, ids=[b[0] for b in BAD_FILES])
def test_bad_field_files_give_one_line_errors(tmp_path, name, text, expect):
    (tmp_path / name).write_text(text)
    case = make_case({**DB_Y, "field": name}, base_dir=tmp_path)
    with pytest.raises(CaseError, match=expect) as err:
        wm.mean_wind(case, LineSystem(case.line))
    msg = str(err.value)
    assert "\n" not in msg and name in msg


def test_bad_npz_and_coverage_errors(tmp_path):
    np.savez(tmp_path / "shape.npz", r_over_dj=np.arange(3.0), z_over_dj=np.array([0.07]), t=np.arange(4.0),
             v_radial=np.ones((3, 4)))
    with pytest.raises(CaseError, match=r'shape.npz: array "v_radial" has shape \(3, 4\): expected .* \(3, 1, 4\)'):
        wm.event_window(make_case({**DB_Y, "field": "shape.npz"}, base_dir=tmp_path))
    np.savez(tmp_path / "order.npz", r_over_dj=np.array([0.0, 2.0, 1.0]), z_over_dj=np.array([0.07]),
             t=np.arange(4.0), v_radial=np.ones((3, 1, 4)))
    with pytest.raises(CaseError, match='array "r_over_dj" entry 2 .* expected strictly increasing'):
        wm.event_window(make_case({**DB_Y, "field": "order.npz"}, base_dir=tmp_path))
    # a table that does not reach the far end of the line
    r, z, t = np.linspace(0.0, 1.5, 4), np.array([0.05, 0.1]), np.linspace(0.0, 600.0, 5)
    write_table_csv(tmp_path / "near.csv", r, z, t, analytic_table(r, z, t))
    case = make_case({**DB_Y, "field": "near.csv"}, base_dir=tmp_path)
    with pytest.raises(CaseError, match=r"near.csv: the line reaches r/D_j from 1.2 to 1.921 but the table covers r_over_dj 0 to 1.5"):
        wm.mean_wind(case, LineSystem(case.line))
    with pytest.raises(CaseError, match="analysis.duration.*expected duration <= 600"):
        wm.event_window(make_case({**DB_Y, "field": "near.csv"}, analysis={"duration": 900.0}, base_dir=tmp_path))
    with pytest.raises(CaseError, match="remove t1 and t_f"):
        wm.event_window(make_case({**DB_Y, "field": "near.csv", "t1": 60.0}, base_dir=tmp_path))


# --------------------------------------------------------------------------- turbulence: determinism
def test_kms_and_general_cholesky_give_the_same_field():
    x = np.arange(21) * 30.0
    grid = tb.spectral_grid(2000, 0.05, 173.3, 40.0)
    phases = tb.random_phases(11, 0, x.size, grid.n_freq)
    kms = tb.synthesize(x, grid, phases, 10.0, 40.0, method="kms")
    gen = tb.synthesize(x, grid, phases, 10.0, 40.0, method="general")
    # same lower-triangular factor (Cholesky is unique), different arithmetic: round-off only
    np.testing.assert_allclose(kms, gen, rtol=0, atol=1e-12)
    # the closed-form factor is the Cholesky factor of rho^|j-k|: apply it to the unit vectors
    rho = 0.83
    c = rho ** np.abs(np.subtract.outer(np.arange(6), np.arange(6)))
    cols = np.stack([tb.kms_apply(np.full(1, rho), np.eye(6)[:, [m]])[:, 0] for m in range(6)], axis=1)
    np.testing.assert_allclose(cols, np.linalg.cholesky(c), rtol=0, atol=1e-15)


def test_general_path_handles_uneven_spacing_and_singular_coherence():
    x = np.array([0.0, 10.0, 35.0, 35.0, 90.0])  # two coincident nodes: singular coherence matrix
    grid = tb.spectral_grid(400, 0.1, 173.3, 40.0)
    phases = tb.random_phases(3, 0, x.size, grid.n_freq)
    u = tb.synthesize(x, grid, phases, 10.0, 40.0, method="general")
    # coincident nodes: the Cholesky pivot of the repeated row is round-off (~1e-16), so the
    # second signal differs from the first by at most ~sqrt(1e-16) = 1e-8 of its amplitude
    np.testing.assert_allclose(u[:, 2], u[:, 3], rtol=0, atol=1e-6)
    # at f -> 0 the coherence matrix is all ones (rank 1): Cholesky fails, the eigen fallback works
    y = tb.general_apply(x, np.array([1e-20]), np.exp(1j * phases[:, :1]), 10.0, 40.0)
    np.testing.assert_allclose(y[:, 0], np.full(5, y[0, 0]), atol=1e-12)  # fully coherent
    assert abs(y[0, 0]) > 0
    # the factor used reproduces the Davenport coherence matrix: L L^T = C
    f = grid.freq[:1]
    lower = np.stack([tb.general_apply(x, f, np.eye(5)[:, [m]].astype(complex), 10.0, 40.0)[:, 0]
                      for m in range(5)], axis=1).real
    c = tb.davenport_coherence(f[0], np.subtract.outer(x, x), 10.0, 40.0)
    np.testing.assert_allclose(lower @ lower.T, c, atol=1e-12)


def test_realization_is_bit_identical_alone_in_a_batch_and_in_another_process():
    case = load_case(CASES / "paper" / "case09-six.toml")
    system = LineSystem(case.line)
    t = np.arange(2000) * 0.05
    alone = tb.fluctuating_velocity(case, system, t, [3])[0]
    batch = tb.fluctuating_velocity(case, system, t, [7, 3, 0])
    assert np.array_equal(alone, batch[1])
    # the stationary unit field does not depend on the time origin (e.g. a burn-in before t = 0)
    assert np.array_equal(tb.fluctuating_velocity(case, system, t - 12.35, [3])[0], alone)
    # SeedSequence(seed).spawn(r + 1)[r] is the documented stream
    ref = np.random.default_rng(np.random.SeedSequence(case.analysis.seed).spawn(4)[3]).random(5)
    assert np.array_equal(tb.realization_rng(case.analysis.seed, 3).random(5), ref)
    code = (
        "import hashlib, numpy as np\n"
        "from linecheck.core.case import load_case\n"
        "from linecheck.core.system import LineSystem\n"
        "from linecheck.core.wind.turbulence import fluctuating_velocity\n"
        f"c = load_case({str(CASES / 'paper' / 'case09-six.toml')!r})\n"
        "u = fluctuating_velocity(c, LineSystem(c.line), np.arange(2000) * 0.05, [3])[0]\n"
        "print(hashlib.sha256(np.ascontiguousarray(u).tobytes()).hexdigest())\n"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == hashlib.sha256(np.ascontiguousarray(alone).tobytes()).hexdigest()


def test_downburst_fluctuation_is_the_unit_field_times_i_vm():
    case = load_case(CASES / "paper" / "case01-six.toml")
    system = LineSystem(case.line)
    t = np.arange(2400) * 0.25
    u = tb.fluctuating_velocity(case, system, t, [2])[0]
    unit = tb.unit_field(case, system, t.size, 0.25, 2)
    a = 0.12 * wm.mean_speed_at_nodes(case, system, t)
    np.testing.assert_allclose(u, a * unit, rtol=1e-15, atol=0)
    assert u.shape == (2400, 61) and np.all(u[0] == 0.0)  # Pi(0) = 0: no turbulence before the event


# --------------------------------------------------------------------------- turbulence: statistics
@pytest.fixture(scope="module", params=["record", "fast"])
def ensemble(request):
    """30 realizations of the synoptic six-span field (paper case 9: L_u = 52/0.3 m, V = 40 m/s),
    2400 s at 0.2 s (Nyquist 2.5 Hz > 2 Hz), as one-sided FFT coefficients per node.

    ``fast``: ``fft_length = "fast"`` on a record of 12,001 samples (= 11 x 1091): the synthesis
    transform has 12,150 points and the record is its first 12,001 samples, so the periodogram's
    frequencies are not the synthesis bins (rectangular-window leakage; the von Karman spectrum
    falls as f^-5/3, slower than the window's 1/f^2 side lobes, so the smoothing it adds stays
    inside the tolerances below, which were set for the record-length synthesis)."""
    case = load_case(CASES / "paper" / "case09-six.toml")
    system = LineSystem(case.line)
    n, dt = 12000, 0.2
    if request.param == "fast":
        case = replace(case, wind=replace(case.wind, fft_length="fast"))
        n = 12001
        assert tb.spectral_grid(n, dt, tb.length_scale(case), case.wind.v_ref, True).n_fft == 12150
    coeffs = []
    for r in range(30):
        u = tb.unit_field(case, system, n, dt, r)
        coeffs.append(np.fft.rfft(u, axis=0)[1:])
    f = np.arange(1, coeffs[0].shape[0] + 1) / (n * dt)
    return case, np.stack(coeffs), f, n, dt


def test_ensemble_psd_within_15_percent_in_every_octave_band(ensemble):
    case, X, f, n, dt = ensemble
    L, V = tb.length_scale(case), case.wind.v_ref
    psd = (2.0 * dt / n) * np.abs(X) ** 2  # one-sided periodogram [1/Hz], (n_real, n_freq, n_nodes)
    edges = [0.005 * 2**k for k in range(9)] + [2.0]
    for lo, hi in zip(edges[:-1], edges[1:]):
        m = (f >= lo) & (f < hi)
        est = psd[:, m, :].mean()
        target = tb.von_karman_psd(f[m], L, V).mean()
        # Tolerance 15 %.  Expected error: a deterministic +3.6 % (bins rescaled for the
        # 3.5 % of variance above 2.5 Hz) plus sampling error 1/sqrt(n_bins n_real n_indep); the
        # lowest band has 12 bins x 30 records and ~3.4 independent node groups (line 1800 m over
        # coherence length V/(C f) = 530 m), so 1/sqrt(1224) = 2.9 %: 15 % is > 3.9 sigma from the
        # bias; every higher band has at least twice as many bins.
        assert est / target == pytest.approx(1.0, abs=0.15), f"band {lo:g}-{hi:g} Hz: ratio {est / target:.3f}"


@pytest.mark.parametrize("sep", [1, 2, 4])
def test_co_coherence_within_0_05_at_three_separations(ensemble, sep):
    case, X, f, _n, _dt = ensemble
    L, V, C = tb.length_scale(case), case.wind.v_ref, case.wind.coherence_decay
    dx = 30.0 * sep
    fc = math.log(2.0) * V / (C * dx)  # target coherence 0.5 here (most sensitive region)
    m = (f >= 0.8 * fc) & (f <= 1.25 * fc)
    a, b = X[:, m, :-sep], X[:, m, sep:]  # all node pairs at this separation
    co = np.real(a * np.conj(b)).sum() / math.sqrt((np.abs(a) ** 2).sum() * (np.abs(b) ** 2).sum())
    w = tb.von_karman_psd(f[m], L, V)
    target = (w * tb.davenport_coherence(f[m], dx, C, V)).sum() / w.sum()
    # Tolerance 0.05.  Co-coherence estimator std ~ (1 - gamma^2)/sqrt(2 n_d) with
    # n_d = n_real x n_bins x independent pairs >= 30 x 25 x 10 = 7500 (sep 120 m, the smallest
    # band): 0.75/122 = 0.006, so 0.05 is ~8 sigma.
    assert co == pytest.approx(target, abs=0.05)


@pytest.mark.parametrize("fft_length", ["record", "fast"])
def test_fluctuation_std_within_3_percent_of_i_v(fft_length):
    case = load_case(CASES / "paper" / "case09-six.toml")  # synoptic, V = 40 m/s, I = 0.12
    case = replace(case, wind=replace(case.wind, fft_length=fft_length))
    system = LineSystem(case.line)
    t = np.arange(12001) * 0.05  # the paper's 600 s record at 0.05 s (fast: a 12,150-point transform)
    u = tb.fluctuating_velocity(case, system, t, range(10))
    # Tolerance 3 %.  The per-record std scatters by 2.0 % (60-record study; the energy
    # sits in ~20 bins near the von Karman peak, 0.03 Hz); pooled over the paper's 10 records that
    # is 0.6 %, so 3 % is 5 sigma.  The process variance is exactly 1 by construction.
    assert u.std() == pytest.approx(0.12 * 40.0, rel=0.03)
    assert np.abs(u.mean()) < 0.02 * 0.12 * 40.0  # zero mean: no DC term in any record


@pytest.mark.slow
def test_downburst_scale_spectrum_and_coherence_long_ensemble():
    """Longer ensemble at the downburst length scale (L_u = D_j = 600 m, V = 20 m/s): 10 % of the
    variance sits below 1/(2T) for T = 600 s and is carried by the first bin, so use T = 4800 s."""
    case = load_case(CASES / "paper" / "case06-six.toml")  # Db_y, L = 300 m, V = 20 m/s
    system = LineSystem(case.line)
    L, V, C = tb.length_scale(case), case.wind.v_ref, case.wind.coherence_decay
    n, dt = 24000, 0.2
    X = np.stack([np.fft.rfft(tb.unit_field(case, system, n, dt, r), axis=0)[1:] for r in range(40)])
    f = np.arange(1, X.shape[1] + 1) / (n * dt)
    psd = (2.0 * dt / n) * np.abs(X) ** 2
    edges = [0.005 * 2**k for k in range(9)] + [2.0]
    for lo, hi in zip(edges[:-1], edges[1:]):
        m = (f >= lo) & (f < hi)
        # lowest band: 24 bins x 40 records x ~1.4 node groups -> 2.7 % sampling error; bias < 1 %
        assert psd[:, m, :].mean() / tb.von_karman_psd(f[m], L, V).mean() == pytest.approx(1.0, abs=0.15)
    for sep in (1, 3, 6):
        dx = 30.0 * sep
        fc = math.log(2.0) * V / (C * dx)
        m = (f >= 0.8 * fc) & (f <= 1.25 * fc)
        a, b = X[:, m, :-sep], X[:, m, sep:]
        co = np.real(a * np.conj(b)).sum() / math.sqrt((np.abs(a) ** 2).sum() * (np.abs(b) ** 2).sum())
        w = tb.von_karman_psd(f[m], L, V)
        assert co == pytest.approx((w * tb.davenport_coherence(f[m], dx, C, V)).sum() / w.sum(), abs=0.05)


def test_fast_fft_length_is_a_different_reproducible_draw_of_the_same_process():
    """``fft_length = "fast"``: the transform is the next 5-smooth length (12,001 ->
    12,150 points), the record keeps its 12,001 samples, the field is reproducible bit for bit
    and is not the record-length field (other frequencies, other phases; the per-process memo
    keeps the two apart)."""
    case = load_case(CASES / "paper" / "case09-six.toml")
    fast = replace(case, wind=replace(case.wind, fft_length="fast"))
    system = LineSystem(case.line)
    grid = tb.spectral_grid(12001, 0.05, tb.length_scale(case), case.wind.v_ref, True)
    assert (grid.n_steps, grid.n_fft) == (12001, 12150) and grid.df == pytest.approx(1.0 / (12150 * 0.05))
    assert tb.spectral_grid(12001, 0.05, tb.length_scale(case), case.wind.v_ref).n_fft == 12001
    a = tb.unit_field(fast, system, 12001, 0.05, 3)
    b = tb.unit_field(fast, system, 12001, 0.05, 3)
    assert a.shape == (12001, system.n_nodes) and np.array_equal(a, b)
    t = np.arange(12001) * 0.05
    rec = tb.fluctuating_velocity(case, system, t, [3])[0]
    fst = tb.fluctuating_velocity(fast, system, t, [3])[0]
    assert np.array_equal(fst, 0.12 * 40.0 * a)  # synoptic: a = I V_ref
    assert not np.allclose(rec, fst)


def test_fast_fft_length_on_a_section_markov_path():
    """A section's unit field (the Markov coherence path) with ``fft_length = "fast"``: the
    record's samples at every node, unit variance over five records (tolerance 5 %: one record's
    std scatters by ≈ 2 % — 0.976 to 1.039 over these five, 0.978 to 1.010 with the record
    length — so the pooled five by ≈ 1 %), not the record-length field."""
    case = load_case(CASES / "examples" / "section-12span.toml")
    fast = replace(case, wind=replace(case.wind, fft_length="fast"))
    system = LineSystem(case.line)
    n = 12001
    u = np.stack([tb.unit_field(fast, system, n, 0.05, r) for r in range(5)])
    assert u.shape == (5, n, system.n_nodes) and np.all(np.isfinite(u))
    assert u.std() == pytest.approx(1.0, rel=0.05)
    assert not np.allclose(u[0], tb.unit_field(case, system, n, 0.05, 0))
