"""Line sections against an independent reference.

Part A validates the reference itself (it runs whatever linecheck can do):
``tests/reference/irvine_inclined.py`` (Irvine 1981 inclined elastic catenary, closed form) against
the level catenary and an ODE integration; ``tests/reference/section_fe.py`` (a self-contained
non-linear 3-D truss FE reading the raw TOML/CSV, no linecheck import) against Irvine, against the
older equal-span FE reference, and for the qualitative section behaviour.

Part B is the acceptance check for sections: linecheck's public outputs (``linecheck static/modes CASE
--json``) against the FE reference on the cases in ``tests/data/sections/``.  Those tests skip
with the reason while linecheck cannot load a towers-form case.
"""

from __future__ import annotations

import json
import math
import re
import shutil
import tomllib
from functools import cache
from pathlib import Path

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from ..reference import irvine_inclined as ii
from ..reference import section_fe as fe

DATA = Path(__file__).resolve().parents[1] / "data" / "sections"
W, EA, H0 = 17.92, 0.7e-4 * 5.2e10, 20000.0  # conductor of the section cases [N/m, N, N]
N_EL = 100  # reference elements per span: discretisation error ~3e-5 of the reactions (test below)


@cache
def _ref(stem: str, n_el: int = N_EL) -> fe.Solution:
    """FE reference solution of tests/data/sections/<stem>.toml (cached per session)."""
    return fe.solve(DATA / f"{stem}.toml", n_el=n_el)


def _drag_direction(path: Path) -> str:
    """The case's ``[analysis] drag_direction`` as linecheck reads it (default "cross-flow"): the
    reference loads the same way (cross-flow: the follower drag on its deformed elements)."""
    return tomllib.loads(path.read_text(encoding="utf-8")).get("analysis", {}).get("drag_direction", "cross-flow")


def _ref_as_linecheck(path: Path, n_el: int = N_EL) -> fe.Solution:
    """FE reference of the case at ``path`` with linecheck's drag model for it."""
    return fe.solve(path, n_el=n_el, drag_direction=_drag_direction(path))


# =============================================================================== A. the reference
# ------------------------------------------------------------------ Irvine inclined catenary
@pytest.mark.parametrize("L", [250.0, 400.0, 600.0])
def test_inclined_catenary_level_limit_is_the_level_elastic_catenary(L):
    """h = 0: V_A = V_B = W L_u / 2, and H, sag agree with the level closed form (Irvine 1981
    Eqs 2.3-2.6 in linecheck.reference, written separately) to round-off."""
    from linecheck.reference import catenary_midspan_sag, catenary_tension

    c = ii.from_tension(L, 0.0, W, EA, H0)
    assert c.VA == pytest.approx(0.5 * W * c.Lu, rel=1e-12)
    assert c.VB == pytest.approx(0.5 * W * c.Lu, rel=1e-12)
    assert catenary_tension(L, c.Lu, W, EA) == pytest.approx(H0, rel=1e-10)
    _, zmid = c.shape(0.5 * c.Lu)
    assert -float(zmid) == pytest.approx(catenary_midspan_sag(L, c.Lu, W, EA), rel=1e-10)


@pytest.mark.parametrize(("L", "h", "H"), [(400.0, 40.0, 20000.0), (300.0, -60.0, 12000.0),
                                           (300.0, 250.0, 5000.0), (450.0, 10.0, 40000.0)])
