"""What a fit reports: intervals, derived quantities, the closed-form cross-check, the verdict, fit.json.

Intervals are `mujoco.sysid.calculate_intervals`' (linearized, Student t on
n - p degrees of freedom, noise variance from the residual). Derived
quantities get theirs by the delta method: g^T Sigma g with g the gradient of
the derived quantity in the fitted parameters (central differences, relative
step 1e-6: error ~1e-12 on these smooth closed forms).
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping
from typing import TYPE_CHECKING, Any

import numpy as np

from springlab.exact import analytic

if TYPE_CHECKING:  # annotations only
    from .engine import Problem
    from .models import SceneFit

#: units of derived quantities
DERIVED_UNITS = {
    "omega_n_rad_s": "rad/s",
    "damping_ratio": "-",
    "natural_frequency_hz": "Hz",
    "damped_frequency_rad_s": "rad/s",
    "damped_period_s": "s",
    "stiffness": "N/m",
    "damping": "N s/m",
    "mass": "kg",
    "belt_stiffness": "N/m",
    "belt_damping": "N s/m",
}


def interval(value: float, half: float) -> list[float]:
    """[low, high] of value +- half."""
    return [value - half, value + half]


def derived_quantities(how: SceneFit, problem: Problem, values: dict[str, float]) -> dict[str, float]:
    """Named results computed from the fitted values (SI)."""
    params = how.scene_params(values, problem.base, problem.modal)
    if how.scene == "kinematics":
        return {
            "cubic_coefficient_m_s3": values["jerk"] / 6,
            "quadratic_coefficient_m_s2": values["a0"] / 2,
            "linear_coefficient_m_s": values["v0"],
            "constant_m": values["x0"],
        }
    m, k, d = how.mode_mass(params), params[how.stiffness], params[how.damping]
    out = {
        "omega_n_rad_s": math.sqrt(k / m),
        "damping_ratio": d / (2 * math.sqrt(k * m)),
        "natural_frequency_hz": math.sqrt(k / m) / (2 * math.pi),
        how.stiffness: k,
        how.damping: d,
    }
    if how.mass:
        out[how.mass] = m
    if out["damping_ratio"] < 1:
        omega_d = out["omega_n_rad_s"] * math.sqrt(1 - out["damping_ratio"] ** 2)
        out["damped_frequency_rad_s"] = omega_d
        out["damped_period_s"] = 2 * math.pi / omega_d
    return out


def gradient(function: Callable[[np.ndarray], Mapping[str, float]], x: np.ndarray) -> dict[str, np.ndarray]:
    """Central-difference gradients of every entry of function(x) (a dict of floats) in x."""
    columns = []
    for i in range(x.size):
        h = 1e-6 * max(abs(x[i]), 1e-8)
        up, down = x.copy(), x.copy()
        up[i] += h
        down[i] -= h
        fu, fd = function(up), function(down)
        columns.append({k: (fu[k] - fd[k]) / (2 * h) for k in fu})
    return {k: np.array([c[k] for c in columns]) for k in columns[0]} if columns else {}


def delta_intervals(
    function: Callable[[np.ndarray], Mapping[str, float]], x: np.ndarray, covariance: np.ndarray, t_quantile: float
) -> dict[str, dict[str, Any]]:
    """name -> {'value', 'ci95', 'unit'} of derived quantities by the delta method."""
    center = function(x)
    grads = gradient(function, x)
    out = {}
    for name, value in center.items():
        g = grads[name]
        half = float(t_quantile * math.sqrt(max(g @ covariance @ g, 0.0)))
        out[name] = {"value": value, "ci95": interval(value, half), "unit": DERIVED_UNITS.get(name, _poly_unit(name))}
    return out


def _poly_unit(name: str) -> str:
    for suffix, unit in (("_m_s3", "m/s^3"), ("_m_s2", "m/s^2"), ("_m_s", "m/s"), ("_m", "m")):
        if name.endswith(suffix):
            return unit
    return "-"


def cross_check(problem: Problem, x: np.ndarray, half_widths: np.ndarray, fitted: np.ndarray) -> dict[str, Any]:
    """The closed form (springlab.analytic) fitted independently with scipy, and how far MuJoCo's fit is from it."""
    how, record = problem.how, problem.record
    t = record.model_time

    def closed(vector):
        values = problem.values(vector)
        params = how.scene_params(values, problem.base, problem.modal)
        return how.closed_form(t, params, values, record.signal, problem.force)

    def residual(vector):
        return (closed(vector) - record.values) / problem.scale

    start = np.array([problem.start[n] for n in problem.free])
    bounds = np.array([how.bounds(n, problem.start[n], record) for n in problem.free]).T
    import scipy.optimize  # here, not at module top: it adds ~0.3 s to every command's start-up

    solution = scipy.optimize.least_squares(
        residual, start, bounds=(bounds[0], bounds[1]), x_scale="jac", xtol=1e-15, ftol=1e-15, gtol=1e-15
    )
    relative = np.abs(solution.x - x) / np.maximum(np.abs(x), 1e-300)
    in_halfwidths = np.abs(solution.x - x) / np.where(half_widths > 0, half_widths, np.inf)
    model_gap = float(np.max(np.abs(closed(x) - fitted)))
    amplitude = float(np.ptp(record.values)) or 1.0
    return {
        "method": "closed form (springlab.analytic) fitted independently with scipy.optimize.least_squares",
        "estimates": dict(zip(problem.free, solution.x.tolist())),
        "max_relative_difference": float(np.max(relative)),
        "max_difference_in_ci95_halfwidths": float(np.max(in_halfwidths)),
        "mujoco_vs_closed_form_at_estimate": model_gap / amplitude,
        "agrees": bool(np.max(in_halfwidths) < 0.01 or np.max(relative) < 1e-6),
    }


