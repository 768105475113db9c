"""audit.png and audit.json: what `springlab audit` writes (reads an Audit, never simulates).

audit.png has three panels:
  left:   the modes, frequency [Hz] vs damping ratio, physically unstable ones in red, the fastest ringed;
  middle: per integrator, the measured stability limit [s] (bar; hatched when the nonlinear runs did not
          confirm it), the closed-form prediction (black tick) and the model's own timestep (dashed line):
          the bar's height over the line is the margin;
  right:  error vs wall time of every swept setting (log-log), the Pareto front (black), --tol (dotted),
          the model's own setting (star) and the verified recommendation (ringed).
"""

from __future__ import annotations

import pathlib

from springlab import files
from springlab.studies.audit.audit import Audit

from .charts import _COLORS, _figure, _save


def plot_audit(result: Audit, path: str | pathlib.Path) -> pathlib.Path:
    """Draw audit.png (module docstring) into `path`."""
    fig, (modes_ax, limits_ax, cost_ax) = _figure(3, (16, 5), layout="constrained")
    _modes_panel(result, modes_ax)
    _limits_panel(result, limits_ax)
    _cost_panel(result, cost_ax)
    own = result.own
    name = pathlib.Path(result.model).name if result.model.endswith((".xml", ".urdf")) else result.model
    fig.suptitle(f"audit of {name}: own setting {own.integrator} at {own.dt:g} s, tol {result.tol:g}")
    return _save(fig, path)


def _modes_panel(result: Audit, ax) -> None:
    modes = [m for m in result.linear.modes if m.kind != "rigid"]
    fastest = result.linear.fastest
    for mode in modes:
        color = "#d62728" if mode.physically_unstable else "#1f77b4"
        ax.scatter(mode.frequency_hz, mode.damping_ratio, s=20, color=color, zorder=3)
    if fastest is not None:
        ax.scatter(fastest.frequency_hz, fastest.damping_ratio, s=140, facecolors="none", edgecolors="k", zorder=4)
    rigid = sum(m.kind == "rigid" for m in result.linear.modes)
    ax.set_xscale("log") if modes else None
    ax.set_xlabel("natural frequency |lambda|/(2 pi) [Hz]")
    ax.set_ylabel("damping ratio [-] (real roots: +1 decaying, -1 growing)")
    ax.set_title(f"{len(modes)} modes (+{rigid} rigid)\nred: physically unstable, ringed: fastest", fontsize=10)
    ax.grid(True, which="both", alpha=0.3)


def _limits_panel(result: Audit, ax) -> None:
    names = list(result.stability)
    own_dt = result.own.dt
    values = []
    for index, name in enumerate(names):
        limit = result.stability[name]
        measured = limit.limit_dt_measured_s
        if measured is None:
            ax.annotate("no limit", (index, own_dt), ha="center", va="bottom", fontsize=8)
            values.append(own_dt)
            continue
        values.append(measured)
        ax.bar(index, measured, color=_COLORS.get(name, "grey"), hatch=None if limit.confirmed else "//", alpha=0.8)
        if limit.limit_dt_predicted_s is not None:
            ax.plot([index - 0.35, index + 0.35], [limit.limit_dt_predicted_s] * 2, "k-", lw=2)
        ax.annotate(f"{measured / own_dt:.3g}x", (index, measured), ha="center", va="bottom", fontsize=8)
    ax.axhline(own_dt, color="k", ls="--", lw=1, label=f"own dt = {own_dt:g} s")
    ax.set_yscale("log")
    ax.set_ylim(min(values + [own_dt]) / 3, max(values + [own_dt]) * 3)
    ax.set_xticks(range(len(names)), names)
    ax.set_ylabel("largest stable dt [s]")
    ax.set_title("stability limit: measured (bar), predicted (tick)\nhatched: not confirmed by runs", fontsize=10)
    ax.legend(loc="lower right", fontsize=8)


def _cost_panel(result: Audit, ax) -> None:
    floor = 1e-17
    for name in dict.fromkeys(r.integrator for r in result.runs):
        # (wall time [s], error [-]) of the runs that finished (a diverged run has no error)
        points = [
            (r.wall_time_s, r.error)
            for r in result.runs
            if r.integrator == name and not r.diverged and r.error is not None
        ]
        if not points:
            continue
        order = result.orders.get(name)
        label = f"{name} (order {order:.2f})" if order is not None else name
        ax.loglog(
            [wall for wall, _ in points],
            [max(error, floor) for _, error in points],
            marker="o",
            ms=3,
            color=_COLORS.get(name, "grey"),
            label=label,
        )
    front = [(r.wall_time_s, r.error) for r in result.pareto if r.error is not None]
    if front:
        ax.loglog([wall for wall, _ in front], [max(error, floor) for _, error in front], "k-", lw=2, alpha=0.4)
    ax.axhline(result.tol, color="k", ls=":", lw=1, label=f"tol {result.tol:g}")
    own = result.own
    if own.error is not None:
        where = (own.wall_time_s, max(own.error, floor))
        ax.scatter(*where, marker="*", s=200, color="gold", edgecolors="k", zorder=5)
        ax.annotate(" own setting", where, fontsize=8)
    pick = result.recommendation
    if pick.integrator is not None and pick.dt is not None and pick.error is not None:
        ax.scatter(pick.wall_time_s, max(pick.error, floor), s=200, facecolors="none", edgecolors="k", zorder=5)
        ax.annotate(f" {pick.integrator} {pick.dt:.3g} s", (pick.wall_time_s, max(pick.error, floor)), fontsize=8)
    ax.set_xlabel("wall time [s] (steps x measured cost per step, one thread)")
    ax.set_ylabel(f"error vs {result.reference.kind} [-]")
    ax.set_title(f"error vs cost over {result.duration:g} s\nblack: Pareto front", fontsize=10)
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=8)


def write_audit(result: Audit, directory: str | pathlib.Path) -> list[pathlib.Path]:
    """Write DIR/audit.json and DIR/audit.png; both appear, or neither does."""
    written = files.write_text_files(directory, {"audit.json": files.dumps(result.to_dict()) + "\n"})
    try:
        written.append(plot_audit(result, pathlib.Path(directory) / "audit.png"))
    except BaseException:
        for path in written:
            path.unlink(missing_ok=True)
        raise
    return written
