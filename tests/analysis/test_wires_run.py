"""Every wire on the tower in one correlated wind (linecheck.analysis.wires_run): each attachment's
reactions, the tower's totals from the summed histories and the load trees.

Two small sections (two 300 m spans, 120 s records, three realizations): three identical wires at
one point, fully coherent (every attachment is the single-wire run bit for bit, each total n x it),
and three distinct wires at distinct points (a twin bundle, a single conductor, a ground wire:
the totals' peaks between the largest attachment's and the sum of the attachments').
"""

from __future__ import annotations

import dataclasses
import threading
from pathlib import Path

import numpy as np
import pytest

from linecheck.analysis import wires_run
from linecheck.analysis.run import run_case
from linecheck.analysis.wires_run import GOVERNING, run_wires
from linecheck.core import budget
from linecheck.core.case import Case, load_case, wire_case
from linecheck.core.errors import Cancelled
from linecheck.core.results import STATISTICS
from linecheck.core.tower_totals import TOTALS
from linecheck.core.tower_totals import reaction_moments as tower_moments

REALIZATIONS = [0, 1, 2]
WIRE = """
[[wires]]
name = "{name}"
kind = "phase"
weight = 17.92
diameter = 0.022
area = 0.7e-4
elastic_modulus = 5.2e10
tension = 20000.0
"""
SECTION = """\
name = "{name}"

[line]
insulator_length = 3.6
tower_of_interest = 2

[[line.towers]]
name = "T1"
station = 0.0
type = "DE"

[[line.towers]]
name = "T2"
station = 300.0
ground = 2.0
type = "S"

[[line.towers]]
name = "T3"
station = 600.0
type = "DE"
{wires}
[[tower_types]]
name = "S"
attachments = [{suspension}]

[[tower_types]]
name = "DE"
attachments = [{strain}]

[wind]
type = "synoptic"
v_ref = 30.0

[analysis]
duration = 120.0
realizations = 3
"""


def _load(tmp_path: Path, text: str) -> Case:
    p = tmp_path / "case.toml"
    p.write_text(text, encoding="utf-8")
    return load_case(p)


@pytest.fixture(scope="module")
def identical(tmp_path_factory) -> Case:
    """Three identical wires A, B, C at one point (y = 2 m, z = 31 m on the suspension type),
    fully coherent (C_y = C_z = 0: the schema asks for > 0, so the case is edited in memory)."""
    names = ("A", "B", "C")
    text = SECTION.format(name="identical", wires="".join(WIRE.format(name=n) for n in names),
                          suspension=", ".join(f'{{ wire = "{n}", y = 2.0, z = 31.0, support = "suspension" }}'
                                               for n in names),
                          strain=", ".join(f'{{ wire = "{n}", y = 2.0, z = 28.0, support = "strain" }}' for n in names))
    case = _load(tmp_path_factory.mktemp("identical"), text)
    return dataclasses.replace(case, wind=dataclasses.replace(case.wind, coherence_decay_y=0.0, coherence_decay_z=0.0))


@pytest.fixture(scope="module")
def three(tmp_path_factory) -> Case:
    """A twin bundle A (y = -5.5 m), a single conductor B (y = 5.5 m, a 4 m insulator) and a
    ground wire G (y = 0, z = 40 m), the default coherence (C_y = 16, C_z = 10)."""
    wires = (WIRE.format(name="A").replace('tension = 20000.0\n', 'tension = 20000.0\nbundle = 2\n'
                                                                  'bundle_spacing = 0.4\nshielding = 0.9\n')
             + WIRE.format(name="B")
             + WIRE.format(name="G").replace('"phase"', '"ground"').replace("17.92", "6.0").replace("0.022", "0.012")
             .replace("0.7e-4", "0.5e-4").replace("5.2e10", "1.6e11").replace("20000.0", "8000.0"))
    text = SECTION.format(
        name="three", wires=wires,
        suspension='{ wire = "A", y = -5.5, z = 31.0, support = "suspension" }, '
                   '{ wire = "B", y = 5.5, z = 31.0, support = "suspension", insulator_length = 4.0 }, '
                   '{ wire = "G", y = 0.0, z = 40.0, support = "suspension", insulator_length = 0.3 }',
        strain='{ wire = "A", y = -5.5, z = 28.0, support = "strain" }, '
               '{ wire = "B", y = 5.5, z = 28.0, support = "strain" }, '
               '{ wire = "G", y = 0.0, z = 37.0, support = "strain" }')
    return _load(tmp_path_factory.mktemp("three"), text)


