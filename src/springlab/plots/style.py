"""The look every springlab plot shares: matplotlib style, line styles, figures and axis labels.

One home for what the static figures (`plots.run`) and the composite video's panel (`plots.panel`)
both use. Matplotlib through `matplotlib.figure.Figure` and the Agg canvas only: nothing touches
pyplot's global state, and the style is applied with `matplotlib.rc_context` around each figure,
never to the caller's global rcParams. Units follow the joint type: slide joints in [m] and
[m/s], hinges in [rad] and [rad/s].
"""

from __future__ import annotations

import functools
from collections.abc import Callable
from typing import Any, TypeVar

import matplotlib
import mujoco
from matplotlib.axes import Axes
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure

from springlab.runs.run import Result

#: line styles of the simulated and the exact curves
SIMULATED: dict[str, Any] = dict(color="C0", lw=1.6)
EXACT: dict[str, Any] = dict(color="k", lw=1.0, ls=(0, (4, 3)))

#: matplotlib settings of springlab's figures, applied with rc_context around each figure and save,
#: so the caller's (global) rcParams are never changed
STYLE: dict[str, Any] = {"font.size": 9, "axes.titlesize": 10, "savefig.dpi": 120}

F = TypeVar("F", bound=Callable[..., Any])


def styled(function: F) -> F:
    """Run `function` inside matplotlib.rc_context(STYLE): text sizes are read when artists are made.

    Parameters
    ----------
    function
        a function (or method) that makes or saves a figure.

    Returns
    -------
    The same function, wrapped.
    """

    @functools.wraps(function)
    def wrapper(*args, **kwargs):  # untyped: rc_context wants matplotlib's literal rc keys
        with matplotlib.rc_context(STYLE):
            return function(*args, **kwargs)

    return wrapper  # type: ignore[return-value]  # functools.wraps keeps the signature


def units(model: mujoco.MjModel, joint: str) -> tuple[str, str]:
    """(position unit, velocity unit) of a joint: m, m/s for slides, rad, rad/s for hinges."""
    if model.joint(joint).type[0] == mujoco.mjtJoint.mjJNT_HINGE:
        return "rad", "rad/s"
    return "m", "m/s"


def axis_labels(model: mujoco.MjModel, joint: str) -> tuple[str, str]:
    """(position axis label, velocity axis label): the quantity and its unit, e.g. 'position x [m]'."""
    if model.joint(joint).type[0] == mujoco.mjtJoint.mjJNT_HINGE:
        return "angle θ [rad]", "angular velocity ω [rad/s]"
    return "position x [m]", "velocity v [m/s]"


def title(result: Result) -> str:
    """'scene / scenario', the start of every figure's title."""
    return f"{result.scene} / {result.scenario}"


def legend_outside(ax: Axes) -> None:
    """Legend to the right of the axes, so it never hides an equilibrium or an orbit."""
    ax.legend(loc="upper left", bbox_to_anchor=(1.02, 1.0), fontsize=7, borderaxespad=0.0)


def new_figure(width: float, height: float) -> Figure:
    """A constrained-layout Figure of `width` x `height` [inches] on its own Agg canvas."""
    figure = Figure(figsize=(width, height), layout="constrained")
    FigureCanvasAgg(figure)
    return figure
