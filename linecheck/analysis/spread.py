"""The downburst model spread (``--models``): one case run under several downburst running-mean
models (Holmes-Oliver, ring jet, a user's field table) with the same analysis settings and
turbulence seeds, so that the spread of the results shows the model uncertainty.  Nothing here
prints.
"""

from __future__ import annotations

from ..core.case import Case
from .run import RunResult, run_case

#: Downburst running-mean models that need no user data; "table" joins them when the case names a field.
BUILTIN_DOWNBURST_MODELS = ("holmes-oliver", "ring-jet")


def spread_models(case: Case) -> tuple[str, ...]:
    """The models a ``--models all`` run uses for ``case``: every built-in downburst model, plus
    "table" when the case names a field file; () for a synoptic case."""
    if case.wind.type != "downburst" or case.wind.downburst is None:
        return ()
    extra = ("table",) if case.wind.downburst.field is not None else ()
    return BUILTIN_DOWNBURST_MODELS + extra


def model_changes(case: Case, model: str) -> dict:
    """Case key changes that put ``case`` under downburst model ``model``: the key ``model`` and
    the removal of the other models' keys (t1/t_f, jet_velocity, field); {} if already so."""
    from ..core.errors import CaseError

    db = case.wind.downburst
    if db is None:
        raise CaseError("has no [wind.downburst] table: a model spread needs a downburst case", key="wind.type")
    if db.model_name == model:
        return {}
    changes: dict = {"wind.downburst.model": model}
    if model != "table":
        changes["wind.downburst.field"] = None
    if model not in ("ring-jet", "ring-jet-inviscid"):  # the ring models read jet_velocity
        changes["wind.downburst.jet_velocity"] = None
    if model != "holmes-oliver":
        changes["wind.downburst.t1"] = None
        changes["wind.downburst.t_f"] = None
    return changes


def case_with_model(case: Case, model: str) -> Case:
    """``case`` under downburst model ``model`` (:func:`model_changes`); geometry, V_ref,
    translation, analysis settings and seeds kept."""
    from ..core.case import with_values

    changes = model_changes(case, model)
    return with_values(case, changes) if changes else case


def parse_models(case: Case, text: str) -> tuple[str, ...]:
    """The models of a ``--models`` option: "all" (:func:`spread_models`) or a comma list."""
    from ..core.case import DOWNBURST_MODELS
    from ..core.errors import CaseError

    if case.wind.type != "downburst":
        raise CaseError("is not a downburst case: --models needs type = \"downburst\"",
                        file=str(case.source) if case.source else None, key="wind.type")
    if text.strip() == "all":
        return spread_models(case)
    names = tuple(dict.fromkeys(n.strip() for n in text.split(",") if n.strip()))
    for n in names:
        if n not in DOWNBURST_MODELS:
            raise CaseError(f'--models: value "{n}" is not allowed: expected "all" or a comma list of '
                            + ", ".join(f'"{m}"' for m in DOWNBURST_MODELS))
    if not names:
        raise CaseError('--models: empty: expected "all" or a comma list of model names')
    return names


def run_models(case: Case, models: tuple[str, ...] | list[str] | None = None, **kwargs) -> dict[str, RunResult]:
    """Run ``case`` under each downburst model (default :func:`spread_models`) with the same
    analysis settings and turbulence seeds; ``kwargs`` go to :func:`run_case`.  Returns the
    results keyed by model name, in the order given."""
    from ..core.errors import CaseError

    names = tuple(models) if models is not None else spread_models(case)
    if not names:
        raise CaseError("is not a downburst case: the model spread (--models) needs type = \"downburst\"",
                        file=str(case.source) if case.source else None, key="wind.type")
    return {m: run_case(case_with_model(case, m), **kwargs) for m in names}
