"""What a phase plane shows and how it is framed: vector field, equilibria, separatrices and limits.

Shared by the static phase figures (`plots.run`) and the composite video's live panel (`plots.panel`).
Positions in [m] (hinges [rad]), velocities in [m/s] ([rad/s]).
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from typing import Any

import numpy as np
from matplotlib.axes import Axes

from springlab.runs.run import Result
from springlab.studies.families import separatrix_crossings

#: the vector field's arrows (light grey) and the separatrices (red dashes)
FIELD_COLOR = "0.72"
SEPARATRIX: dict[str, Any] = dict(color="C3", lw=1.1, ls=(0, (6, 3)))

#: (x, v) -> (dx/dt, dv/dt) of a scene's unforced equations of motion (Scene.phase_field)
Field = Callable[[np.ndarray, np.ndarray], tuple[np.ndarray, np.ndarray]]
#: separatrix branches as (x, v) arrays
Curves = list[tuple[np.ndarray, np.ndarray]]
Limits = tuple[float, float]


def phase_limits(xs: Sequence[np.ndarray], vs: Sequence[np.ndarray], pad: float = 0.12) -> list[Limits]:
    """[(x low, x high), (v low, v high)] around every finite point, widened by `pad` of each span."""
    x = np.concatenate([np.ravel(a) for a in xs])
    v = np.concatenate([np.ravel(a) for a in vs])
    x, v = x[np.isfinite(x)], v[np.isfinite(v)]
    limits = []
    for values in (x, v):
        low, high = (float(values.min()), float(values.max())) if values.size else (-1.0, 1.0)
        span = high - low
        if span <= 1e-12 * max(1.0, abs(high)):
            span = max(abs(high), 1e-3)
        limits.append((low - pad * span, high + pad * span))
    return limits


def phase_extras(result: Result) -> tuple[Field | None, list[dict], Curves]:
    """(field, equilibria, separatrices) of a result's scene, or (None, [], []) for several joints."""
    if len(result.pos) != 1:
        return None, [], []
    field = result.case.phase_field()
    if field is None:
        return None, [], []
    return field, result.case.equilibria(), result.case.separatrices()


def separatrix_window(curves: Curves, center_xs: Sequence[float]) -> tuple[list[np.ndarray], list[np.ndarray]]:
    """Separatrix points worth keeping in view: those within the span of the crossings."""
    crossings = separatrix_crossings(curves) + list(center_xs)
    if not crossings or not curves:
        return [], []
    low, high = min(crossings), max(crossings)
    margin = 0.1 * max(high - low, 1e-9)
    xs, vs = [], []
    for x, v in curves:
        keep = (x >= low - margin) & (x <= high + margin)
        xs.append(x[keep])
        vs.append(v[keep])
    return xs, vs


def draw_phase_background(
    ax: Axes,
    field: Field | None,
    equilibria: list[dict],
    separatrices: Curves,
    xlim: Limits,
    vlim: Limits,
    *,
    arrows: int = 21,
) -> None:
    """Vector field (normalized arrows, grey), separatrices and equilibria on `ax` within the limits.

    An equilibrium with a "to" entry is one end of a continuum of equilibria (dry friction's stick
    zone), drawn as a thick segment of the v = 0 axis to the position "to" names.
    """
    if field is not None:
        gx, gv = np.meshgrid(np.linspace(xlim[0], xlim[1], arrows), np.linspace(vlim[0], vlim[1], int(arrows * 0.8)))
        with np.errstate(all="ignore"):
            dx, dv = field(gx, gv)
            dx, dv = np.broadcast_to(dx, gx.shape), np.broadcast_to(dv, gx.shape)
            # direction on screen: scale by the axis spans before normalizing
            sx, sv = dx / (xlim[1] - xlim[0]), dv / (vlim[1] - vlim[0])
            norm = np.hypot(sx, sv)
            norm = np.where(norm > 0, norm, 1.0)
        ax.quiver(
            gx,
            gv,
            sx / norm,
            sv / norm,
            color=FIELD_COLOR,
            angles="uv",
            pivot="mid",
            scale=arrows * 1.4,
            width=0.0035,
            headwidth=3.5,
            headlength=4,
            zorder=1,
            label="equations of motion",
        )
    for i, (x, v) in enumerate(separatrices):
        ax.plot(x, v, zorder=2, label="separatrix" if i == 0 else None, **SEPARATRIX)
    # dry friction: a continuum of equilibria, its ends given with "to" naming the other end
    zones = {tuple(sorted((e["x"], e["to"]))) for e in equilibria if "to" in e}
    for i, (low, high) in enumerate(sorted(zones)):
        ax.plot(
            [low, high],
            [0.0, 0.0],
            color="k",
            lw=3.5,
            solid_capstyle="butt",
            zorder=5,
            label="stick zone (every point at rest stays)" if i == 0 else None,
        )
        ax.plot(
            [low, high],
            [0.0, 0.0],
            "|",
            color="k",
            ms=14,
            mew=2,
            zorder=5,
            label="its ends: centres of the arcs" if i == 0 else None,
        )
    stable = [e["x"] for e in equilibria if e.get("stable") and "to" not in e]
    unstable = [e["x"] for e in equilibria if not e.get("stable") and "to" not in e]
    if stable:
        ax.plot(stable, np.zeros(len(stable)), "o", color="k", ms=7, zorder=5, label="stable equilibrium")
    if unstable:
        ax.plot(
            unstable,
            np.zeros(len(unstable)),
            "o",
            mfc="white",
            mec="k",
            mew=1.5,
            ms=7,
            zorder=5,
            label="unstable equilibrium",
        )
    ax.set_xlim(*xlim)
    ax.set_ylim(*vlim)


def phase_view(result: Result, joint: str) -> tuple[Field | None, list[dict], Curves, Limits, Limits]:
    """Everything a phase plane of one joint needs: field, equilibria, separatrices, limits."""
    field, equilibria, separatrices = phase_extras(result)
    xs = [result.pos[joint]]
    vs = [result.vel[joint]]
    if joint in result.ref_pos:
        xs.append(result.ref_pos[joint])
        vs.append(result.ref_vel[joint])
    eq_x = [e["x"] for e in equilibria]
    if eq_x:
        xs.append(np.asarray(eq_x))
        vs.append(np.zeros(len(eq_x)))
    sx, sv = separatrix_window(separatrices, eq_x)
    xlim, vlim = phase_limits(xs + sx, vs + sv)
    return field, equilibria, separatrices, xlim, vlim
