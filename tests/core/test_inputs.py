"""Hostile input and resource guards."""

from __future__ import annotations

import os
import subprocess
import sys
import time
import warnings

import numpy as np
import pytest
from typer.testing import CliRunner

from linecheck import service
from linecheck.analysis import run as run_module
from linecheck.cli.app import app
from linecheck.core import budget
from linecheck.core.case import MAX_CASE_BYTES, load_case, read_regular_file, with_values
from linecheck.core.errors import CaseError

from ..conftest import CASES
from .test_case import GOOD, write

PAPER = CASES / "paper"


def cli(*args: str):
    return CliRunner().invoke(app, list(args))


# --------------------------------------------------------------------------- item 6
@pytest.mark.parametrize(("old", "new", "key", "code"), [
    ('name = "case09"', 'name = "case\\u001b[31m09"', "name", "U+001B"),
    ('description = "Synoptic', 'description = "Syn\\u0000optic', "description", "U+0000"),
    ('description = "Synoptic', 'description = "Syn\\u009boptic', "description", "U+009B"),  # C1 CSI
    ('type = "synoptic"', 'type = "synoptic\\u0007"', "wind.type", "U+0007"),
    ('[analysis]', '[analysis]\n"x\\u001b" = 1', "analysis", "U+001B"),
])
def test_control_characters_are_rejected_with_key_and_code_point(tmp_path, old, new, key, code):
    p = write(tmp_path, GOOD.replace(old, new, 1))
    with pytest.raises(CaseError) as exc:
        load_case(p)
    msg = str(exc.value)
    assert f"{key}:" in msg and code in msg
    assert "\x1b" not in msg and "\x00" not in msg and "\x9b" not in msg and "\n" not in msg
    r = cli("check", str(p))
    assert r.exit_code == 2 and "\x1b" not in r.output


def test_tab_is_allowed_in_a_description(tmp_path):
    case = load_case(write(tmp_path, GOOD.replace('description = "Synoptic', 'description = "Syn\\toptic', 1)))
    assert case.description.startswith("Syn\toptic")


# --------------------------------------------------------------------------- item 8
def test_fifo_case_exits_2_without_hanging(tmp_path):
    fifo = tmp_path / "case.toml"
    os.mkfifo(fifo)
    # A subprocess so that a regression (a blocking open) cannot hang the test session; the
    # 300 s bound only stops such a regression, the verdict is the exit code and message.
    out = subprocess.run([sys.executable, "-c", "from linecheck.cli.app import main; main()", "check", str(fifo)],
                         capture_output=True, text=True, timeout=300)
    assert out.returncode == 2
    assert "is not a regular file" in out.stderr and "Traceback" not in out.stderr


def test_symlink_to_dev_zero_and_oversize_files_exit_2(tmp_path):
    link = tmp_path / "zero.toml"
    link.symlink_to("/dev/zero")
    r = cli("check", str(link))
    assert r.exit_code == 2 and "is not a regular file" in r.output
    big = tmp_path / "big.toml"
    with big.open("wb") as fh:  # sparse: no 10 MB written
        fh.truncate(MAX_CASE_BYTES + 1)
    r = cli("run", str(big))
    assert r.exit_code == 2 and "too large" in r.output and "10.0 MB" in r.output


def test_read_regular_file_reads_at_most_the_cap(tmp_path):
    p = tmp_path / "f.txt"
    p.write_bytes(b"x" * 100)
    assert read_regular_file(p, "text", 100) == b"x" * 100
    with pytest.raises(CaseError, match="100 bytes is too large: expected at most 99 bytes"):
        read_regular_file(p, "text", 99)


def test_oversize_field_file_is_refused_before_reading(tmp_path, monkeypatch):
    import linecheck.core.wind.field_table as mean

    src = (CASES / "fields" / "example-field.csv").read_bytes()
    p = tmp_path / "field.csv"
    p.write_bytes(src)
    monkeypatch.setattr(mean, "MAX_FIELD_BYTES", len(src) - 1)
    with pytest.raises(CaseError, match="too large"):
        mean.load_field_table(p)


