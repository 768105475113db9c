"""audit.png and audit.json: what `springlab audit` writes (reads an Audit, never simulates).

audit.png has three panels:
  left:   the modes, frequency [Hz] vs damping ratio, physically unstable ones in red, the fastest ringed;
          titled with the same count as the text (`Audit.mode_count`); readable at any number of modes
          (a log axis padded to at least a decade, labels on major ticks only);
  middle: per integrator, the audit's stability limit [s] (bar, labelled with its margin; hatched and
          labelled UNCONFIRMED when runs did not confirm it; "map" or "runs" says which method gave it;
          an arrow where no run blew up up to the largest tried), the closed-form prediction (black
          tick; dashed when it is an estimate) and the model's own timestep (dashed line);
  right:  error vs counted work of every swept setting (log-log; springlab.plots.settings.error_cost_panel,
          the panel every settings study draws), the Pareto front (black steps), --tol (dashed), the model's
          own setting (star) and the verified recommendation (ringed); runs beyond a confirmed limit hollow.
"""

from __future__ import annotations

import math
import pathlib
from typing import TYPE_CHECKING

from springlab.studies.audit.results import Audit

from .charts import _COLORS, _figure, _save
from .settings import Mark, Points, error_cost_panel, legend_beside

if TYPE_CHECKING:
    from matplotlib.figure import Figure


def plot_audit(result: Audit, path: str | pathlib.Path) -> pathlib.Path:
    """Draw audit.png (module docstring) into `path`."""
    return _save(audit_figure(result), path)


def audit_figure(result: Audit) -> Figure:
    """The three panels of audit.png (module docstring)."""
    fig, (modes_ax, limits_ax, cost_ax) = _figure(3, (16, 5), layout="constrained")
    _modes_panel(result, modes_ax)
    _limits_panel(result, limits_ax)
    _cost_panel(result, cost_ax)
    own = result.own
    name = pathlib.Path(result.model).name if result.model.endswith((".xml", ".urdf")) else result.model
    fig.suptitle(f"audit of {name}: own setting {own.integrator} at {own.dt:g} s, tol {result.tol:g}")
    return fig


def _modes_panel(result: Audit, ax) -> None:
    from matplotlib.ticker import LogLocator, NullFormatter

    modes = [m for m in result.linear.modes if m.kind != "rigid"]
    fastest = result.linear.fastest
    for mode in modes:
        color = "#d62728" if mode.physically_unstable else "#1f77b4"
        ax.scatter(mode.frequency_hz, mode.damping_ratio, s=20, color=color, zorder=3)
    if fastest is not None:
        ax.scatter(fastest.frequency_hz, fastest.damping_ratio, s=140, facecolors="none", edgecolors="k", zorder=4)
    if modes:
        low = min(m.frequency_hz for m in modes)
        high = max(m.frequency_hz for m in modes)
        pad = max(math.sqrt(10 * low / high), 1.0)  # at least a decade shown, centred on the modes
        ax.set_xscale("log")
        ax.set_xlim(low / pad / 1.5, high * pad * 1.5)
        ax.xaxis.set_major_locator(LogLocator(base=10, numticks=6))
        ax.xaxis.set_minor_formatter(NullFormatter())  # minor labels overlap on a narrow range
    ax.set_ylim(-1.15, 1.15)
    ax.set_xlabel("natural frequency |lambda|/(2 pi) [Hz]")
    ax.set_ylabel("damping ratio [-] (real roots: +1 decaying, -1 growing)")
    ax.set_title(f"{result.mode_count}\nred: physically unstable, ringed: fastest", fontsize=10)
    ax.grid(True, which="both", alpha=0.3)