@pytest.fixture(scope="module")
def identical_runs(identical):
    single = run_case(wire_case(identical, "A"), realizations=REALIZATIONS, spectral_check=False)
    return run_wires(identical, realizations=REALIZATIONS), single


@pytest.fixture(scope="module")
def three_run(three):
    return run_wires(three, realizations=REALIZATIONS)


def _equal_stats(a, b) -> bool:
    return all(np.array_equal(a.values(n), b.values(n), equal_nan=True) for n in STATISTICS)


# --------------------------------------------------------------------------- (a) identical wires
def test_identical_coherent_wires_are_each_the_single_wire_run(identical_runs):
    """Every attachment's statistics are the single-wire run's bit for bit (the same turbulence:
    wires at wire 0's point get its field, which is the single-wire field), and so are the still-air
    reactions and the burn-in."""
    multi, single = identical_runs
    assert multi.wires == ("A", "B", "C")
    np.testing.assert_array_equal(multi.offsets, [[2.0, 31.0 - 3.6]] * 3)
    assert multi.station_spread == 0.0
    np.testing.assert_array_equal(multi.time, single.time)
    for w in range(3):
        assert _equal_stats(multi.attachments[w], single.stats)
        np.testing.assert_array_equal(multi.still_air[w], single.still_air)
        assert multi.burn_in[w] == single.burn_in
    assert _equal_stats(multi.attachment_moments[1], multi.attachment_moments[0])


def test_identical_coherent_wires_total_n_times_one(identical_runs):
    """Each total force is 3 x the single wire's reaction in every force statistic, its gust factors
    and contributions are the single wire's (to rounding); each total moment is 3 x an attachment's
    moment; the sum of the attachment peaks is the total's peak (the wires peak together)."""
    multi, single = identical_runs
    s = single.stats
    for name in ("mean_max", "rms_background", "rms_resonant", "rms_fluctuating", "peak_quasi_static",
                 "peak_dynamic", "peak_quasi_static_total", "peak_dynamic_total"):
        np.testing.assert_allclose(multi.forces.values(name), 3.0 * s.values(name), rtol=1e-12, atol=1e-9)
        np.testing.assert_allclose(multi.moments.values(name), 3.0 * multi.attachment_moments[0].values(name),
                                   rtol=1e-12, atol=1e-8)
    for name in ("GF_Dy", "GF_QS", "Cont_M", "Cont_BG", "Cont_R", "peak_normalised", "peak_normalised_total"):
        np.testing.assert_allclose(multi.forces.values(name), s.values(name), rtol=1e-11, atol=1e-12)
    assert np.isfinite(s.values("GF_Dy")[:, 1, 1]).all()  # the transverse gust factor is defined
    np.testing.assert_allclose(multi.totals_still_air[:, :3], 3.0 * single.still_air, rtol=1e-15)
    np.testing.assert_allclose(multi.peak_sum(), multi.totals("peak_dynamic"), rtol=1e-12, atol=1e-8)
    # the design values (Gumbel, analysis.design_fractile) of the totals are 3 x the single wire's
    forces, _ = multi.totals_summary()
    one = single.summary()
    np.testing.assert_allclose(forces.statistics["peak_dynamic"].gumbel.design,
                               3.0 * one.statistics["peak_dynamic"].gumbel.design, rtol=1e-12)


def _single_tree(single, arm: tuple[float, float]):
    """The single wire's load tree at the tower of interest: for each governing quantity (of the
    one wire, the moments at ``arm`` = (y, z)) its instant per realization and the reaction there
    (still air and mean added), from the run's B, R histories."""
    j = single.tower_index
    T = single.still_air[j] + single.mean[None, :, j] + single.background + single.resonant  # (n_real, n_t, 3)
    six = np.concatenate([T, tower_moments(T, *arm)], axis=-1)
    out = {}
    for case, (k, sense) in GOVERNING.items():
        at = np.argmin(six[..., k], axis=1) if sense == "min" else np.argmax(np.abs(six[..., k]), axis=1)
        out[case] = (at, T[np.arange(T.shape[0]), at], six[np.arange(T.shape[0]), at, k])
    return out