# --------------------------------------------------------------------------- item 9
def test_deep_nesting_is_a_case_error(tmp_path):
    deep = write(tmp_path, GOOD + "x = " + "[" * 20000 + "]" * 20000 + "\n")  # tomllib: RecursionError
    r = cli("check", str(deep))
    assert r.exit_code == 2 and "nested too deeply" in r.output
    mid = write(tmp_path, GOOD.replace("seed = 2015", "seed = " + "[" * 40 + "1" + "]" * 40), "mid.toml")
    with pytest.raises(CaseError, match="analysis.seed: value nested 17 levels deep"):
        load_case(mid)


def test_geometry_below_ground_is_rejected(tmp_path):
    low = GOOD.replace("height = 43.0", "height = 5.0").replace("sag = 10.0", "sag = 70.0").replace(
        "span_length = 300.0", "span_length = 1000.0")
    with pytest.raises(CaseError, match=r"line.sag: value 70.0 is not allowed with height = 5.0: expected sag < height"):
        load_case(write(tmp_path, low))
    six = (PAPER / "case01-six.toml").read_text()
    tall = six.replace("insulator_length = 4.0", "insulator_length = 20.0").replace("height = 43.0", "height = 15.0")
    with pytest.raises(CaseError, match="line.insulator_length: value 20.0 .* expected insulator_length < height"):
        load_case(write(tmp_path, tall, "tall.toml"))
    # strain towers only: the (default) insulator length does not apply
    ok = GOOD.replace("height = 43.0", "height = 3.0").replace("sag = 10.0", "sag = 2.0")
    assert load_case(write(tmp_path, ok, "ok.toml")).line.height == 3.0


def test_check_reads_the_field_file(tmp_path):
    bad = tmp_path / "bad.csv"
    bad.write_text("r_over_dj,z_over_dj,t,v_radial\n0,0,0,1\n")
    text = (CASES / "examples" / "downburst-user-field.toml").read_text().replace(
        "../fields/example-field.csv", str(bad))
    r = cli("check", str(write(tmp_path, text)))
    assert r.exit_code == 2
    assert f"{bad}: column r_over_dj has 1 distinct value(s)" in " ".join(r.output.split())


def test_v_ref_zero_message_names_the_file(tmp_path):
    p = write(tmp_path, GOOD.replace("v_ref = 40.0", "v_ref = 0.0"))
    r = cli("check", str(p))
    assert r.exit_code == 2 and f"{p}: wind.v_ref: value 0.0 is not allowed" in " ".join(r.output.split())
    from linecheck.core.system import LineSystem
    from linecheck.core.wind.turbulence import unit_field

    case = load_case(p)
    with pytest.raises(CaseError, match=f"^{p}: wind.v_ref"):
        unit_field(case, LineSystem(case.line), 64, 0.05, 0)


def test_zero_turbulence_leaks_no_runtime_warning(tmp_path):
    case = load_case(write(tmp_path, GOOD.replace("turbulence_intensity = 0.12", "turbulence_intensity = 0.0")))
    with warnings.catch_warnings():
        warnings.simplefilter("error", RuntimeWarning)
        res = service.spectral_analysis(case)
    ex = res.exact
    # no turbulence: zero fluctuation, peaks equal the mean, Cont_R = 0 where the peak is not zero
    assert np.all(ex.rms_fluctuating == 0.0)
    nz = ex.peak_dynamic > 0
    assert nz.any() and np.all(ex.Cont_R[nz] == 0.0) and np.all(np.isnan(ex.Cont_R[~nz]))


def test_stale_temporaries_of_a_killed_writer_are_removed(tmp_path):
    from linecheck.io import atomic

    target = tmp_path / "out.xlsx"
    stale = tmp_path / ".out.xlsx.abc123.tmp"
    other = tmp_path / ".other.xlsx.abc123.tmp"
    for f in (stale, other):
        f.write_bytes(b"partial")
        old = atomic._PROCESS_START - 3600
        os.utime(f, (old, old))
    fresh = tmp_path / ".out.xlsx.new999.tmp"  # a writer that started after this process: kept
    fresh.write_bytes(b"live")
    future = time.time() + 60
    os.utime(fresh, (future, future))
    atomic.write_text_atomic(target, "ok")
    assert target.read_text() == "ok"
    assert not stale.exists() and other.exists() and fresh.exists()


