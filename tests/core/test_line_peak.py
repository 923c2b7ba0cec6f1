"""The line's largest running mean over a downburst, where and when (linecheck.core.wind.line_peak),
against a brute-force scan of the nodes."""

from __future__ import annotations

import numpy as np
import pytest

from linecheck.core.case import load_case, with_values
from linecheck.core.errors import CaseError
from linecheck.core.system import LineSystem
from linecheck.core.wind import mean as M
from linecheck.core.wind.line_peak import line_peak

from ..conftest import CASES


def test_line_peak_reports_where_and_when_the_line_sees_its_largest_mean():
    for model in ("holmes-oliver", "ring-jet"):
        case = with_values(load_case(CASES / "paper" / "case07-six.toml"), {"wind.downburst.model": model})
        lp = line_peak(case)
        # p is tower 4 (a node): the line's largest running mean is V_ref there, at the instant of the peak
        assert lp.speed == pytest.approx(case.wind.v_ref, rel=1e-6)
        assert lp.speed >= case.wind.v_ref * (1 - 1e-9)
        assert lp.node == 30 and lp.station == pytest.approx(1500.0)
        # brute force over the nodes on a fine grid
        s = LineSystem(case.line)
        t = np.linspace(*M.event_window(case), 20001)
        v = M.mean_speed_at_nodes(case, s, t)
        assert v.max() <= lp.speed * (1 + 1e-9)
        assert lp.time == pytest.approx(t[np.unravel_index(np.argmax(v), v.shape)[0]], abs=2 * (t[1] - t[0]))
    # a single span whose p lies beyond it (Db_x, x_p = 480 m > L = 300 m): the line sees less than V_ref
    case = load_case(CASES / "paper" / "case01-single.toml")
    lp = line_peak(case)
    assert lp.speed < case.wind.v_ref and lp.over_v_ref == pytest.approx(lp.speed / case.wind.v_ref)
    assert lp.station == pytest.approx(300.0)  # the end of the span nearest p


def test_line_peak_json_dict_and_synoptic_refusal():
    with pytest.raises(CaseError):
        line_peak(load_case(CASES / "examples" / "section-12span.toml"))  # synoptic: V_ref everywhere
    case = with_values(load_case(CASES / "paper" / "case03-six.toml"), {"wind.downburst.model": "ring-jet"})
    lp = line_peak(case)
    s = LineSystem(case.line)
    assert lp.height == pytest.approx(float(s.node_height[lp.node]))
    assert lp.xy == pytest.approx(tuple(s.node_xyz0[lp.node, :2]))
    d = lp.to_dict()
    assert set(d) == {"speed", "v_ref", "over_v_ref", "time", "node", "station", "xy", "height"}
    assert isinstance(d["xy"], list) and d["speed"] == lp.speed


def test_a_translating_storm_loads_another_tower_above_v_ref():
    """V_ref fixes the running mean at p only: a storm moving along the line (15 m/s toward +x)
    adds its translation to the outflow downstream of p, where the line sees more than V_ref."""
    base = load_case(CASES / "paper" / "case07-six.toml")
    for model in ("holmes-oliver", "ring-jet"):
        case = with_values(base, {"wind.downburst.model": model, "wind.downburst.translation_speed": 15.0,
                                  "wind.downburst.translation_direction": 0.0})
        lp = line_peak(case)
        assert lp.over_v_ref > 1.05 and lp.station > 1500.0  # beyond p (tower 4, station 1500 m)
        s = LineSystem(case.line)
        t = np.linspace(*M.event_window(case), 8001)
        assert M.mean_speed_at_nodes(case, s, t).max() <= lp.speed * (1 + 1e-9)