def t_quantile(dof: int) -> float:
    """Two-sided 95 % Student t quantile for `dof` degrees of freedom."""
    import scipy.stats  # here, not at module top: it adds ~0.5 s to every command's start-up

    return float(scipy.stats.t.ppf(0.975, max(dof, 1)))


def plus_minus(value: float, half: float, unit: str = "") -> str:
    """'18.40 +- 0.05 rad/s': the value to the precision of two significant digits of its interval."""
    unit = "" if unit in ("-", "") else f" {unit}"
    if not math.isfinite(half) or half <= 0:
        return f"{value:.6g}{unit}"
    digits = max(0, 1 - int(math.floor(math.log10(half))))
    if abs(value) >= 1e5 or (abs(value) < 1e-3 and value != 0):
        exponent = int(math.floor(math.log10(abs(value))))
        scale = 10.0**exponent
        d = max(0, 1 - int(math.floor(math.log10(half / scale))))
        return f"({value / scale:.{d}f} ± {half / scale:.{d}f})e{exponent}{unit}"
    return f"{value:.{digits}f} ± {half:.{digits}f}{unit}"


def length(value: float) -> str:
    """A length [m] in the unit that reads best (m, mm, um)."""
    magnitude = abs(value)
    if magnitude >= 0.1 or magnitude == 0:
        return f"{value:.3g} m"
    if magnitude >= 1e-4:
        return f"{value * 1e3:.3g} mm"
    return f"{value * 1e6:.3g} µm"


def verdict(result) -> str:
    """The one-line answer, e.g. 'ω_n = 18.40 ± 0.05 rad/s, ζ = 0.156 ± 0.004: underdamped; residual RMS ...'."""
    est, der, record = result.estimates, result.derived, result.record
    rms = result.residual_rms
    signal_unit = record.unit
    rms_text = length(rms) if signal_unit == "m" else f"{rms:.3g} {signal_unit}"
    amplitude = result.amplitude
    share = f" ({100 * rms / amplitude:.2g} % of the initial amplitude)" if amplitude > 0 else ""
    if result.scene == "kinematics":
        coefficients = [
            der[n]
            for n in ("cubic_coefficient_m_s3", "quadratic_coefficient_m_s2", "linear_coefficient_m_s", "constant_m")
        ]
        powers = ["t³", "t²", "t", ""]
        terms = [
            f"({plus_minus(c['value'], c['ci95'][1] - c['value'])}){(' ' + p) if p else ''}"
            for c, p in zip(coefficients, powers)
        ]
        text = "x(t) = " + " + ".join(terms) + " m"
    else:
        parts = []
        for name, symbol in (("omega_n_rad_s", "ω_n"), ("damping_ratio", "ζ")):
            q = der.get(name) or est[{"omega_n_rad_s": "omega_n", "damping_ratio": "zeta"}[name]]
            parts.append(f"{symbol} = {plus_minus(q['value'], q['ci95'][1] - q['value'], q['unit'])}")
        for name in result.free:
            if name in ("omega_n", "zeta", "x0", "v0", "offset", "delay"):
                continue
            q = est[name]
            parts.append(f"{name} = {plus_minus(q['value'], q['ci95'][1] - q['value'], q['unit'])}")
        zeta = (der.get("damping_ratio") or est["zeta"])["value"]
        m, k, d = 1.0, 1.0, 2 * zeta
        text = ", ".join(parts) + f": {analytic.regime(m, k, d) if zeta > 0 else 'undamped'}"
    status = "" if result.converged else f"; NOT CONVERGED ({result.optimizer['status']})"
    return f"{text}; residual RMS {rms_text}{share}{status}"