# --------------------------------------------------------------------------- item 5
def test_huge_realization_override_exits_2_with_the_estimate_before_computing(monkeypatch):
    def fail(*a, **k):
        raise AssertionError("the run started")

    monkeypatch.setattr(run_module, "static_result", fail)
    monkeypatch.setattr(run_module, "integrate", fail)
    r = cli("run", str(PAPER / "case01-single.toml"), "-n", "1000000000")
    out = " ".join(r.output.split())
    assert r.exit_code == 2, out
    # realizations run in memory-sized chunks, but the result keeps B and R at the
    # tower of interest of every one: 1e9 x 12001 steps x 6 doubles x 8 bytes = 5.76e14 bytes
    assert "run needs about 577 TB of memory" in out and "--max-memory" in out


def _address_space_limit(nbytes: int):
    """A ``preexec_fn`` that caps the child's address space (RLIMIT_AS) at ``nbytes``."""
    def limit() -> None:
        import resource

        resource.setrlimit(resource.RLIMIT_AS, (nbytes, nbytes))
    return limit


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="RLIMIT_AS as a hard cap: Linux")
def test_huge_realization_override_is_refused_before_any_allocation():
    """The guard runs before anything is sized by the realization count: the same refusal in a
    process whose address space is capped at 4 GB, where allocating the 1e9 realizations' indices
    (8 GB) first would end in a MemoryError (exit 1) instead of the one-line estimate (exit 2)."""
    code = "import sys; from linecheck.cli.app import main; sys.argv[0] = 'linecheck'; main()"
    env = {**os.environ, "COLUMNS": "250"}
    r = subprocess.run([sys.executable, "-c", code, "run", str(PAPER / "case01-single.toml"), "-n", "1000000000"],
                       capture_output=True, text=True, env=env, timeout=120,
                       preexec_fn=_address_space_limit(4_000_000_000))
    err = " ".join(r.stderr.split())
    assert r.returncode == 2, r.stdout + r.stderr
    assert "run needs about 577 TB of memory" in err and "--max-memory" in err
    assert "Traceback" not in r.stderr and len(r.stderr.strip().splitlines()) == 1


def test_overrides_are_validated_like_the_file():
    r = cli("run", str(PAPER / "case01-single.toml"), "-n", "2000000000")
    assert r.exit_code == 2
    assert "--realizations: value 2000000000 is out of range" in " ".join(r.output.split())
    r = cli("run", str(PAPER / "case01-single.toml"), "--seed", str(10**23))
    assert r.exit_code == 2 and "--seed: value 100000000000000000000000 is out of range" in " ".join(r.output.split())


def test_estimate_counts_match_the_model():
    """Sizes computed arithmetically equal those of the real record grid and FE model."""
    from linecheck.core.model import build_model
    from linecheck.core.wind.point import record_times

    for f in ("case01-six.toml", "case09-single.toml", "case12-six.toml"):
        case = load_case(PAPER / f)
        est = budget.estimate(case)
        assert est.n_steps == record_times(case).size
        model = build_model(service.LineSystem(case.line), service.static_analysis(case).mean.still_air)
        assert est.n_dof == model.K_band.shape[1]
        assert est.n_nodes == service.LineSystem(case.line).n_nodes


def test_memory_limit_option_env_and_warning(monkeypatch):
    case = load_case(PAPER / "case01-single.toml")
    est = budget.estimate(case)
    monkeypatch.setenv(budget.ENV_MAX_MEMORY, f"{est.memory * 1.5:.0f}")
    got: list[str] = []
    budget.check(est, case, got.append)  # between half the limit and the limit: a warning
    assert len(got) == 1 and "more than 50% of the memory limit" in got[0]
    monkeypatch.setenv(budget.ENV_MAX_MEMORY, "1MB")
    with pytest.raises(CaseError, match="above the memory limit of 1 MB"):
        service.run_case(case, realizations=[0])
    monkeypatch.delenv(budget.ENV_MAX_MEMORY)
    r = cli("run", str(PAPER / "case01-single.toml"), "--max-memory", "1MB")
    assert r.exit_code == 2 and "above the memory limit of 1 MB" in " ".join(r.output.split())


