"""The numerical core and the service layer never import a UI library."""

from __future__ import annotations

import subprocess
import sys

import pytest

CORE_MODULES = [
    "linecheck.core.crossflow",
    "linecheck.core.case",
    "linecheck.core.case_schema",
    "linecheck.core.case_model",
    "linecheck.core.case_validate",
    "linecheck.core.case_files",
    "linecheck.core.case_towers",
    "linecheck.core.case_geometry",
    "linecheck.core.case_wires",
    "linecheck.core.tower_totals",
    "linecheck.core.case_load",
    "linecheck.core.errors",
    "linecheck.core.names",
    "linecheck.core.system",
    "linecheck.core.static",
    "linecheck.core.span_operators",
    "linecheck.core.model",
    "linecheck.core.dynamics",
    "linecheck.core.damping",
    "linecheck.core.results",
    "linecheck.core.extremes",
    "linecheck.core.modes",
    "linecheck.core.budget",
    "linecheck.core.spectral",
    "linecheck.core.complex_modes",
    "linecheck.core.gust_factor",
    "linecheck.core.codes",
    "linecheck.core.kernel",
    "linecheck.core.second_order",
    "linecheck.core.banded",
    "linecheck.core.catenary",
    "linecheck.core.uplift",
    "linecheck.core.node_bases",
    "linecheck.core.pieces",
    "linecheck.core.wind.mean",
    "linecheck.core.wind.downburst",
    "linecheck.core.wind.downburst_case",
    "linecheck.core.wind.field_table",
    "linecheck.core.wind.turbulence",
    "linecheck.core.wind.wires",
    "linecheck.core.wind.point",
    "linecheck.core.wind.ring",
    "linecheck.core.wind.profiles",
    "linecheck.core.wind.line_peak",
    "linecheck.core.loads",
    "linecheck.core.line_damping",
    "linecheck.service",
    "linecheck.io.jsonout",
    "linecheck.io.display",
    "linecheck.io.document",
    "linecheck.io.stat_table",
    "linecheck.io.result_blocks",
    "linecheck.io.result_schema",
    "linecheck.io.section",
    "linecheck.io.provenance",
]
#: core modules that import Numba themselves: loaded only by linecheck.core.kernel when the
#: optional compiled kernel is asked for
KERNEL_MODULES = ["linecheck.core._loops", "linecheck.core._loops_wind", "linecheck.core._loops_second_order"]


def test_core_imports_no_ui_libraries():
    code = (
        "import importlib, sys\n"
        f"for m in {CORE_MODULES + KERNEL_MODULES!r}:\n"
        "    importlib.import_module(m)\n"
        "bad = sorted(n for n in ('textual', 'rich', 'typer', 'openpyxl', 'pandas') if n in sys.modules)\n"
        "print(','.join(bad))\n"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "", f"core imported UI/front-end libraries: {out.stdout.strip()}"


def test_core_imports_numba_only_when_the_kernel_is_asked_for():
    """Numba (the optional compiled step loop) is never imported by importing the core;
    only :func:`linecheck.core.kernel.available` loads it."""
    code = (
        "import importlib, sys\n"
        f"for m in {CORE_MODULES!r}:\n"
        "    importlib.import_module(m)\n"
        "print('numba' in sys.modules)\n"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "False"


def test_every_core_module_is_listed():
    """A new core module must be added to the boundary check above."""
    from pathlib import Path

    import linecheck

    root = Path(linecheck.__file__).parent
    found = {
        "linecheck." + ".".join(p.relative_to(root).with_suffix("").parts)
        for p in (root / "core").rglob("*.py")
        if p.name != "__init__.py"
    }
    missing = found - set(CORE_MODULES) - set(KERNEL_MODULES)
    assert not missing, f"add to CORE_MODULES: {sorted(missing)}"


#: modules the start-up of ``linecheck --help`` must not load: each costs 0.1-0.5 s (scipy.stats
#: alone ≈ 0.4 s) and none is needed to print the help; the commands import them where they work
HEAVY_AT_STARTUP = ("scipy.stats", "scipy.optimize", "linecheck.core.dynamics", "linecheck.service", "numba",
                    "textual", "pandas", "openpyxl")


@pytest.mark.parametrize("args", [["--help"], ["run", "--help"], ["batch", "--help"]], ids=" ".join)
def test_help_loads_no_heavy_module(args):
    """``linecheck --help`` (and a command's help) answers without loading the numerical core or
    the front-end libraries: asserted on the modules loaded, not on seconds (a test's verdict never
    depends on the machine's load)."""
    code = (
        "import contextlib, io, sys\n"
        "from linecheck.cli.app import main\n"
        f"sys.argv = ['linecheck', *{args!r}]\n"
        "out = io.StringIO()\n"
        "try:\n"
        "    with contextlib.redirect_stdout(out):\n"
        "        main()\n"
        "except SystemExit as e:\n"
        "    code = e.code\n"
        "else:\n"
        "    code = 0\n"
        f"bad = [m for m in {HEAVY_AT_STARTUP!r} if m in sys.modules]\n"
        "print(code, 'Usage' in out.getvalue(), ','.join(bad))\n"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    code_, usage, bad = (out.stdout.strip().split(" ") + [""])[:3]
    assert (code_, usage) == ("0", "True"), out.stdout + out.stderr  # the help was printed
    assert bad == "", f"linecheck {' '.join(args)} loaded {bad}"


def test_check_loads_no_solver():
    """`linecheck check` of a synoptic and a downburst case loads the case model, the budget and the
    mean wind only: not the solvers (static, dynamics, model), scipy.stats/optimize/interpolate,
    the service or Numba (start-up time; checked by modules, never by seconds)."""
    from pathlib import Path

    root = Path(__file__).resolve().parents[1]
    code = (
        "import sys\n"
        "from linecheck.cli.app import main\n"
        f"sys.argv = ['linecheck', 'check', {str(root / 'cases/paper/case09-six.toml')!r},"
        f" {str(root / 'cases/paper/case01-six.toml')!r}]\n"
        "try:\n    main()\nexcept SystemExit as e:\n    assert e.code in (0, None), e.code\n"
        "heavy = ['linecheck.service', 'linecheck.core.static', 'linecheck.core.dynamics', 'linecheck.core.model',\n"
        "         'scipy.stats', 'scipy.optimize', 'scipy.interpolate', 'scipy.integrate', 'numba']\n"
        "print('loaded:' + ','.join(m for m in heavy if m in sys.modules))\n"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip().splitlines()[-1] == "loaded:", out.stdout