def test_inclined_catenary_identities(L, h, H):
    """End conditions, vertical equilibrium, mirror symmetry, the inverse (L_u -> H) and an
    independent numerical integration of the cable equations (dp/ds = 1 + T/EA) all hold."""
    c = ii.from_tension(L, h, W, EA, H)
    x, z = c.shape(np.array([0.0, c.Lu]))
    assert abs(x[0]) < 1e-12 and abs(z[0]) < 1e-12
    assert abs(x[1] - L) <= 1e-10 * L and abs(z[1] - h) <= 1e-10 * L
    assert c.VA + c.VB == pytest.approx(W * c.Lu, rel=1e-13)
    m = ii.from_tension(L, -h, W, EA, H)  # mirror: the same cable seen from B
    assert m.Lu == pytest.approx(c.Lu, rel=1e-12)
    assert (m.VA, m.VB) == pytest.approx((c.VB, c.VA), rel=1e-9, abs=1e-9 * W * c.Lu)
    assert ii.from_length(L, h, W, EA, c.Lu).H == pytest.approx(H, rel=1e-10)

    def rhs(s, y):  # (dx/ds, dz/ds) = (1 + T/EA) (H, Q)/T, Q = Q0 + W s (Irvine 1981 Eq. 2.1-2.2)
        Q = c.Q0 + W * s
        T = math.hypot(H, Q)
        return [(1.0 + T / EA) * H / T, (1.0 + T / EA) * Q / T]

    sol = solve_ivp(rhs, (0.0, c.Lu), [0.0, 0.0], rtol=1e-12, atol=1e-12, dense_output=True)
    s = np.linspace(0.0, c.Lu, 7)
    xs, zs = c.shape(s)
    np.testing.assert_allclose(sol.sol(s)[0], xs, atol=1e-7 * L)
    np.testing.assert_allclose(sol.sol(s)[1], zs, atol=1e-7 * L)


# ------------------------------------------------------------------ FE reference
def _single_span(n_el: int, L=400.0, h=40.0):
    T = fe.Tower
    sec = fe.Section(W=W, D=0.022, EA=EA, Cd=1.0, H0=H0, v_default=4.0,
                     towers=(T("A", 0.0, 0.0, 43.0, "strain", 0.0, None), T("B", L, h, 43.0, "strain", 0.0, None)))
    return fe.solve(sec, n_el=n_el).still


def test_fe_single_inclined_span_converges_to_irvine():
    """L = 400 m, h = 40 m, H0 = 20 kN: the FE chain's reactions at both ends converge to the
    inclined elastic catenary's (H, 0, V_A), (-H, 0, V_B) as O(1/n^2) and are within 0.05 %
    at the reference mesh (measured: 5.1e-4, 1.28e-4, 3.2e-5, 8.0e-6 of the largest
    component for n = 25, 50, 100, 200)."""
    c = ii.from_tension(400.0, 40.0, W, EA, H0)
    exact = np.array([[c.H, 0.0, c.VA], [-c.H, 0.0, c.VB]])
    errs = []
    for n in (25, 50, 100, 200):
        R = _single_span(n).reactions
        errs.append(float(np.max(np.abs(R - exact) / np.abs(exact).max(axis=1, keepdims=True))))
    assert errs[2] <= 5e-4, errs
    ratios = [errs[k] / errs[k + 1] for k in range(3)]
    assert all(3.6 < r < 4.4 for r in ratios), (errs, ratios)  # second order: ratio 4 per halving


@pytest.mark.parametrize("stem", ["unequal-still", "inclined-still"])
def test_straight_section_still_air_does_not_move(stem):
    """A straight section clipped in at H0 is already in equilibrium under weight: the clamps
    stay put, every span keeps H0 and each suspension tower carries the two adjacent Irvine
    half-spans (V_B of the left span + V_A of the right), all to the mesh's O(1/n^2) ~3e-5."""
    sol = _ref(stem)
    st = sol.still
    assert np.max(np.abs(st.clamp_displacement)) < 2e-4  # [m] (measured 1.9e-5: mesh error + penalty stretch)
    np.testing.assert_allclose(st.tension, H0, rtol=1e-4)
    cats = sol.geometry.catenary
    for j in range(1, len(cats)):
        expect = cats[j - 1].VB + cats[j].VA
        assert st.reactions[j, 2] == pytest.approx(expect, rel=1e-4)
        assert abs(st.reactions[j, 0]) < 1e-4 * expect and abs(st.reactions[j, 1]) < 1e-4 * expect
    assert st.reactions[0, 2] == pytest.approx(cats[0].VA, rel=1e-4)
    assert st.reactions[-1, 2] == pytest.approx(cats[-1].VB, rel=1e-4)
    assert st.insulator_length_error < 1e-4  # [m] the penalty link is rigid enough