def test_parse_size():
    assert budget.parse_size("8GB") == 8e9
    assert budget.parse_size("1.5GiB") == 1.5 * 2**30
    assert budget.parse_size("512 mb") == 512e6
    assert budget.parse_size("1e9") == 1e9
    with pytest.raises(CaseError, match="--max-memory: value 'lots'"):
        budget.parse_size("lots")


def test_with_values_keeps_large_legal_case_refused_by_the_guard_not_the_schema():
    case = with_values(load_case(PAPER / "case09-single.toml"), {"analysis.realizations": 10000})
    est = budget.estimate(case)
    # realizations in chunks of 1 GB / (12001 steps x 8 bytes x (3 x 11 nodes + 24 x 2 towers)) = 128
    # at once: 4 arrays x 8 bytes x 128 x 12001 x 11 nodes + 8 x 8 x 12001 x 11, what the result
    # keeps of all 1e4 (6 doubles per step, 45 statistics per tower), + 100 MB + one state of
    # 27 DOF (33 less the 6 of the two pinned strain towers) + 7 dense 27 x 27 matrices + the
    # turbulence memos at their caps (1e4 unit fields of 1.06 MB: 256 MB; phases and phasors of
    # 3 x 11 x 6000 doubles: 128 MB)
    assert budget.realization_chunk(case, 12001) == 128
    expect = (4 * 8 * 128 * 12001 * 11 + 8 * 8 * 12001 * 11 + 6 * 8 * 1e4 * 12001 + 45 * 8 * 1e4 * 2
              + 100e6 + (20 * 8 * 27 + 3e3) + 7 * 27**2 * 8 + 256e6 + 128e6)
    assert est.memory == pytest.approx(expect, rel=1e-12)


def test_the_estimate_counts_the_turbulence_memos():
    """The per-process memos of unit fields and phases are in the estimate: n_real
    fields of n_steps x n_nodes doubles and 3 n_nodes n_freq doubles of phases each, up to their
    caps; a field above a quarter of the cap (a long line) is not kept, so not counted."""
    six = load_case(PAPER / "case09-six.toml")
    est = budget.estimate(six, realizations=3)
    n = est.n_steps
    assert budget.memo_bytes(3, n, 61) == 3 * 8 * n * 61 + 3 * 3 * 8 * (n // 2) * 61
    assert budget.memo_bytes(1000, n, 61) == 256e6 + 128e6  # the caps
    assert budget.memo_bytes(10, n, 2001) == 0.0  # 200 spans: 192 MB a field, 288 MB of phases: not kept
    few = budget.estimate(six, realizations=1)
    assert est.memory - few.memory >= 2 * (8 * n * 61 + 3 * 8 * (n // 2) * 61)


def test_check_warns_between_half_the_limit_and_the_limit(monkeypatch):
    case = load_case(PAPER / "case01-six.toml")
    est = budget.estimate(case)
    monkeypatch.setenv(budget.ENV_MAX_MEMORY, f"{est.memory * 1.2:.0f}")
    r = cli("check", str(PAPER / "case01-six.toml"))
    out = " ".join(r.output.split())
    assert r.exit_code == 0 and "warning: run needs about" in out and "ok " in out
    monkeypatch.setenv(budget.ENV_MAX_MEMORY, f"{est.memory * 0.8:.0f}")
    r = cli("check", str(PAPER / "case01-six.toml"))
    assert r.exit_code == 2 and "above the memory limit" in r.output


def test_batch_task_above_the_limit_fails_only_that_case(tmp_path, monkeypatch):
    monkeypatch.setenv(budget.ENV_MAX_MEMORY, "1MB")  # restored after the test (the option sets it too)
    r = cli("batch", str(PAPER / "case01-single.toml"), "-j", "1", "--json-dir", str(tmp_path / "res"),
            "--max-memory", "1MB")
    assert r.exit_code == 1 and "above the memory limit of 1 MB" in " ".join(r.output.split())
    assert not list((tmp_path / "res").glob("*.json"))
