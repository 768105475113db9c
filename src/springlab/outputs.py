"""One output writer: `write(result, directory)` puts every file a result declares into `directory`.

Every command that writes a folder (`run`, `tradeoff`, `stability`, `sweep`, `design`, `audit`, `fit`,
`frequency`, `refine`, `friction-settings`, `rms`) and the demo write through `write`. A result declares
its files with `outputs()` (springlab.files.Output: the name, and the text of a JSON or CSV file); the
figures (.png) and videos (.mp4) it names are drawn here, by the drawing functions of the table below, since
the results live in layers below the plots and renderers. The files appear all at once or not at all
(springlab.files.write_all: each written to a temporary file beside it, then every one renamed; on any
error nothing is left).

>>> import springlab
>>> from springlab import outputs
>>> outputs.write(springlab.run("slider", "free", duration=0.5), "out/run")  # doctest: +SKIP
[PosixPath('out/run/trajectory.csv'), PosixPath('out/run/summary.json')]
"""

from __future__ import annotations

import dataclasses
import os
import pathlib
from collections.abc import Callable
from typing import Any, Protocol

from springlab import files
from springlab.errors import BadInputError
from springlab.runs.model_run import ModelRun
from springlab.runs.result import Result
from springlab.studies.audit.results import Audit
from springlab.studies.design.study import Study
from springlab.studies.fit.results import FitResult
from springlab.studies.frequency.results import FrequencyResponse
from springlab.studies.friction_results import FrictionSettings
from springlab.studies.model_tradeoff import ModelTradeoff
from springlab.studies.random_load import Ensemble
from springlab.studies.refine import Refinement
from springlab.studies.rms_settings import RmsSettings
from springlab.studies.stability import AmplificationMap, StabilityReport
from springlab.studies.sweeps import Sweep
from springlab.studies.tradeoff import Tradeoff


class Writable(Protocol):
    """A result that declares the files it writes (`outputs()`)."""

    def outputs(self) -> tuple[files.Output, ...]: ...


@dataclasses.dataclass(frozen=True)
class Options:
    """What some drawings need beyond their result (see `write`).

    Attributes
    ----------
    quantity
        the quantity a sweep's sweep.png shows (None: its headline quantity).
    amplification
        the amplification map stability.png draws (springlab.studies.stability.amplification_map).
    """

    quantity: str | None = None
    amplification: AmplificationMap | None = None


# the drawings import the plots here, when a file is drawn: importing springlab.outputs (every command does)
# must not load matplotlib


def _tradeoff(result: Tradeoff, path: pathlib.Path, options: Options) -> object:
    from springlab.plots import charts

    return charts.plot_tradeoff(result, path)


def _model_tradeoff(result: ModelTradeoff, path: pathlib.Path, options: Options) -> object:
    from springlab.plots import model_tradeoff

    return model_tradeoff.plot_model_tradeoff(result, path)


def _stability_map(report: StabilityReport, path: pathlib.Path, options: Options) -> object:
    from springlab.plots import charts

    if options.amplification is None:
        raise BadInputError(
            "stability.png draws the amplification map: pass amplification=springlab.studies.stability.amplification_map()"
        )
    return charts.plot_stability(report, options.amplification, path)


def _energy(report: StabilityReport, path: pathlib.Path, options: Options) -> object:
    from springlab.plots import charts

    return charts.plot_energy(report.energy_histories, path)


def _sweep(result: Sweep, path: pathlib.Path, options: Options) -> object:
    from springlab.plots import sweep

    return sweep.plot(result, path, options.quantity)


def _design(study: Study, path: pathlib.Path, options: Options) -> object:
    from springlab.plots import design

    return design.plot(study, path)


def _sobol(study: Study, path: pathlib.Path, options: Options) -> object:
    from springlab.plots import design

    assert study.sobol is not None, "a study declares sobol.png only with its Sobol indices"
    return design.plot_sobol(study.sobol, path)


def _audit(result: Audit, path: pathlib.Path, options: Options) -> object:
    from springlab.plots import audit

    return audit.plot_audit(result, path)


def _fit(result: FitResult, path: pathlib.Path, options: Options) -> object:
    from springlab.plots import fit

    return fit.plot_fit(result, path)


def _bode(result: FrequencyResponse, path: pathlib.Path, options: Options) -> object:
    from springlab.plots import frequency

    return frequency.plot_bode(result, path)