def test_angle_tower_insulators_swing_inside_and_tensions_relax():
    """angles-still: at the +15 deg tower (line turning left) the clamp swings to +y' (the inside),
    at the -25 deg tower to -y'; the straight suspension tower barely moves; the spans next to
    the angle towers lose tension; each insulator is a two-force member (its top reaction points
    along it)."""
    sol = _ref("angles-still")
    st, geo = sol.still, sol.geometry
    d = fe.to_tower_frame(st.clamp_displacement, geo.psi)
    assert d[1, 1] > 1.0 and d[4, 1] < -1.0, d  # [m] swings of 2.2 m and 3.8 m measured
    assert abs(d[1, 0]) < 0.1 * d[1, 1] and abs(d[4, 0]) < 0.1 * abs(d[4, 1])
    assert np.hypot(*d[2, :2]) < 0.1 * abs(d[1, 1])
    assert st.reactions_tower[1, 1] > 0 and st.reactions_tower[4, 1] < 0  # pulled inward
    assert np.all(st.tension < H0) and st.tension[3] < st.tension[2]  # relaxed, most near -25 deg
    for j in (1, 2, 4):
        link = geo.clamp[j] + st.clamp_displacement[j] - geo.top[j]
        F = st.reactions[j] * np.array([1.0, 1.0, -1.0])  # back to z up
        assert np.linalg.norm(np.cross(F / np.linalg.norm(F), link / np.linalg.norm(link))) < 1e-9


def test_fe_matches_equal_span_reference_under_uniform_wind():
    """Three equal level spans, wind normal to the line (d = 0, uniform profile): the section FE
    and the older equal-span FE (tests/reference/fe_static.py, written separately) solve the
    same discrete problem when H0 is chosen to give the same unstretched length, so they agree
    to solver round-off (measured 5e-11)."""
    from linecheck.core.system import LineSystem
    from linecheck.validation import paper_line

    from ..reference.fe_static import solve_fe

    system = LineSystem(paper_line(300.0, spans=3))
    Lu = system.unstretched_length
    h0 = ii.from_length(300.0, 0.0, W, EA, Lu).H
    V = 30.0
    g = 0.5 * 1.25 * 1.0 * 0.022 * V**2
    old = solve_fe(system, np.full((3, system.ne + 1), g), n_el=N_EL)
    T = fe.Tower
    sec = fe.Section(W=W, D=0.022, EA=EA, Cd=1.0, H0=h0, v_default=4.0, v_ref=V,
                     towers=tuple(T(f"T{j}", 300.0 * j, 0.0, 43.0, "suspension" if 0 < j < 3 else "strain", 0.0, None)
                                  for j in range(4)))
    new = fe.solve(sec, n_el=N_EL).wind
    scale = np.abs(old.reactions).max(axis=1, keepdims=True)
    np.testing.assert_array_less(np.abs(new.reactions - old.reactions) / scale, 1e-8)
    np.testing.assert_allclose(new.clamp_displacement, old.displacement, atol=1e-8)


@pytest.mark.parametrize("d", [0.0, 20.0, -50.0])
def test_fe_level_span_oblique_wind_is_the_tilted_level_catenary(d):
    """One level span, uniform wind at direction d: the drag 1/2 rho C_d D (V cos d)^2 along +y is
    uniform, so the cable is the level elastic catenary under w = sqrt(W^2 + g^2) in a tilted plane
    (tests/reference/irvine.py): reactions (H, g L_u/2, W L_u/2) within the mesh error."""
    from ..reference import irvine

    T = fe.Tower
    V = 35.0
    sec = fe.Section(W=W, D=0.022, EA=EA, Cd=1.0, H0=H0, v_default=4.0, v_ref=V, direction=d,
                     towers=(T("A", 0.0, 0.0, 43.0, "strain", 0.0, None), T("B", 350.0, 0.0, 43.0, "strain", 0.0, None)))
    sol = fe.solve(sec, n_el=N_EL)
    g = 0.5 * 1.25 * 1.0 * 0.022 * (V * math.cos(math.radians(d))) ** 2
    Rx, Ry, Rz = irvine.reactions(350.0, sol.unstretched_length[0], W, g, EA)
    exact = np.array([[Rx, Ry, Rz], [-Rx, Ry, Rz]])
    err = np.abs(sol.wind.reactions - exact) / np.abs(exact).max(axis=1, keepdims=True)
    assert err.max() < 1e-4, (sol.wind.reactions, exact)


