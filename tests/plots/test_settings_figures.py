"""The settings studies' figures show only what is valid and say what the data show (issue 34 item 4).

tradeoff.png, refine.png and friction_settings.png draw their error-vs-cost panel with one function
(springlab.plots.settings.error_cost_panel). Rendered here, each legend must cover no marked point, no axis
label and no other axes; a run beyond its stability limit is drawn apart from the valid runs, never as one of
them; and friction_settings.png's model-error titles follow the curves: `incline_slide`'s RK4 error still
falls as dt shrinks, so its title says so (it said "flat as dt -> 0" for every case).
"""

from __future__ import annotations

import numpy as np
import pytest

from helpers.figures import assert_legends_clear
from helpers.timing import constant_time_run
from springlab.plots import charts
from springlab.plots import friction_settings as friction_chart
from springlab.plots import refine as refine_chart
from springlab.plots.settings import BEYOND_STYLE
from springlab.scenes import get
from springlab.studies import refine, tradeoff
from springlab.studies.friction_settings import friction_settings

SPEC = get("friction").dry_friction
ENDS = {s.name: (s.mujoco_default, s.values[-1]) for s in SPEC.settings}


@pytest.fixture(scope="module")
def incline_slide():
    """The slide on the incline at each setting's two ends, euler and rk4 at three timesteps, picks for 2e-2."""
    return friction_settings(
        "friction", ["incline_slide"], tol=2e-2, integrators=("euler", "rk4"), dts=(2e-3, 1e-3, 5e-4), values=ENDS
    )


def _points(axis, label_start: str) -> list[tuple[float, float]]:
    out = []
    for line in axis.get_lines():
        if line.get_label().startswith(label_start):
            out += list(zip(*line.get_data()))
    return out


def test_the_tradeoff_figure_keeps_its_legends_clear_of_the_marked_points(monkeypatch):
    # no run timed again alone (helpers/timing.py): the figure draws error against counted work, no time
    monkeypatch.setattr(tradeoff, "time_run", constant_time_run)
    result = tradeoff.tradeoff("slider", "free", tol=1e-4, duration=0.5)
    figure = charts.tradeoff_figure(result)
    assert assert_legends_clear(figure) > len(result.runs)
    star = _points(figure.axes[1], "tol 0.0001: ")
    assert star == [(result.recommendation.cost, result.recommendation.error)]


def test_the_refine_figure_draws_a_run_beyond_its_limit_apart_and_keeps_its_legends_clear():
    study = refine.refine("drill_string", tol=0.2, sizes=(4, 8), integrators=("euler", "rk4"))
    figure = refine_chart.refine_figure(study)
    assert_legends_clear(figure)
    error_cost = figure.axes[0]
    beyond = [r for r in study.runs if r.beyond_limit and not r.diverged and r.error_bound is not None]
    assert any(r.dt == 1.0 and r.size == 4 and r.integrator == "euler" for r in beyond)
    hollow = _points(error_cost, "beyond the stability limit")
    assert sorted(hollow) == sorted((r.cost, r.error_bound) for r in beyond)
    assert next(line for line in error_cost.get_lines() if line.get_label().startswith("beyond")).get_mfc() == "none"
    assert BEYOND_STYLE["mfc"] == "none"
    front = _points(error_cost, "Pareto front")
    assert (beyond[0].cost, beyond[0].error_bound) not in front
    # the valid runs' points are exactly the valid runs: no beyond-limit run among them
    valid = [p for line in error_cost.get_lines() if line.get_label().startswith("_") for p in zip(*line.get_data())]
    assert sorted(valid) == sorted((r.cost, r.error_bound) for r in study.runs if r.run.valid)
    # the middle panel's best integration error per size and integrator comes from valid runs only
    middle = figure.axes[1]
    for name in ("euler", "rk4"):
        (line,) = [line for line in middle.get_lines() if line.get_label() == f"{name}: best integration error"]
        best = {
            size: min(r.integration_error for r in study.runs if (r.size, r.integrator) == (size, name) and r.run.valid)
            for size in (4, 8)
        }
        assert dict(zip(*line.get_data())) == best


def test_the_friction_titles_follow_the_data_and_the_legends_stay_clear(incline_slide):
    case = incline_slide.cases[0]
    figure = friction_chart.friction_figure(incline_slide)
    assert_legends_clear(figure)
    _, dt_panel = figure.axes[:2]
    title = dt_panel.get_title()
    # read off the drawn curves: a curve is flat when its two smallest timesteps agree within CONVERGED
    curves = [line for line in dt_panel.get_lines() if not line.get_label().startswith(("_", "tol"))]
    assert curves
    flat = {}
    for line in curves:
        dts, errors = line.get_data()
        finest = np.argsort(dts)[:2]
        flat[line.get_label().split(":")[0]] = abs(errors[finest[1]] - errors[finest[0]]) <= 0.1 * errors[finest[0]]
    # the slide accelerates: RK4's error at MuJoCo's defaults still falls with dt (0.0055 -> 0.0046 at 1, 0.5 ms)
    assert not flat["MuJoCo's defaults"] and case.default_model is not None and not case.default_model.converged
    assert "still falling" in title and title != "flat as dt → 0: what is left is MuJoCo's model error"
    if all(not f for f in flat.values()):
        assert title.startswith("still falling as dt → 0")
    # the legend names the defaults once, not "MuJoCo's defaults: MuJoCo's defaults"
    assert "MuJoCo's defaults" in [line.get_label() for line in curves]


def test_a_flat_model_error_is_titled_flat():
    values = {**ENDS, "noslip_iterations": (0.0,)}
    study = friction_settings("friction", ["coulomb_decay"], integrators=("rk4",), dts=(1e-3, 5e-4), values=values)
    figure = friction_chart.friction_figure(study)
    case = study.cases[0]
    assert case.default_model.converged and case.best_model.converged  # the joint decay's model error is flat
    assert figure.axes[1].get_title() == "flat as dt → 0: what is left is MuJoCo's model error"


def test_the_sweep_figure_draws_a_configuration_that_failed_its_check_apart():
    """rk4 at 10 ms over the slider's stiffness: the stiffest configuration (omega dt = 0.71) misses its
    tolerance; it is a hollow grey circle labelled not valid, off the curve of the valid ones."""
    from springlab.plots import sweep as sweep_chart
    from springlab.studies.sweeps import sweep

    result = sweep(
        "slider", "free", vary={"stiffness": (50.0, 5000.0, 7, "log")}, integrator="rk4", dt=0.01, duration=0.5
    )
    failed = [i for i, row in enumerate(result.rows) if row.passed is False and not row.diverged]
    assert failed and len(failed) < result.size
    figure = sweep_chart.sweep_figure(result, "max_displacement_m")
    assert_legends_clear(figure)
    axis = figure.axes[0]
    (curve,) = [line for line in axis.get_lines() if line.get_label() == "max_displacement_m"]
    (apart,) = [line for line in axis.get_lines() if line.get_label().startswith("failed its check")]
    stiffness = result.values["stiffness"]
    assert sorted(curve.get_xdata()) == sorted(stiffness[i] for i in range(result.size) if i not in failed)
    assert list(apart.get_xdata()) == [stiffness[i] for i in failed] and apart.get_mfc() == "none"
