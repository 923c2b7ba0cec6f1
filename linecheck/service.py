"""Service layer: the one function per job that every front end calls.

CLI, TUI, Excel export and batch runners call these functions and nothing deeper.  They take a
validated :class:`~linecheck.core.case.Case`, report progress through a callback
``progress(stage, done, total)`` and stop when the ``cancel`` event is set (raising
:class:`~linecheck.core.errors.Cancelled`).  The jobs themselves live in
:mod:`linecheck.analysis`, one module per job; this module only gathers their entry points and
result types (and the core names the tests use beside them).  Nothing here prints.
"""

from __future__ import annotations

from .analysis.burnin import BurnIn, burn_in, synoptic_burn_in
from .analysis.code_check import (
    CodeCheck,
    CodesResult,
    ReactionCheck,
    TowerCheck,
    code_loads,
    codes_analysis,
    design_peaks,
)
from .analysis.concurrency import run_threads
from .analysis.guard import Warn, check_budget, check_case, warn_case
from .analysis.linear import SynopticModel, damping_matrices, synoptic_model
from .analysis.modes import ModesResult, modes_analysis
from .analysis.record import peak_window_steps, record_mean_wind, record_time, record_wind
from .analysis.run import RunResult, TowerRun, run_case, run_tower
from .analysis.spectral_check import (
    CHECK_WINDOW_HALVES,
    CHECK_WINDOW_RTOL,
    CheckWindow,
    SanityItem,
    SpectralResult,
    closed_form_not_applicable,
    sanity_check,
    spectral_analysis,
)
from .analysis.spread import (
    BUILTIN_DOWNBURST_MODELS,
    case_with_model,
    model_changes,
    parse_models,
    run_models,
    spread_models,
)
from .analysis.step1 import Progress, StaticResult, mean_state_times, static_analysis, static_result
from .analysis.until import UntilInfo, join_runs, relative_standard_error, run_until
from .analysis.wind_export import (
    WindAtP,
    WindField,
    loads_from_field,
    read_wind_field,
    record_grid,
    wind_at_p,
    wind_field,
)
from .analysis.windows import CHECK_WINDOW_MIN_SPANS, window_case, windowed
from .analysis.wires_run import LoadTrees, WiresRun, run_wires
from .analysis.wires_static import WiresStatic, wires_static_analysis, wires_uplift_warnings
from .core.codes import CODES_PEAK
from .core.damping import aerodynamic_damping_stack, stiffness_proportional_stack
from .core.dynamics import integrate
from .core.line_damping import reference_state_index, structural_omega1
from .core.loads import fluctuating_loads, mean_loads, to_global_nodes, turbulence_variance_ratio
from .core.model import build_model, build_models
from .core.system import LineSystem
from .core.tower_totals import TOTALS, tower_totals

__all__ = [  # the names front ends, tests and benchmarks use
    "BUILTIN_DOWNBURST_MODELS", "CHECK_WINDOW_HALVES", "CHECK_WINDOW_MIN_SPANS", "CHECK_WINDOW_RTOL", "CODES_PEAK",
    "TOTALS", "BurnIn", "CheckWindow", "CodeCheck", "CodesResult", "LineSystem", "LoadTrees", "ModesResult",
    "Progress", "ReactionCheck", "RunResult", "SanityItem", "SpectralResult", "StaticResult", "SynopticModel",
    "TowerCheck", "TowerRun", "UntilInfo", "Warn", "WindAtP", "WindField", "WiresRun", "WiresStatic",
    "aerodynamic_damping_stack", "build_model", "build_models", "burn_in", "case_with_model", "check_budget",
    "check_case", "closed_form_not_applicable", "code_loads", "codes_analysis", "damping_matrices", "design_peaks",
    "fluctuating_loads", "integrate", "join_runs", "loads_from_field", "mean_loads", "mean_state_times",
    "model_changes", "modes_analysis", "parse_models", "peak_window_steps", "read_wind_field", "record_grid",
    "record_mean_wind", "record_time", "record_wind", "reference_state_index", "relative_standard_error",
    "run_case", "run_models", "run_threads", "run_tower", "run_until", "run_wires", "sanity_check",
    "spectral_analysis", "spread_models", "static_analysis", "static_result", "stiffness_proportional_stack",
    "structural_omega1", "synoptic_burn_in", "synoptic_model", "to_global_nodes", "tower_totals",
    "turbulence_variance_ratio", "warn_case", "wind_at_p", "wind_field", "window_case", "windowed",
    "wires_static_analysis", "wires_uplift_warnings"
]
