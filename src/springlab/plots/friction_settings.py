"""The friction-settings study drawn, and its files written: error vs cost per case, model error vs timestep.

Reads a springlab.studies.friction_settings.FrictionSettings and never simulates. One row of two
log-log panels per case:

* error vs CPU time of every run (grey), the Pareto front (black steps), MuJoCo's defaults (red
  square), the verified pick for the tolerance (gold star) and the tolerance (dashed);
* error vs timestep for RK4 at three settings (MuJoCo's defaults, the pick's, the best model),
  flattening as dt -> 0: what is left there is MuJoCo's model error, not the integration's.
"""

from __future__ import annotations

import pathlib
from typing import TYPE_CHECKING

import numpy as np

from springlab import files
from springlab.studies.friction_settings import MODEL_INTEGRATOR, CaseStudy, FrictionSettings, ModelError

from .style import new_figure, styled

if TYPE_CHECKING:
    from matplotlib.figure import Figure

#: drawn instead of an error of exactly 0 on a log axis (NoSlip can make a creep vanish) [-]
FLOOR = 1e-12


def _shown(value: float) -> float:
    return max(value, FLOOR)


def _case_panels(case: CaseStudy, cost_ax, dt_ax, tol: float | None) -> None:
    runs = [r for r in case.runs if not r.diverged]
    cost_ax.loglog(
        [r.cpu_time_s for r in runs], [_shown(r.error) for r in runs], ".", ms=2.5, color="0.65", label="every run"
    )
    front = case.pareto
    cost_ax.step(
        [r.cpu_time_s for r in front],
        [_shown(r.error) for r in front],
        where="post",
        color="k",
        lw=1.1,
        label="Pareto front",
    )
    if case.default is not None:
        cost_ax.plot(
            [case.default.cpu_time_s],
            [_shown(case.default.error)],
            "s",
            ms=7,
            color="C3",
            label=f"MuJoCo's defaults ({case.default.integrator}, dt = {case.default.dt:g} s)",
        )
    if tol is not None:
        cost_ax.axhline(tol, color="0.4", lw=0.8, ls="--", label=f"tol {tol:g}")
    pick = case.pick
    if pick is not None and pick.run is not None:
        cost_ax.plot(
            [pick.run.cpu_time_s],
            [_shown(pick.run.error)],
            "*",
            ms=14,
            color="gold",
            markeredgecolor="k",
            label=f"cheapest for tol: {pick.run.integrator}, dt = {pick.run.dt:g} s",
        )
    cost_ax.set_xlabel("CPU time of the run [s]")
    cost_ax.set_ylabel("max relative error [-]")
    cost_ax.set_title(f"{case.scenario}: error vs cost ({len(case.runs)} runs)", fontsize=9)
    cost_ax.legend(fontsize=6.5, loc="lower left")
    shown: list[tuple[ModelError, str]] = []
    for label, model, style in (
        ("MuJoCo's defaults", case.default_model, "C3"),
        ("the pick's settings", _pick_model(case), "goldenrod"),
        ("best model", case.best_model, "C2"),
    ):
        if model is None or any(m is model for m, _ in shown):
            continue
        points = [(d, e) for d, e in zip(model.dts, model.errors) if e is not None]
        if not points:
            continue
        shown.append((model, label))
        dt_ax.loglog(
            [d for d, _ in points],
            [_shown(e) for _, e in points],
            "o-",
            ms=4,
            color=style,
            label=f"{label}: {case.describe(model.settings)}",
        )
    if tol is not None:
        dt_ax.axhline(tol, color="0.4", lw=0.8, ls="--")
    dt_ax.set_xlabel("timestep dt [s]")
    dt_ax.set_ylabel(f"max relative error of {MODEL_INTEGRATOR} [-]")
    dt_ax.set_title("flat as dt -> 0: MuJoCo's model error", fontsize=9)
    if dt_ax.get_legend_handles_labels()[0]:  # no curve: no model error measured (MODEL_INTEGRATOR not swept)
        dt_ax.legend(fontsize=6.5, loc="best")
    for axis in (cost_ax, dt_ax):
        axis.grid(True, which="both", alpha=0.3)


def _pick_model(case: CaseStudy) -> ModelError | None:
    if case.pick is None or case.pick.run is None:
        return None
    return next((m for m in case.model_errors if m.settings == case.pick.run.settings), None)


@styled
def plot(study: FrictionSettings, path: str | pathlib.Path) -> pathlib.Path:
    """Write the study's figure (see the module docstring) to `path` (.png); return the path."""
    figure = friction_figure(study)
    path = pathlib.Path(path)
    files.prepare_directory(path.parent)
    with files.atomic_path(path) as temporary:
        figure.savefig(temporary, format="png")
    return path


@styled
def friction_figure(study: FrictionSettings) -> Figure:
    """The study's figure (see the module docstring): per case, error vs cost and error vs dt."""
    figure = new_figure(11.0, 3.4 * len(study.cases) + 0.6)
    axes = figure.subplots(len(study.cases), 2, squeeze=False)
    for case, (cost_ax, dt_ax) in zip(study.cases, axes):
        _case_panels(case, cost_ax, dt_ax, study.tol)
    figure.suptitle(f"{study.scene}: MuJoCo's friction settings, error vs cost ({study.runs} runs)")
    return figure


def write(study: FrictionSettings, directory: str | pathlib.Path) -> list[pathlib.Path]:
    """Write DIR/friction_settings.json (the study), DIR/friction_settings.csv (one row per run) and
    DIR/friction_settings.png; return their paths."""
    rows = [r.row() for case in study.cases for r in case.runs]
    names = list(dict.fromkeys(name for row in rows for name in row))
    lines = [",".join(names)] + [",".join(_cell(row.get(name)) for name in names) for row in rows]
    written = files.write_text_files(
        directory,
        {
            "friction_settings.json": files.dumps(study.to_dict()) + "\n",
            "friction_settings.csv": "\n".join(lines) + "\n",
        },
    )
    written.append(plot(study, pathlib.Path(directory) / "friction_settings.png"))
    return written


def _cell(value) -> str:
    if value is None:
        return ""
    if isinstance(value, (bool, np.bool_)):
        return str(bool(value)).lower()
    if isinstance(value, (float, np.floating)):  # np.float64's own repr is `np.float64(0.1)` under numpy 2
        return files.number_text(value)
    return str(value)
