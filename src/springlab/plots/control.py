"""Control figures: shapers.png (input shapers' residual vibration over a frequency error, MuJoCo's points on
the exact curves) and step_response.png (sampled loops' step responses, MuJoCo against exact).

Draws what it is given (never simulates): any objects with the attributes of `ShaperCurve` and
`StepResponse` below (a scene computes them, e.g. the printer head's figures module). Frequency errors in [%],
vibration in [%], times in [ms], positions in [mm].
"""

from __future__ import annotations

import pathlib
from collections.abc import Sequence
from typing import TYPE_CHECKING, Protocol

import numpy as np

from springlab import files

if TYPE_CHECKING:
    from matplotlib.figure import Figure

__all__ = ["ShaperCurve", "StepResponse", "shaper_figure", "step_figure", "write"]


class ShaperCurve(Protocol):
    """A shaper's robustness: exact V [-] over frequency errors [-], MuJoCo's points, the time it adds [s]."""

    @property
    def name(self) -> str: ...
    @property
    def errors(self) -> np.ndarray: ...
    @property
    def vibration(self) -> np.ndarray: ...
    @property
    def point_errors(self) -> np.ndarray: ...
    @property
    def point_vibration(self) -> np.ndarray: ...
    @property
    def duration_s(self) -> float: ...


class StepResponse(Protocol):
    """A loop's step at its sample times [s]: MuJoCo's encoder and the exact loop's [m], the set point, margins."""

    @property
    def encoder(self) -> str: ...
    @property
    def time(self) -> np.ndarray: ...
    @property
    def measured(self) -> np.ndarray: ...
    @property
    def exact(self) -> np.ndarray: ...
    @property
    def reference(self) -> float: ...
    @property
    def gain_margin_db(self) -> float: ...
    @property
    def phase_margin_deg(self) -> float: ...


def _save(fig: Figure, path: pathlib.Path) -> pathlib.Path:
    files.prepare_directory(path.parent)
    with files.atomic_path(path) as temporary:
        fig.savefig(temporary, dpi=110, format="png")
    return path


def shaper_figure(curves: Sequence[ShaperCurve]) -> Figure:
    """V [%] over the belt-frequency error [%] per shaper: the exact curve, MuJoCo's runs as points."""
    from matplotlib.figure import Figure

    fig = Figure(figsize=(7.5, 4.6), layout="constrained")
    ax = fig.add_subplot()
    for index, curve in enumerate(curves):
        color = f"C{index}"
        label = f"{curve.name.upper()} (+{curve.duration_s * 1e3:.2f} ms)"
        ax.plot(100 * curve.errors, 100 * curve.vibration, color=color, label=label)
        ax.plot(100 * curve.point_errors, 100 * curve.point_vibration, "o", color=color, markersize=5, mfc="none")
    ax.plot([], [], "o", color="0.3", mfc="none", label="MuJoCo (rk4, 0.1 ms)")
    ax.axhline(5, color="0.6", linestyle=":", linewidth=1)
    ax.set_xlabel("belt frequency error [%] (the shaper designed at the nominal belt)")
    ax.set_ylabel("residual vibration V [%] of the unshaped move's")
    ax.set_title("input shapers on a belt mode: exact V, MuJoCo's runs")
    ax.set_ylim(bottom=0)
    ax.legend(loc="upper center", fontsize=8, ncols=3)
    return fig


def step_figure(responses: Sequence[StepResponse]) -> Figure:
    """Each loop's encoder [mm] over time [ms], MuJoCo's samples on the exact sampled loop, and their difference."""
    from matplotlib.figure import Figure

    fig = Figure(figsize=(8.5, 4.6), layout="constrained")
    top, bottom = fig.subplots(2, 1, sharex=True, height_ratios=(3, 1))
    for index, response in enumerate(responses):
        color = f"C{index}"
        label = (
            f"{response.encoder} encoder (gain margin {response.gain_margin_db:.3g} dB,"
            f" phase margin {response.phase_margin_deg:.3g} deg)"
        )
        top.step(1e3 * response.time, 1e3 * response.exact, where="post", color=color, label=f"exact: {label}")
        top.plot(1e3 * response.time[::10], 1e3 * response.measured[::10], ".", color=color, markersize=4)
        bottom.plot(1e3 * response.time, np.abs(response.measured - response.exact), color=color)
    top.axhline(1e3 * responses[0].reference, color="0.6", linestyle=":", linewidth=1)
    top.plot([], [], ".", color="0.3", label="MuJoCo at the samples (every 10th)")
    top.set_ylabel("encoder [mm]")
    top.set_title("sampled loops, a step of the set point: MuJoCo against the exact sampled-data loop")
    top.legend(fontsize=8, loc="lower right")
    bottom.set_yscale("log")
    bottom.set_xlabel("time [ms]")
    bottom.set_ylabel("|MuJoCo - exact| [m]")
    return fig


def write(curves: Sequence[ShaperCurve], responses: Sequence[StepResponse], folder: pathlib.Path) -> list[pathlib.Path]:
    """shapers.png and step_response.png in `folder`."""
    return [
        _save(shaper_figure(curves), folder / "shapers.png"),
        _save(step_figure(responses), folder / "step_response.png"),
    ]
