"""The human-readable answers of the commands run on a model file (`run`, `sweep`, `tradeoff` MODEL.xml).

Like springlab.cli.text, this module only formats what the library returned; a model file has no exact
solution, so every answer here says what it was measured against.
"""

from __future__ import annotations

import pathlib
from typing import TYPE_CHECKING

import numpy as np

if TYPE_CHECKING:  # annotations only: the commands import the studies lazily
    from springlab.runs.model_run import ModelRun
    from springlab.studies.model_sweep import ModelSweep
    from springlab.studies.model_tradeoff import ModelTradeoff


def print_model_run(run: ModelRun, output: str | None) -> None:
    """`springlab run MODEL.xml`: the setting, what the motion measured, and that nothing was validated."""
    print(run.question_answer.text())
    print(
        f"{run.model_path} from {run.start.label}: {run.integrator}, dt = {run.dt:g} s,"
        f" {run.steps} steps ({run.duration:g} s) in {run.wall_time_s * 1e3:.1f} ms"
    )
    for name, value in run.measures.items():
        print(f"  {name:<32} {value:.10g}")
    print(f"  {run.verdict}: {run.message}")
    if output:
        print(f"  wrote {pathlib.Path(output) / 'trajectory.csv'} ({len(run.columns)} columns) and summary.json")


def print_model_sweep(result: ModelSweep, quantity: str, output: str | None) -> None:
    """`springlab sweep MODEL.xml`: the configurations run, how many blew up, and the range of `quantity`."""
    print(result.question_answer.text())
    print(
        f"{result.scene} from {result.scenario}: {result.size} configurations ({result.integrator},"
        f" dt = {result.dt:g} s unless varied, {result.duration:g} s each) in {result.wall_time_s:.2f} s on"
        f" {result.executor}"
    )
    print(
        f"  diverged {result.diverged} of {result.size}; measured, not validated (a model file has no exact solution)"
    )
    values = result.column(quantity)
    finite = values[np.isfinite(values)]
    if finite.size:
        low, high = (
            int(np.nanargmin(np.where(np.isfinite(values), values, np.nan))),
            int(np.nanargmax(np.where(np.isfinite(values), values, np.nan))),
        )
        where = {i: ", ".join(f"{n} = {result.values[n][i]:.4g}" for n in result.values) for i in (low, high)}
        print(f"  {quantity}: min {finite.min():.4g} (at {where[low]}), max {finite.max():.4g} (at {where[high]})")
    else:
        print(f"  {quantity}: no configuration measured it")
    if output:
        print(f"  wrote {pathlib.Path(output) / 'sweep.csv'} and sweep.png")


def print_model_tradeoff(result: ModelTradeoff, output: str | None) -> None:
    """`springlab tradeoff MODEL.xml`: what the errors are against (first, always), the model's own setting, the
    Pareto front and the recommendation."""
    print(result.question_answer.text())
    from springlab.studies.model_tradeoff import REFERENCE_NOTE

    reference = result.reference
    converged = (
        "converged"
        if result.converged
        else "NOT converged: errors near its own are not resolved (contacts cost RK4 its order)"
    )
    print(
        f"{result.model} from {result.start}: {len(result.runs)} runs over {result.duration:g} s, each against RK4 at"
        f" dt = {reference.dt:.3g} s ({converged}; its own estimated error {reference.error_estimate:.2g})"
    )
    print(f"  {REFERENCE_NOTE}")
    own = result.own
    mine = "diverged" if own.diverged else f"error {own.error:.3g}, counted work {own.cost:.4g}"
    print(f"  your setting, {own.integrator} at {own.dt:g} s: {mine}")
    print(f"  {'integrator':<13}{'dt [s]':>11}{'error [-]':>12}{'work':>12}   (Pareto front: cheapest for its error)")
    for run in result.pareto:
        print(f"  {run.integrator:<13}{run.dt:>11.4g}{run.error or 0.0:>12.3g}{run.cost:>12.4g}")
    orders = ", ".join(f"{name} {order:.2f}" for name, order in result.orders.items() if order is not None)
    if orders:
        print(f"  observed orders: {orders}")
    diverged = sum(run.diverged for run in result.runs)
    if diverged:
        print(f"  {diverged} of {len(result.runs)} runs diverged")
    if result.recommendation is not None:
        print(f"  {result.recommendation.text}")
    if output:
        print(f"  wrote {pathlib.Path(output) / 'tradeoff.json'} and tradeoff.png")