def test_identical_wires_load_trees_are_the_single_wire_at_its_own_peak(identical_runs):
    """At the tower of interest, each governing total of three identical coherent wires peaks when
    the single wire does: every attachment's coincident load is the single wire's reaction at the
    instant of its own peak, and the total's value 3 x the single wire's."""
    multi, single = identical_runs
    j = single.tower_index
    trees = multi.load_trees
    assert trees.cases == tuple(GOVERNING) == ("max_transverse", "max_longitudinal", "max_overturning", "max_torsion",
                                              "min_vertical")
    assert trees.loads.shape == (3, 3, 5, 3, 3)
    for c, (case, (at, load, value)) in enumerate(_single_tree(single, (2.0, 31.0)).items()):
        np.testing.assert_array_equal(trees.time[:, j, c], single.time[at], err_msg=case)
        for w in range(3):
            np.testing.assert_allclose(trees.loads[:, j, c, w], load, rtol=1e-12, atol=1e-9, err_msg=case)
        np.testing.assert_allclose(trees.value[:, j, c], 3.0 * value, rtol=1e-12, err_msg=case)
    np.testing.assert_allclose(trees.mean()[j, :, 0], trees.loads[:, j, :, 0].mean(axis=0), rtol=1e-15)
    assert trees.std().shape == (3, 5, 3, 3)


# --------------------------------------------------------------------------- (b) distinct wires
def test_distinct_wires_total_between_largest_and_sum(three, three_run):
    """Three wires at distinct points: per realization and tower, each total's peak is at most the
    sum of its attachments' peaks (exactly: the triangle inequality) and, for the forces and the
    overturning moments, at least the largest attachment's (their attachments push the same way).
    Torsion is not bounded below: the phases at y = -5.5 and +5.5 m twist the tower in opposite
    senses, so the total's peak is below the larger attachment's.  The correlation saves: the
    transverse total's mean peak is below the sum of the attachments' (at T2 15,603 N against
    16,228 N: 0.961; the largest attachment's 8,393 N)."""
    r = three_run
    assert r.wires == ("A", "B", "G") and TOTALS == ("Fx", "Fy", "Fz", "Mx", "My", "Mz")
    np.testing.assert_array_equal(r.offsets, [[-5.5, 31.0 - 3.6], [5.5, 31.0 - 4.0], [0.0, 40.0 - 0.3]])
    np.testing.assert_array_equal(r.arms[1], [[-5.5, 31.0], [5.5, 31.0], [0.0, 40.0]])
    for name in ("peak_dynamic", "peak_dynamic_total", "peak_quasi_static"):
        total, top, largest = r.totals(name), r.peak_sum(name), r.peak_largest(name)
        assert np.all(total <= top * (1.0 + 1e-12)), name
        assert np.all(total[..., :5] >= largest[..., :5]), name
    assert np.all(r.totals("peak_dynamic")[:, 1, 5] < r.peak_largest()[:, 1, 5])  # torsion at T2
    fy, top = r.forces.mean("peak_dynamic")[1, 1], r.peak_sum().mean(axis=0)[1, 1]
    assert 0.9 * top < fy < 0.99 * top


def test_the_first_wire_is_its_single_wire_run(three, three_run):
    """Wire 0's turbulence is the single-wire field bit for bit (its own burn-in cut from the
    longest one's lead), so its attachment is the single-wire run of wire A; the others draw their
    own phases (correlated, not equal)."""
    single = run_case(wire_case(three, "A"), realizations=REALIZATIONS, spectral_check=False)
    assert _equal_stats(three_run.attachments[0], single.stats)
    assert three_run.burn_in[0].seconds != max(b.seconds for b in three_run.burn_in[1:])  # leads do differ
    other = run_case(wire_case(three, "B"), realizations=REALIZATIONS, spectral_check=False)
    assert not np.array_equal(three_run.attachments[1].peak_dynamic, other.stats.peak_dynamic)
    np.testing.assert_array_equal(three_run.attachments[1].mean_max, other.stats.mean_max)  # the same step 1