def test_reference_mesh_is_converged_for_the_sections():
    """The comparison mesh (100 elements per span) against 200: reactions differ by < 1e-4 of the
    largest component at each tower (O(1/n^2): measured ~2e-5), far below the 0.5 % tolerance."""
    for stem in ("angles-wind", "inclined-wind"):
        a, b = _ref(stem).wind, _ref(stem, 2 * N_EL).wind
        for Ra, Rb in ((a.reactions, b.reactions), (a.reactions_tower, b.reactions_tower)):
            err = np.abs(Ra - Rb) / np.abs(Rb).max(axis=1, keepdims=True)
            assert err.max() < 1e-4, (stem, err.max())


def test_reference_wind_state_statics():
    """Wind states: total vertical reaction = total conductor weight, total horizontal reaction =
    total drag (sum over the elements of the applied nodal loads), per section."""
    for stem in ("unequal-wind", "inclined-wind", "angles-wind"):
        sol = _ref(stem)
        R = sol.wind.reactions
        assert R[:, 2].sum() == pytest.approx(W * sol.unstretched_length.sum(), rel=1e-9)
        # the drag is horizontal along each span's normal; wind at 20 deg pushes toward +y overall
        assert R[:, 1].sum() > 0


def test_still_air_modes_of_refined_mesh_converge():
    """Lowest 4 in-plane and out-of-plane still-air frequencies of the inclined span: the mesh of
    200 elements is within 5e-4 of the Richardson-extrapolated 200/400 value (lumped-mass chain
    error ~ (k pi / 2n)^2 / 6 = 1.6e-4 for k = 4, n = 200; measured 1.7e-4), and the lowest
    out-of-plane one is the taut string's (1/(2 l)) sqrt(T/m) with the mean tension within 0.5 %."""
    f = DATA / "inclined-span-modes.toml"
    ip, op = fe.refined_frequencies(f, n_el=200)
    m = fe.still_air_modes(f, n_el=200, n_modes=16)
    np.testing.assert_allclose(m.in_plane(4), ip, rtol=5e-4)
    np.testing.assert_allclose(m.out_plane(4), op, rtol=5e-4)
    assert np.all(m.in_plane(4) < ip) and np.all(m.out_plane(4) < op)  # the lumped chain is too soft
    c = ii.from_tension(400.0, 40.0, W, EA, H0)
    s = np.linspace(0.0, c.Lu, 2001)
    T_mean = float(np.mean(c.tension(s)))
    arc = c.Lu * (1.0 + T_mean / EA)
    f1 = math.sqrt(T_mean / (W / fe.GRAVITY)) / (2.0 * arc)
    assert op[0] == pytest.approx(f1, rel=5e-3)


# =============================================================================== B. linecheck
# Marker for the defect this reference found in the first section core (measured with
# tests/reference/section_report.py): a synoptic step-1 mean wind that puts the full v_ref on every
# span's normal, ignoring the wind direction (V_n = V cos(d + h_i)) and the profile
# V(z) = v_ref (z_agl/z_ref)^alpha, was 17-23 % off (39 % on the 12-span example); with direction
# and profile removed from the reference the sections agreed to 0.004 %.  No test carries it now
# that the mean wind has both; strict: an XPASS fails.
WIND_DEFECT = pytest.mark.xfail(strict=True, reason="linecheck's synoptic mean wind ignores wind.direction and "
                                "wind.profile_exponent (docs/validation.md 'Independent section reference')")
STATIC_CASES = ["unequal-still", "unequal-wind", "inclined-still", "inclined-wind", "angles-still", "angles-wind"]
TOL_SECTION = 0.005  # acceptance: 0.5 % of the largest reaction component at that tower
TOL_IRVINE = 0.001  # acceptance: 0.1 %
TOL_MODES = 0.02  # acceptance: 2 %


def _linecheck_json(command: str, stem: str, tmp_path: Path, *extra: str) -> dict:
    """Run ``linecheck <command> CASE --json OUT`` in process; skip if linecheck cannot load a
    towers-form case (a build without section support)."""
    from typer.testing import CliRunner

    from linecheck.cli.app import app
    from linecheck.core.case import load_case
    from linecheck.core.errors import CaseError

    case = DATA / f"{stem}.toml"
    try:
        load_case(case)
    except CaseError as exc:
        pytest.skip(f"linecheck cannot load a towers-form section case: {exc}")
    out = tmp_path / f"{stem}.{command}.json"
    r = CliRunner(env={"COLUMNS": "250"}).invoke(app, [command, str(case), "--json", str(out), *extra])
    assert r.exit_code == 0, r.output
    return json.loads(out.read_text(encoding="utf-8"))