def _refine(result: Refinement, path: pathlib.Path, options: Options) -> object:
    from springlab.plots import refine

    return refine.plot_refine(result, path)


def _friction(result: FrictionSettings, path: pathlib.Path, options: Options) -> object:
    from springlab.plots import friction_settings

    return friction_settings.plot(result, path)


def _ensemble(result: Ensemble, path: pathlib.Path, options: Options) -> object:
    from springlab.plots import random_load

    return random_load.plot_ensemble(result, path)


def _rms_settings(result: RmsSettings, path: pathlib.Path, options: Options) -> object:
    from springlab.plots import random_load

    return random_load.plot_settings(result, path)


#: (result type, file name) -> the function drawing that file at the path it is given (a literal table: a
#: result type that declares a .png or .mp4 has its drawing here)
DRAWN: dict[tuple[type, str], Callable[[Any, pathlib.Path, Options], object]] = {
    (Tradeoff, "tradeoff.png"): _tradeoff,
    (ModelTradeoff, "tradeoff.png"): _model_tradeoff,
    (StabilityReport, "stability.png"): _stability_map,
    (StabilityReport, "energy.png"): _energy,
    (Sweep, "sweep.png"): _sweep,
    (Study, "design.png"): _design,
    (Study, "sobol.png"): _sobol,
    (Audit, "audit.png"): _audit,
    (FitResult, "fit.png"): _fit,
    (FrequencyResponse, "bode.png"): _bode,
    (Refinement, "refine.png"): _refine,
    (FrictionSettings, "friction_settings.png"): _friction,
    (Ensemble, "rms.png"): _ensemble,
    (RmsSettings, "rms_settings.png"): _rms_settings,
}


def _text_writer(text: str) -> Callable[[pathlib.Path], object]:
    return lambda path: path.write_text(text)


def _drawing_writer(result: Any, name: str, options: Options) -> Callable[[pathlib.Path], object]:
    # a subclass (a model file's ModelSweep is a Sweep) draws as its base unless it has its own entry
    drawing = next((DRAWN[(cls, name)] for cls in type(result).__mro__ if (cls, name) in DRAWN), None)
    if drawing is None:
        raise TypeError(f"{type(result).__name__} declares {name} but springlab.outputs.DRAWN has no drawing of it")
    return lambda path: drawing(result, path, options)


def write(
    result: Writable | Result | ModelRun,
    directory: str | os.PathLike,
    *,
    every: int = 1,
    quantity: str | None = None,
    amplification: AmplificationMap | None = None,
) -> list[pathlib.Path]:
    """Write every file `result` declares (`result.outputs()`) into `directory`: all of them, or none.

    Parameters
    ----------
    result
        a run (springlab.Result, or a model file's ModelRun: trajectory.csv, summary.json) or a study's result
        (Tradeoff, a model file's ModelTradeoff, StabilityReport,
        Sweep, design Study, Audit, FitResult, FrequencyResponse, Refinement, FrictionSettings, Ensemble,
        RmsSettings); each names its files in its `outputs()` docstring.
    directory
        the folder (created with its parents).
    every
        a run only: keep every `every`-th step in trajectory.csv (the last always), as `--record-every` [-].
    quantity
        a Sweep only: the quantity sweep.png shows (None: the scenario's headline quantity).
    amplification
        a StabilityReport only: the amplification map stability.png draws.

    Returns
    -------
    list[pathlib.Path]
        the written files, in the order the result declares them.

    Raises
    ------
    BadInputError
        a folder that cannot be created or written, an option the result does not take, a sweep's unknown
        quantity, a stability report without its amplification map.
    """
    if every != 1 and not isinstance(result, Result | ModelRun):
        raise BadInputError(f"every= thins a run's trajectory.csv; {type(result).__name__} has none")
    if quantity is not None and not isinstance(result, Sweep):
        raise BadInputError(f"quantity= chooses what sweep.png shows; {type(result).__name__} writes no sweep.png")
    if amplification is not None and not isinstance(result, StabilityReport):
        raise BadInputError(f"amplification= is stability.png's map; {type(result).__name__} writes no stability.png")
    declared = result.outputs(every=every) if isinstance(result, Result | ModelRun) else result.outputs()
    options = Options(quantity=quantity, amplification=amplification)
    writers = {
        output.name: _text_writer(output.text)
        if output.text is not None
        else _drawing_writer(result, output.name, options)
        for output in declared
    }
    return files.write_all(directory, writers)