def test_chunks_do_not_change_a_bit(three, three_run, monkeypatch):
    """One realization per chunk (a tiny chunk budget) gives the same results bit for bit."""
    monkeypatch.setattr(budget, "RUN_CHUNK_BYTES", 1.0)
    seen, field = [], wires_run.fluctuating_velocity_wires

    def counted(case, system, offsets, time, realizations, **kw):
        seen.append(len(realizations))
        return field(case, system, offsets, time, realizations, **kw)

    monkeypatch.setattr(wires_run, "fluctuating_velocity_wires", counted)
    chunked = run_wires(three, realizations=REALIZATIONS)
    assert seen == [1, 1, 1]
    for a, b in zip(chunked.attachments + chunked.attachment_moments + (chunked.forces, chunked.moments),
                    three_run.attachments + three_run.attachment_moments + (three_run.forces, three_run.moments)):
        assert _equal_stats(a, b)
    for k in ("value", "time", "loads"):
        np.testing.assert_array_equal(getattr(chunked.load_trees, k), getattr(three_run.load_trees, k))


def test_threads_do_not_change_a_bit(three, three_run):
    """Two threads (chunks of two and one realization at once) give the same results bit for bit."""
    threaded = run_wires(three, realizations=REALIZATIONS, threads=2)
    for a, b in zip(threaded.attachments + threaded.attachment_moments + (threaded.forces, threaded.moments),
                    three_run.attachments + three_run.attachment_moments + (three_run.forces, three_run.moments)):
        assert _equal_stats(a, b)
    for k in ("value", "time", "loads"):
        np.testing.assert_array_equal(getattr(threaded.load_trees, k), getattr(three_run.load_trees, k))


def test_a_case_without_wires_is_refused(three):
    with pytest.raises(ValueError, match="has no \\[\\[wires\\]\\]"):
        run_wires(wire_case(three, "A"))


def test_progress_and_cancel(three):
    """Progress reports each wire's step 1, the field per chunk and the dynamics summed over the
    wires' steps; a set cancel event stops the run."""
    seen: list[tuple[str, int, int]] = []
    run_wires(three, realizations=[0], progress=lambda stage, done, total: seen.append((stage, done, total)))
    stages = {s for s, _, _ in seen}
    assert {"wind", "steps 2-3: dynamics"} <= stages
    dyn = [(d, t) for s, d, t in seen if s == "steps 2-3: dynamics"]
    assert all(0 <= d <= t for d, t in dyn) and len({t for _, t in dyn}) == 1
    assert ("wind", 1, 1) in seen and dyn[-1][0] == dyn[-1][1]
    cancel = threading.Event()
    cancel.set()
    with pytest.raises(Cancelled):
        run_wires(three, realizations=[0], cancel=cancel)


def test_load_trees_at_the_totals_peaks_with_peak_windows(three):
    """With 30 s peak windows every statistic and tree is per window (3 realizations x 4 windows of
    the 120 s record): each governing total's value is its peak with still air (max |total|:
    peak_dynamic_total up to the sign; uplift: the least F_z, at most F_z at the other instants),
    its instant lies in its window, and its attachments' loads add up to it (forces: the sum;
    moments: tower_moments of the loads)."""
    case = dataclasses.replace(three, analysis=dataclasses.replace(three.analysis, peak_window=30.0))
    r = run_wires(case, realizations=REALIZATIONS)
    trees, n_win = r.load_trees, 4
    assert r.forces.n_samples == trees.value.shape[0] == 3 * n_win
    six = r.totals("peak_dynamic_total")
    for c, (k, sense) in enumerate(GOVERNING.values()):
        if sense == "abs":
            np.testing.assert_allclose(np.abs(trees.value[..., c]), six[..., k], rtol=1e-12)
    window = np.arange(trees.time.shape[0]) % n_win  # the sample's window in its realization
    start = r.time[0] + window * 30.0
    assert np.all((trees.time >= start[:, None, None] - 1e-9) & (trees.time < start[:, None, None] + 30.0 - 1e-9))
    forces = trees.loads.sum(axis=3)  # (n_s, n_towers, n_cases, 3)
    moments = tower_moments(trees.loads, r.arms[None, :, None, :, 0], r.arms[None, :, None, :, 1]).sum(axis=3)
    totals = np.concatenate([forces, moments], axis=-1)
    for c, (k, _) in enumerate(GOVERNING.values()):
        np.testing.assert_allclose(totals[..., c, k], trees.value[..., c], rtol=1e-9, atol=1e-6)
    # the least F_z of a window is at most its F_z at any other case's instant in that window
    assert np.all(trees.value[..., 4] <= totals[..., :4, 2].min(axis=-1) + 1e-9)
