"""The figure of any result: what `result.plot()` draws (springlab.display.plot imports this module by name).

The results live in layers below this one and cannot import it; `figure` picks the drawing function by the
result's type from the table below (a literal table, not a registry filled at import) and returns the bare
matplotlib Figure the same function draws for the command's PNG.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import TYPE_CHECKING, Any

from springlab.errors import BadInputError
from springlab.runs.run import Result
from springlab.studies.audit.results import Audit
from springlab.studies.design.sobol import SobolStudy
from springlab.studies.design.study import Study
from springlab.studies.families import PhaseFamily, ZetaFamily
from springlab.studies.fit.results import FitResult
from springlab.studies.frequency import FrequencyResponse
from springlab.studies.friction_settings import FrictionSettings
from springlab.studies.model_sweep import ModelSweep
from springlab.studies.refine import Refinement
from springlab.studies.stability import StabilityReport
from springlab.studies.sweeps import Sweep
from springlab.studies.tradeoff import Tradeoff

from . import audit, charts, design, fit, frequency, friction_settings, refine, run, sweep

if TYPE_CHECKING:
    from matplotlib.figure import Figure


def _stability(report: StabilityReport, amplification: Any = None) -> Figure:
    if amplification is None:
        return charts.energy_figure(report.energy_histories)
    return charts.stability_figure(report, amplification)


#: result type -> the function drawing its figure (options such as a sweep's `quantity` passed on)
DRAWERS: dict[type, Callable[..., Figure]] = {
    Result: run.time_series,
    ZetaFamily: run.zeta_family,
    PhaseFamily: run.phase_family,
    Sweep: sweep.sweep_figure,
    ModelSweep: sweep.sweep_figure,
    Tradeoff: charts.tradeoff_figure,
    StabilityReport: _stability,
    FitResult: fit.fit_figure,
    Audit: audit.audit_figure,
    FrequencyResponse: frequency.bode_figure,
    Study: design.design_figure,
    SobolStudy: design.sobol_figure,
    FrictionSettings: friction_settings.friction_figure,
    Refinement: refine.refine_figure,
}


def figure(result: Any, **options: Any) -> Figure:
    """The matplotlib Figure of `result` (a result in DRAWERS).

    Parameters
    ----------
    result
        a result springlab returned.
    **options
        passed to its drawing function.

    Raises
    ------
    BadInputError
        `result` is of no type that has a figure.
    """
    for kind in type(result).__mro__:
        if kind in DRAWERS:
            return DRAWERS[kind](result, **options)
    raise BadInputError(
        f"no figure for a {type(result).__name__}; results with one: {', '.join(t.__name__ for t in DRAWERS)}"
    )