def _limits_panel(result: Audit, ax) -> None:
    names = list(result.stability)
    own_dt = result.own.dt
    values = [own_dt]
    for index, name in enumerate(names):
        limit = result.stability[name]
        figure = limit.limit_dt_s
        method = {"linear map": "map", "nonlinear runs": "runs"}.get(limit.method, "")
        if limit.limit_dt_predicted_s is not None:
            values.append(limit.limit_dt_predicted_s)
            style = "-" if limit.prediction == "exact" else "--"
            ax.plot([index - 0.35, index + 0.35], [limit.limit_dt_predicted_s] * 2, "k", ls=style, lw=2)
        if figure is None:
            bounded = limit.runs_bounded_dt_s
            if bounded is not None and limit.runs_blew_up_dt_s is None:
                values.append(bounded)
                ax.annotate(
                    "", (index, bounded * 2), (index, bounded), arrowprops={"arrowstyle": "->", "color": "grey"}
                )
                ax.annotate(f"none up to\n{bounded:.3g} s", (index, bounded), ha="center", va="top", fontsize=7)
            elif limit.runs_blew_up_dt_s is not None:
                values.append(limit.runs_blew_up_dt_s)
                ax.annotate(
                    f"blew up\nat {limit.runs_blew_up_dt_s:.3g} s",
                    (index, limit.runs_blew_up_dt_s),
                    ha="center",
                    va="top",
                    fontsize=7,
                    color="#d62728",
                )
            else:
                ax.annotate("no limit", (index, own_dt), ha="center", va="bottom", fontsize=8)
            continue
        values.append(figure)
        confirmed = bool(limit.confirmed)
        ax.bar(
            index,
            figure,
            color=_COLORS.get(name, "grey"),
            hatch=None if confirmed else "//",
            alpha=0.8 if confirmed else 0.35,
        )
        label = f"{figure / own_dt:.3g}x {method}" if confirmed else f"UNCONFIRMED\n{method}"
        ax.annotate(label, (index, figure), ha="center", va="bottom", fontsize=7)
    ax.axhline(own_dt, color="k", ls="--", lw=1, label=f"own dt = {own_dt:g} s")
    ax.set_yscale("log")
    ax.set_ylim(min(values) / 3, max(values) * 6)
    ax.set_xticks(range(len(names)), names, rotation=20)
    ax.set_xlim(-0.6, len(names) - 0.4)
    ax.set_ylabel("largest stable dt [s]")
    ax.set_title(
        "stability limit (bar: margin; map or runs) and prediction (tick; dashed: estimate)\n"
        "hatched: UNCONFIRMED, never used for a verdict",
        fontsize=9,
    )
    legend_beside(ax, 8)


def _cost_panel(result: Audit, ax) -> None:
    """Error against counted work (springlab.plots.settings.error_cost_panel, as tradeoff.png and refine.png
    draw it), with the model's own setting and the verified recommendation marked."""
    groups = []
    for name in dict.fromkeys(r.integrator for r in result.runs):
        order = result.orders.get(name)
        label = f"{name} (order {order:.2f})" if order is not None else name
        rows = [r for r in result.runs if r.integrator == name]
        groups.append(Points(rows, label, dict(marker="o", ms=3, ls="-", color=_COLORS.get(name, "grey"))))
    marks = []
    own = result.own
    if own.error is not None and math.isfinite(own.cost):
        marks.append(
            Mark(
                own.cost,
                own.error,
                f"own setting: {own.integrator}, dt = {own.dt:g} s",
                dict(marker="*", ms=14, color="gold", markeredgecolor="black"),
            )
        )
    pick = result.recommendation
    if pick.found and pick.cost is not None and pick.error is not None:
        marks.append(
            Mark(
                pick.cost,
                pick.error,
                f"cheapest within tol: {pick.integrator}, dt = {pick.dt:.3g} s (verified)",
                dict(marker="o", ms=14, mfc="none", mec="black", mew=1.5),
            )
        )
    error_cost_panel(
        ax,
        groups,
        result.pareto,
        marks=marks,
        tol=result.tol,
        ylabel=f"error vs {result.reference.kind} [-]",
        title=f"error vs cost over {result.duration:g} s (counted work: steps x evaluations)",
    )
    low, high = ax.get_ylim()
    if high > 1e3:  # a run that left the physics (error 1e30) would flatten every other curve
        ax.set_ylim(low, 1e3)
        ax.annotate("errors above 1e3 off the top", (0.02, 0.97), xycoords="axes fraction", fontsize=7, va="top")
