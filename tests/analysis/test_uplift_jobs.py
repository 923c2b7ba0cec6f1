"""Uplift as a result of step 1 and the jobs it stops (linecheck.analysis.uplift).

The valley section of tests/core/test_uplift.py (five 300 m spans, T3 below its neighbours,
H0 = 22 kN): 40 m lower, T3 lifts in still air (margin -491.65 N, Irvine's closed form there);
35 m lower it hangs in still air and lifts under the mean wind, whose drag raises the tensions
and with them the upward pull H h / L of the inclined spans.
"""

from __future__ import annotations

import re

import numpy as np
import pytest

from linecheck.analysis.step1 import static_result
from linecheck.analysis.uplift import require_tension, step1_uplift, uplift_warning
from linecheck.core.case import with_values
from linecheck.core.errors import UpliftError
from linecheck.service import modes_analysis, run_case, spectral_analysis

from ..core.test_uplift import W, valley_case


def test_the_mean_state_holds_the_valley_clamp_and_reports_its_margin():
    """Under the mean wind T3 stays held at its still-air point (zero displacement) while its
    neighbours swing downwind; the margins are R_z of the states (the still-air one -491.65 N)
    and the weight spans R_z / W."""
    st = static_result(valley_case())
    m = st.mean
    assert m.held[0].tolist() == [False, False, True, False, False, False]
    assert np.all(m.displacement[0, 2] == 0.0)
    assert m.displacement[0, 1, 1] > 0.1 and m.displacement[0, 3, 1] > 0.1  # T2, T4 swing with the wind
    u = step1_uplift(st)
    assert u.margin[0, 2] == m.reactions[0, 2, 2] < u.margin_still_air[2] < 0.0  # the wind lifts it further
    assert u.margin_still_air[2] == pytest.approx(-491.649, abs=1e-3)
    np.testing.assert_allclose(u.weight_span[0, 1:5], m.reactions[0, 1:5, 2] / W, rtol=1e-15)
    assert u.first_uplift() == (2, None, pytest.approx(-491.649, abs=1e-3))  # still air named first


def test_jobs_that_linearise_refuse_an_uplifting_case_in_one_line():
    """run, modes and the frequency-domain check refuse the case with one message naming the case,
    the tower, its margin and the state; the step-1 warning names both states."""
    case = valley_case()
    message = ("valley: uplift at tower T3 (margin -492 N in still air): the dynamic model needs every "
               "suspension insulator in tension; see `linecheck static`")
    for job in (run_case, modes_analysis, spectral_analysis):
        with pytest.raises(UpliftError) as err:
            job(case)
        assert str(err.value) == message and err.value.exit_code == 1
    text = uplift_warning(static_result(case))
    assert re.match(r"valley: uplift at tower T3 \(margin -492 N in still air, -\d+ N under the mean wind\): ", text)


def test_uplift_under_the_mean_wind_only():
    """35 m lower: T3 hangs in still air (+242 N) but lifts under the mean wind (the run is refused,
    naming that state)."""
    st = static_result(valley_case(35.0))
    u = step1_uplift(st)
    assert not u.held_still_air.any() and u.held[0, 2]
    assert u.margin_still_air[2] > 200.0 and u.margin[0, 2] < -200.0
    with pytest.raises(UpliftError, match=r"uplift at tower T3 \(margin -\d+ N under the mean wind\)"):
        require_tension(st)


def test_downburst_names_the_instant_and_holds_only_where_it_lifts():
    """A downburst over the 35 m valley: T3 is held only in the states whose wind lifts it, each
    state's flag its own; the message names the instant of the smallest held margin."""
    case = with_values(valley_case(35.0, v_ref=40.0), {
        "wind.type": "downburst", "wind.turbulence_intensity": 0.11,
        "wind.downburst": {"jet_diameter": 640.0, "distance": 700.0, "angle": 0.0},
        "analysis.mean_states": 20, "analysis.duration": None})
    st = static_result(case)
    u = step1_uplift(st)
    held = u.held[:, 2]
    assert held.any() and not held.all()  # calm states hang, the storm's peak lifts
    assert np.all(u.margin[held, 2] < 0.0) and np.all(u.margin[~held, 2] > 0.0)
    assert not u.held[:, [1, 3, 4]].any()
    k = int(np.argmin(np.where(held, u.margin[:, 2], np.inf)))
    with pytest.raises(UpliftError, match=rf"under the mean wind at t = {st.mean.time[k]:.1f} s\)"):
        require_tension(st)