def _lc_reactions(doc: dict) -> tuple[np.ndarray, np.ndarray]:
    """(tower-frame, global) reactions [N] from a static JSON, shape (n_towers, 3) each."""
    missing = [t.get("index") for t in doc["towers"] if not isinstance(t.get("global"), dict)]
    assert not missing, f'static JSON towers {missing} lack the "global" reactions block (docs/method.md, "Line sections")'
    tw = np.array([[t["Rx"], t["Ry"], t["Rz"]] for t in doc["towers"]], dtype=float)
    gl = np.array([[t["global"]["Rx"], t["global"]["Ry"], t["global"]["Rz"]] for t in doc["towers"]], dtype=float)
    return tw, gl


def _table(name: str, lc: np.ndarray, ref: np.ndarray) -> str:
    rows = [f"{name}: tower  component  linecheck [N]  reference [N]  diff/max|R_ref| at tower"]
    for j in range(ref.shape[0]):
        scale = np.abs(ref[j]).max()
        for c, comp in enumerate(("Rx", "Ry", "Rz")):
            rows.append(f"  {j + 1:3d}  {comp}  {lc[j, c]:14.2f}  {ref[j, c]:14.2f}  {(lc[j, c] - ref[j, c]) / scale:+.4%}")
    return "\n".join(rows)


@pytest.mark.parametrize("stem", STATIC_CASES)
def test_static_reactions_match_reference(stem, tmp_path):
    """Every tower, every component, tower frame and global frame: |R_lc - R_ref| <= 0.5 % of the
    largest reaction component at that tower (the acceptance check).  The reference mesh error
    (~3e-5) is negligible against the tolerance."""
    doc = _linecheck_json("static", stem, tmp_path)
    sol = _ref_as_linecheck(DATA / f"{stem}.toml")
    state = sol.wind if sol.wind is not None else sol.still
    tw, gl = _lc_reactions(doc)
    assert tw.shape == state.reactions.shape, f"{tw.shape[0]} towers in the JSON, {state.reactions.shape[0]} in the case"
    for name, lc, ref in (("tower frame", tw, state.reactions_tower), ("global", gl, state.reactions)):
        scale = np.abs(ref).max(axis=1, keepdims=True)
        err = np.abs(lc - ref) / scale
        assert np.all(err <= TOL_SECTION), (f"{stem}: largest difference {err.max():.3%} at tower "
                                            f"{np.unravel_index(err.argmax(), err.shape)[0] + 1}\n" + _table(name, lc, ref))


def test_inclined_single_span_matches_irvine(tmp_path):
    """Still air, L = 400 m, h = 40 m, H0 = 20 kN: both ends' (R_x, R_y, R_z) within 0.1 % of the
    inclined elastic catenary (H, 0, V_A) and (-H, 0, V_B) (R_y: within 0.1 % of the largest)."""
    doc = _linecheck_json("static", "inclined-span", tmp_path)
    c = ii.from_tension(400.0, 40.0, W, EA, H0)
    exact = np.array([[c.H, 0.0, c.VA], [-c.H, 0.0, c.VB]])
    tw, gl = _lc_reactions(doc)
    for name, lc in (("tower frame", tw), ("global", gl)):
        msg = _table(name, lc, exact)
        for j in range(2):
            assert lc[j, 0] == pytest.approx(exact[j, 0], rel=TOL_IRVINE), msg
            assert lc[j, 2] == pytest.approx(exact[j, 2], rel=TOL_IRVINE), msg
            assert abs(lc[j, 1]) <= TOL_IRVINE * np.abs(exact[j]).max(), msg


