"""The OpenSeesPy non-linear reference (bench/opensees_reference.py) in still air.

Skipped when openseespy is not importable (the ``bench`` extra) or cannot load the system
BLAS/LAPACK.  The reference's static state under the weight alone (corotational trusses of
unstretched length L_u / n_el, stiff insulator trusses) must give linecheck's still-air reactions
within 0.5 % (the discrete chain approaches the elastic catenary as 1/n_el^2: -0.3 % in R_x with
linecheck's 10 elements per span, -0.08 % with 40).
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
import pytest

pytest.importorskip("openseespy")

ROOT = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT / "bench"))

import opensees_reference as ref

from linecheck.core.case import load_case
from linecheck.core.static import still_air_state
from linecheck.core.system import LineSystem

TOL = 0.005  # 0.5 %


@pytest.fixture(scope="module")
def opensees():
    try:
        return ref.load_opensees()
    except ref.OpenSeesUnavailable as exc:
        pytest.skip(str(exc))


@pytest.mark.slow
@pytest.mark.parametrize("name", ["case09-single", "case09-six"])
@pytest.mark.parametrize("n_el", [None, 40])
def test_still_air_reactions_match_linecheck(opensees, name, n_el):
    case = load_case(ROOT / "cases" / "paper" / f"{name}.toml")
    lc = still_air_state(LineSystem(case.line)).reactions  # (n_towers, 3)
    os_ = ref.NonlinearLine(case, n_el=n_el).still_air()
    scale = np.linalg.norm(lc, axis=1)  # per tower
    assert np.all(scale > 0)
    err = np.abs(os_ - lc) / scale[:, None]
    assert err.max() <= TOL, f"{name}, n_el={n_el}: largest difference {100 * err.max():.3f} % of |R|"
    # the non-zero components each within 0.5 % of themselves
    big = np.abs(lc) > 1e-6 * scale[:, None]
    assert np.all(np.abs(os_ - lc)[big] <= TOL * np.abs(lc)[big])
    # and the zero ones stay zero (symmetry: R_y = 0 in still air, R_x = 0 at inner suspension towers)
    assert np.all(np.abs(os_[~big]) <= 1e-6 * np.repeat(scale[:, None], 3, axis=1)[~big])


def test_missing_blas_is_reported_in_one_line(monkeypatch):
    """The loader turns the wheel's wrapped linker error into one actionable line."""
    import builtins

    real_import = builtins.__import__

    def fake_import(name, *args, **kwargs):
        if name in ("openseespy.opensees", "openseespylinux.opensees"):
            raise ImportError("libblas.so.3: cannot open shared object file: No such file or directory")
        return real_import(name, *args, **kwargs)

    monkeypatch.setattr(builtins, "__import__", fake_import)
    with pytest.raises(ref.OpenSeesUnavailable) as info:
        ref.load_opensees()
    msg = str(info.value)
    assert "\n" not in msg and "libblas3" in msg and "liblapack3" in msg