def test_inclined_span_still_air_frequencies_match_refined_mesh(tmp_path):
    """Lowest 4 in-plane (JSON direction x or z) and 4 out-of-plane (y) still-air frequencies of
    the inclined span within 2 % of the reference's refined mesh (Richardson 200/400 elements).
    The case uses 30 elements per span: a lumped-mass chain of n elements underestimates mode k by
    about (k pi / 2n)^2 / 6, i.e. 6.5 % for k = 4 at n = 10 but 0.7 % at n = 30."""
    doc = _linecheck_json("modes", "inclined-span-modes", tmp_path, "--count", "16")
    f = np.array(doc["still_air"]["frequencies_hz"], dtype=float)
    d = np.array(doc["still_air"]["direction"])
    lc_ip, lc_op = f[d != "y"][:4], f[d == "y"][:4]
    ip, op = fe.refined_frequencies(DATA / "inclined-span-modes.toml", n_el=200)
    msg = f"in-plane lc {lc_ip} ref {ip}; out-of-plane lc {lc_op} ref {op}"
    assert lc_ip.size == 4 and lc_op.size == 4, msg
    np.testing.assert_allclose(lc_ip, ip, rtol=TOL_MODES, err_msg=msg)
    np.testing.assert_allclose(lc_op, op, rtol=TOL_MODES, err_msg=msg)


#: the single-wire section examples: the reference is one wire (a case with [[wires]] is each wire's
#: single-wire case attachment by attachment, tests/analysis/test_wires_static.py)
EXAMPLES = [p for p in sorted((Path(__file__).resolve().parents[2] / "cases" / "examples").glob("section-*.toml"))
            if "wires" not in tomllib.loads(p.read_text(encoding="utf-8"))]


def _variant(src: Path, dst_dir: Path, still: bool) -> Path:
    """Copy a shipped section example (and its towers CSV) with ``drag = "linear"`` (step 1 under
    the mean drag exactly, as the reference) and, for ``still``, v_ref = 0."""
    text = src.read_text(encoding="utf-8")
    data = __import__("tomllib").loads(text)
    csv_name = data["line"].get("towers_file")
    if csv_name:
        shutil.copy(src.parent / csv_name, dst_dir / csv_name)
    text = re.sub(r"(?m)^\s*drag\s*=.*$", "", text)
    if re.search(r"(?m)^\[analysis\]", text):
        text = re.sub(r"(?m)^\[analysis\]\s*$", '[analysis]\ndrag = "linear"', text, count=1)
    else:
        text += '\n[analysis]\ndrag = "linear"\n'
    if still:
        text = re.sub(r"(?m)^v_ref\s*=.*$", "v_ref = 0.0", text)
    dst = dst_dir / f"{src.stem}-{'still' if still else 'wind'}.toml"
    dst.write_text(text, encoding="utf-8")
    return dst


@pytest.mark.parametrize("still", [True, False], ids=["still", "wind"])
@pytest.mark.parametrize("example", EXAMPLES or [None], ids=[p.stem for p in EXAMPLES] or ["none"])
def test_shipped_section_examples_match_reference(example, still, tmp_path):
    """The shipped cases/examples/section-*.toml (real-looking sections with angle towers) under
    the same 0.5 % acceptance, tower frame and global."""
    if example is None:
        pytest.skip("no cases/examples/section-*.toml shipped")
    case = _variant(example, tmp_path, still)
    from linecheck.core.case import load_case
    from linecheck.core.errors import CaseError

    try:
        load_case(case)
    except CaseError as exc:
        pytest.skip(f"linecheck cannot load a towers-form section case: {exc}")
    from typer.testing import CliRunner

    from linecheck.cli.app import app

    out = tmp_path / "static.json"
    r = CliRunner(env={"COLUMNS": "250"}).invoke(app, ["static", str(case), "--json", str(out)])
    assert r.exit_code == 0, r.output
    tw, gl = _lc_reactions(json.loads(out.read_text(encoding="utf-8")))
    sol = _ref_as_linecheck(case)
    state = sol.still if still else sol.wind
    for name, lc, ref in (("tower frame", tw, state.reactions_tower), ("global", gl, state.reactions)):
        err = np.abs(lc - ref) / np.abs(ref).max(axis=1, keepdims=True)
        assert np.all(err <= TOL_SECTION), (f"{example.stem}: largest difference {err.max():.3%} at tower "
                                            f"{np.unravel_index(err.argmax(), err.shape)[0] + 1}\n" + _table(name, lc, ref))
