"""What a fit reports: the result (`FitResult`), intervals, derived quantities, the closed-form cross-check,
the verdict.

Intervals are `mujoco.sysid.calculate_intervals`' (linearized, Student t on
n - p degrees of freedom, noise variance from the residual). Derived
quantities get theirs by the delta method: g^T Sigma g with g the gradient of
the derived quantity in the fitted parameters (central differences, relative
step 1e-6: error ~1e-12 on these smooth closed forms).
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Callable, Mapping
from typing import TYPE_CHECKING, Any

import numpy as np

from springlab import display, files, tables
from springlab.answer import Answer
from springlab.exact import analytic
from springlab.files import Output
from springlab.runs import compare
from springlab.studies import answers

from . import reductions
from .data import Record
from .models import POWER_TERMS

if TYPE_CHECKING:  # annotations only
    import pandas
    from matplotlib.figure import Figure

    from springlab.runs.run import Result

    from .engine import Problem

#: t^n as the verdict writes it
POWERS = ("", "t", "t²", "t³")
#: the closed-form cross-check allows this share of an estimate's 95 % half-width (plus its numerical accuracy)
CROSS_IN_HALFWIDTHS = 0.01
#: the Gauss-Newton step a converged fit may still have open, in standard errors of each estimate [-]
STEP_IN_SE = 0.1


@dataclasses.dataclass(frozen=True, eq=False, repr=False)  # arrays: compare fields, not results
class FitResult(display.Shown):
    """An identified scene, built once and immutable (its arrays are read-only).

    Attributes
    ----------
    scene, scenario
        What was fitted.
    kind
        The kind of fit the scene declares: 'oscillator' or 'polynomial' (springlab.scenes.capabilities).
    record
        The cleaned record (springlab.studies.fit.data.Record).
    free
        Fitted names, in order.
    estimates
        Name -> {'value', 'ci95' [low, high], 'unit'}.
    derived
        The same for quantities computed from the estimates.
    correlation
        (p, p) correlation matrix of the estimates.
    covariance
        (p, p) covariance [units of the names].
    residual_rms
        RMS of measured - fitted [signal unit].
    dof
        Degrees of freedom n - p.
    parameters
        The scene's parameters at the estimate (SI).
    fitted
        (n,) the fitted signal at the recorded times.
    cross_check
        The closed form fitted independently, and how far it is.
    optimizer
        Status, iterations, rollouts, times.
    converged
        Whether the solution converged (`convergence`; `success`, as scipy calls it): judged on the solution,
        not on the optimizer's message (`message`).
    run
        The identified scene's own run (springlab.runs.run.Result), or None.
    run_note
        What the run leaves out, or why there is none ('' if nothing).
    curves
        A polynomial's x(t), v(t), a(t) with 95 % half-widths over the record (empty for an oscillator).
    amplitude
        The motion's size in the fitted signal [signal unit] (about its rest level, or its range).
    starts
        The multi-start record (springlab.studies.fit.starts.starts_entry): count, best, at_best_minimum, spread.
    convergence
        Whether the solution converged, and why (`convergence`): the remaining Gauss-Newton step, the
        cross-check, the optimizer's message.
    timestep
        The simulation grid and why (`timestep`): dt_s, steps, rule, error_bound, measured_error, ...
    release
        Where the motion starts and why (springlab.studies.fit.release.Release.to_dict): decision, start_s,
        release_s, statistic, threshold, false_alarm, noise, held_samples, reason.
    """

    scene: str
    scenario: str
    kind: str
    record: Record
    free: tuple[str, ...]
    estimates: dict[str, dict[str, Any]]
    derived: dict[str, dict[str, Any]]
    correlation: np.ndarray
    covariance: np.ndarray
    residual_rms: float
    dof: int
    parameters: dict[str, float]
    fitted: np.ndarray
    cross_check: dict[str, Any]
    optimizer: dict[str, Any]
    converged: bool
    run: Result | None = None
    run_note: str = ""
    curves: dict[str, Any] = dataclasses.field(default_factory=dict)
    amplitude: float = 0.0
    starts: dict[str, Any] = dataclasses.field(default_factory=dict)
    release: dict[str, Any] = dataclasses.field(default_factory=dict)
    convergence: dict[str, Any] = dataclasses.field(default_factory=dict)
    timestep: dict[str, Any] = dataclasses.field(default_factory=dict)

    def __post_init__(self) -> None:
        object.__setattr__(self, "free", tuple(self.free))
        for name in ("correlation", "covariance", "fitted"):
            view = np.asarray(getattr(self, name), float).view()
            view.flags.writeable = False
            object.__setattr__(self, name, view)

    @property
    def success(self) -> bool:
        """Whether the solution converged (scipy's name for `converged`)."""
        return self.converged

    @property
    def message(self) -> str:
        """Why the optimizer stopped, e.g. 'norm(dx) < tol' (scipy's `message`; `convergence` judges the solution)."""
        return str(self.optimizer["status"])

    @property
    def verdict(self) -> str:
        """The one-line answer (see `verdict`)."""
        return verdict(self)

    @property
    def question(self) -> str:
        """What the fit asks, in words: which values of the free parameters reproduce the record."""
        record = self.record
        return (
            f"Which {', '.join(self.free)} of {self.scene} / {self.scenario} reproduce the record {record.column}"
            f" ({record.time.size} samples from {record.time[0]:.4g} s to {record.time[-1]:.4g} s)?"
        )

    @property
    def answer(self) -> str:
        """The answer in words with units: the estimates with their 95% intervals, the residual (`verdict`)."""
        return self.verdict

    @property
    def question_answer(self) -> Answer:
        """The question and `answer` (the verdict), with the estimates and the residual it quotes (SI)."""
        quoted = {**self.estimates, **self.derived}
        shown = ["omega_n_rad_s" if "omega_n_rad_s" in self.derived else "omega_n"]
        shown += ["damping_ratio" if "damping_ratio" in self.derived else "zeta"]
        shown += [n for n in self.free if n not in ("omega_n", "zeta", "x0", "v0", "offset", "delay")]
        numbers = {n: float(quoted[n]["value"]) for n in shown if n in quoted and quoted[n].get("value") is not None}
        if self.kind == "polynomial":  # its verdict quotes the polynomial's coefficients instead
            numbers = {n: float(q["value"]) for n, q in self.derived.items() if q.get("value") is not None}
        numbers["residual_rms"] = self.residual_rms
        if self.amplitude > 0:
            numbers["residual_share_of_amplitude"] = self.residual_rms / self.amplitude
        return answers.of_words(self.question, self.answer, numbers)

    def _shown(self) -> display.Summary:
        """The fit as a notebook shows it: converged or not with the one-line answer, then the estimates."""
        rows = [
            (name, q["value"], q["ci95"][0], q["ci95"][1], q.get("unit", ""))
            for name, q in [*self.estimates.items(), *self.derived.items()]
        ]
        return display.Summary(
            "FitResult",
            f"{self.scene} / {self.scenario} ({self.kind})",
            "converged" if self.converged else "not converged",
            self.converged,
            self.verdict,
            (
                display.Fact("residual RMS", self.residual_rms, self.record.unit),
                display.Fact("samples", int(self.record.time.size)),
                display.Fact("degrees of freedom", self.dof),
                display.Fact("free", ", ".join(self.free)),
            ),
            display.table(("estimate", "value", "95 % low", "95 % high", "unit"), rows),
        )

    def plot(self) -> Figure:
        """Data and fit, the residuals, and the phase plane (`springlab.plots.fit.fit_figure`).

        Returns
        -------
        matplotlib.figure.Figure
            a bare Figure (no pyplot): Jupyter shows it inline; `.savefig(path)` writes it.
        """
        return display.plot(self)

    def to_dict(self) -> dict[str, Any]:
        """fit.json's content, exactly what `springlab fit --json` prints (docs/fit.md, "fit.json").

        Plain JSON types: lists for arrays and tuples, None for a non-finite number.
        """
        r = self.record
        return files.json_ready(
            {
                **self.question_answer.to_dict(),
                "scene": self.scene,
                "scenario": self.scenario,
                "signal": r.name,
                "signal_unit": r.unit,
                "column": r.column,
                "free": list(self.free),
                "estimates": self.estimates,
                "derived": self.derived,
                "correlation": {a: dict(zip(self.free, row)) for a, row in zip(self.free, self.correlation.tolist())},
                "residual_rms": self.residual_rms,
                "degrees_of_freedom": self.dof,
                "samples": int(r.time.size),
                "rows": r.rows,
                "skipped_nan_rows": r.skipped_nan,
                "dropped_before_start": r.dropped_before_start,
                "time_origin_s": r.origin,
                "time_span_s": [float(r.time[0]), float(r.time[-1])],
                "data_notes": list(r.notes),
                "parameters": self.parameters,
                "curves": self.curves,
                "cross_check": self.cross_check,
                "optimizer": self.optimizer,
                "starts": self.starts,
                "release": self.release,
                "converged": self.converged,
                "convergence": self.convergence,
                "timestep": self.timestep,
                "run_note": self.run_note,
                "verdict": self.verdict,
            }
        )

    def outputs(self) -> tuple[Output, ...]:
        """The files `springlab fit --output DIR` writes (springlab.outputs.write): fit.json, the identified
        scene's run as trajectory.csv (MuJoCo's clock) and summary.json where there is one, and fit.png."""
        written = [Output.json("fit.json", self.to_dict())]
        if self.run is not None:
            written.append(Output("trajectory.csv", files.csv_text(self.run.columns())))
            written.append(Output.json("summary.json", self.run.to_dict()))
        return (*written, Output("fit.png"))

    def to_pandas(self) -> pandas.DataFrame:
        """The estimates, one row per fitted name: `name`, `value`, `ci95_low`, `ci95_high`, `unit` (pandas optional)."""
        rows = [
            {"name": name, "value": q["value"], "ci95_low": q["ci95"][0], "ci95_high": q["ci95"][1], "unit": q["unit"]}
            for name, q in self.estimates.items()
        ]
        return tables.to_pandas(rows)


def interval(value: float, half: float) -> list[float]:
    """[low, high] of value +- half."""
    return [value - half, value + half]


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
    function: Callable[[np.ndarray], Mapping[str, float]],
    x: np.ndarray,
    covariance: np.ndarray,
    t_quantile: float,
    units: Mapping[str, str] | None = None,
) -> dict[str, dict[str, Any]]:
    """name -> {'value', 'ci95', 'unit'} of derived quantities by the delta method (unit from `units`, else '-')."""
    units = units or {}
    center = function(x)
    grads = gradient(function, x)
    out = {}
    for name, value in center.items():
        g = grads[name]
        half = float(t_quantile * math.sqrt(max(g @ covariance @ g, 0.0)))
        out[name] = {"value": value, "ci95": interval(value, half), "unit": units.get(name, "-")}
    return out


def intervals(residuals: list[np.ndarray], jacobian: np.ndarray, samples: int) -> tuple[np.ndarray, np.ndarray]:
    """(covariance, 95 % half-widths) of `mujoco.sysid.calculate_intervals`, for `samples` residuals.

    sysid takes the noise variance as |r|^2 / (rows - p) and Student t on rows - p degrees of freedom from the
    residuals it is given; a compressed record's reduced rows (springlab.studies.fit.engine) hold the same |r|^2
    and J^T J in fewer rows, so its answer is rescaled to the true samples - p: the covariance by
    (rows - p) / (samples - p), the half-widths by that ratio's square root and the ratio of the t quantiles.
    """
    from mujoco import sysid
    from scipy import special

    covariance, half = sysid.calculate_intervals(residuals, jacobian)
    rows, p = sum(int(np.size(r)) for r in residuals), int(jacobian.shape[1])
    if rows == samples:
        return covariance, half
    ratio = (rows - p) / (samples - p)
    quantiles = special.stdtrit(samples - p, 0.975) / special.stdtrit(rows - p, 0.975)
    return np.asarray(covariance, float) * ratio, np.asarray(half, float) * math.sqrt(ratio) * quantiles


def cross_check(
    problem: Problem,
    x: np.ndarray,
    half_widths: np.ndarray,
    fitted: np.ndarray,
    effect: np.ndarray | None = None,
    scale: np.ndarray | None = None,
) -> dict[str, Any]:
    """The closed form (springlab.analytic) fitted independently with scipy, and how far MuJoCo's fit is from it.

    The two agree when every estimate differs by at most its tolerance: CROSS_IN_HALFWIDTHS of its 95 %
    half-width, plus the fit's own numerical accuracy: SAFETY x how far its simulation moves it (`effect`
    [units of the names], engine.accuracy's J^+ e), plus EXACT_ACCURACY of its `scale` (the optimizer's, [units
    of the names]) for the optimizers' own stopping; so an exact record, whose half-widths vanish, is held to
    what its simulation resolves.

    The closed-form fit is independent of MuJoCo's: the closed form at every recorded time (no grid, no
    interpolation), scipy's trust-region reflective solver, started where the MuJoCo fit started (the linear-
    algebra start, not its estimate, so that it can land in another minimum). A record of more than
    reductions.BLOCK samples reaches the same solver through reductions.Reduced: at each point one pass over
    blocks of samples accumulates the QR factor of [J | r], and the solver sees p + 1 rows with the per-sample
    cost, gradient, Gauss-Newton matrix and column norms exactly, hence the same steps, holding a block instead
    of the n x p Jacobian and its copies (1.2 GB on 2 million samples). Not the MuJoCo fit's grid reduction
    (engine): that one is exact for a signal read from a grid, and the closed form is what the grid is checked
    against.
    """
    from .engine import EXACT_ACCURACY

    how, record = problem.how, problem.record
    samples = problem.samples

    def closed(vector: np.ndarray, start: int = 0, stop: int | None = None) -> np.ndarray:
        values = problem.values(vector)
        params = how.scene_params(values, problem.base, problem.modal)
        return how.closed_form(problem.times(slice(start, stop)), params, values, record.signal, problem.force)

    def residual(vector: np.ndarray, start: int = 0, stop: int | None = None) -> np.ndarray:
        return (closed(vector, start, stop) - record.values[start:stop]) / problem.scale

    start = np.array([problem.start[n] for n in problem.free])
    bounds = np.array([how.bounds(n, problem.start[n], record) for n in problem.free]).T
    import scipy.optimize  # here, not at module top: it adds ~0.3 s to every command's start-up

    options: dict[str, Any] = {"bounds": (bounds[0], bounds[1]), "x_scale": "jac", "xtol": 1e-15, "ftol": 1e-15}
    if samples <= reductions.BLOCK:
        solution = scipy.optimize.least_squares(residual, start, gtol=1e-15, **options)
        model_gap = float(np.max(np.abs(closed(x) - fitted)))
    else:
        reduced = reductions.Reduced(samples, residual, (bounds[0], bounds[1]))
        solution = scipy.optimize.least_squares(reduced.fun, start, jac=reduced.jac, gtol=1e-15, **options)
        model_gap = max(float(np.max(np.abs(closed(x, a, b) - fitted[a:b]))) for a, b in reductions.blocks(samples))
    difference = np.abs(solution.x - x)
    relative = difference / np.maximum(np.abs(x), 1e-300)
    in_halfwidths = difference / np.where(half_widths > 0, half_widths, np.inf)
    numerical = np.zeros_like(x) if effect is None else compare.SAFETY * np.abs(np.asarray(effect, float))
    scale = np.abs(x) if scale is None else np.asarray(scale, float)
    tolerance = CROSS_IN_HALFWIDTHS * np.abs(half_widths) + numerical + EXACT_ACCURACY * scale
    amplitude = float(np.ptp(record.values)) or 1.0
    return {
        "method": "closed form (springlab.analytic) fitted independently with scipy.optimize.least_squares",
        "estimates": dict(zip(problem.free, solution.x.tolist())),
        "max_relative_difference": float(np.max(relative)),
        "max_difference_in_ci95_halfwidths": float(np.max(in_halfwidths)),
        "mujoco_vs_closed_form_at_estimate": model_gap / amplitude,
        "numerical_accuracy": dict(zip(problem.free, numerical.tolist())),
        "tolerance": dict(zip(problem.free, tolerance.tolist())),
        "max_difference_in_tolerances": float(np.max(difference / tolerance)),
        "agrees": bool(np.all(difference <= tolerance)),
    }


#: why the optimizer stops, as the convergence reason explains it
STOPS = {
    "norm(dx) < tol": "its step fell below its tolerance",
    "norm(gradient) < tol": "its gradient fell below its tolerance",
    "insufficient reduction": "no step reduced the cost any further, as on the round-off floor of a minimum",
    "maximum iterations reached": "it ran out of iterations",
    "factorization failed": "its linear system could not be factorized",
}


def convergence(
    problem: Problem,
    solved: dict[str, Any],
    covariance: np.ndarray,
    accuracy: dict[str, Any],
    cross: dict[str, Any],
) -> dict[str, Any]:
    """Whether the fit converged, judged on its solution rather than on the optimizer's message.

    Converged: the Gauss-Newton step still open at the estimate (J^+ r, names at a bound they press against
    held) moves no estimate by more than its allowance, max(STEP_IN_SE standard errors, EXACT_ACCURACY of
    its scale, the fit's numerical accuracy), and the closed-form cross-check agrees. fit.json's
    `convergence`: converged, optimizer_status, optimizer_met_tolerance, remaining_step (name -> [unit]),
    remaining_step_in_standard_errors, remaining_step_in_allowances (the largest), remaining_cost_reduction
    (what the step would still take off the sum of squares, in noise variances), at_bound, cross_check_agrees,
    reason (one line), short (the verdict's words when not converged).
    """
    from .engine import EXACT_ACCURACY

    free = problem.free
    x = np.asarray(solved["x"], float)
    scale = np.asarray(solved["scale"], float)
    residual = np.concatenate(solved["residuals"])
    jacobian = np.asarray(solved["jacobian"], float) * scale
    if problem.bounds is not None:
        bounds = np.array([problem.bounds[n] for n in free], float)
    else:
        bounds = np.array([problem.how.bounds(n, problem.start[n], problem.record) for n in free], float)
    width = bounds[:, 1] - bounds[:, 0]
    held = np.zeros(x.size, bool)
    for _ in range(x.size):
        step = np.zeros(x.size)
        if np.any(~held):
            step[~held] = -np.linalg.lstsq(jacobian[:, ~held], residual, rcond=None)[0]
        pressing = ((x <= bounds[:, 0] + 1e-9 * width) & (step < 0)) | ((x >= bounds[:, 1] - 1e-9 * width) & (step > 0))
        if not np.any(pressing & ~held):
            break
        held |= pressing
    explained = jacobian @ step
    n, p = problem.samples, x.size  # a compressed record's reduced rows hold the sum of squares of all n samples
    noise = float(residual @ residual) / max(n - p, 1)
    step = step * scale
    standard_error = np.sqrt(np.clip(np.diag(covariance), 0.0, None))
    allowance = np.maximum.reduce(
        [STEP_IN_SE * standard_error, EXACT_ACCURACY * scale, compare.SAFETY * np.abs(np.asarray(accuracy["effect"]))]
    )
    in_allowances = np.abs(step) / allowance
    in_errors = np.abs(step) / np.where(standard_error > 0, standard_error, np.inf)
    status = str(solved["status"])
    met = status in ("norm(dx) < tol", "norm(gradient) < tol")
    settled = bool(np.all(in_allowances <= 1.0))
    agrees = bool(cross["agrees"])
    worst = free[int(np.argmax(in_allowances))] if p else ""
    stopped = f"the optimizer stopped on '{status}' ({STOPS.get(status, 'unknown reason')})"
    left = (
        f"the remaining Gauss-Newton step is {float(np.max(in_allowances)):.2g} of its allowance"
        f" ({STEP_IN_SE:g} standard errors, or the fit's numerical accuracy)"
    )
    if settled and agrees:
        short = ""
        reason = f"converged: {left} and the closed-form cross-check agrees; {stopped}"
        if not met:
            reason = f"converged although {stopped}: {left} and the closed-form cross-check agrees"
    elif not settled:
        i = free.index(worst)
        short = f"{worst} can still move {in_errors[i]:.3g} standard errors"
        reason = (
            f"NOT CONVERGED: the remaining Gauss-Newton step still moves {worst} by {in_errors[i]:.3g} standard"
            f" errors ({in_allowances[i]:.3g} x its allowance); {stopped}"
        )
    else:
        names = cross.get("tolerance", {})
        far = max(names, key=lambda n: abs(cross["estimates"][n] - x[free.index(n)]) / names[n]) if names else worst
        short = f"the closed-form cross-check disagrees in {far}"
        reason = (
            f"NOT CONVERGED: {left}, but the closed form fitted independently lands"
            f" {cross.get('max_difference_in_tolerances', math.inf):.3g} tolerances away in {far}"
            f" (another minimum, or the simulation misses the closed form); {stopped}"
        )
    return {
        "converged": settled and agrees,
        "optimizer_status": status,
        "optimizer_met_tolerance": met,
        "remaining_step": dict(zip(free, step.tolist())),
        "remaining_step_in_standard_errors": float(np.max(in_errors)) if p else 0.0,
        "remaining_step_in_allowances": float(np.max(in_allowances)) if p else 0.0,
        "remaining_cost_reduction": float(explained @ explained) / noise if noise > 0 else 0.0,
        "at_bound": [name for name, flag in zip(free, held) if flag],
        "cross_check_agrees": agrees,
        "reason": reason,
        "short": short,
    }


def timestep(grid: Mapping[str, Any], numerics: Mapping[str, Any]) -> dict[str, Any]:
    """fit.json's `timestep`: the grid (engine.choose_dt's facts) and its check at the estimate.

    Parameters
    ----------
    grid
        engine.Problem.grid: dt_s [s], steps, integrator, rule, error_bound and needed_error [signal unit],
        noise, median_sample_spacing_s [s], rate_dt, estimate_range.
    numerics
        engine.accuracy at the estimate.
    """
    out = dict(grid)
    spacing = float(out.get("median_sample_spacing_s") or 0.0)
    out["samples_per_step"] = out["dt_s"] / spacing if spacing > 0 else None
    out["measured_error"] = numerics["error"]
    out["within_error_bound"] = bool(numerics["error"] <= out.get("error_bound", math.inf))
    out["effect"] = numerics["effect"].tolist()
    out["effect_in_standard_errors"] = numerics["in_standard_errors"]
    out["effect_in_allowances"] = numerics["ratio"]
    return out


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


def verdict(result: FitResult) -> str:
    """The one-line answer, e.g. 'ω_n = 18.40 ± 0.05 rad/s, ζ = 0.156 ± 0.004: underdamped; residual RMS ...'.

    A polynomial's: 'x(t) = (c3 ± h3) t³ + ... + (c0 ± h0) m; residual RMS ...'.
    """
    est, der, record = result.estimates, result.derived, result.record
    rms = result.residual_rms
    signal_unit = record.unit
    rms_text = length(rms) if signal_unit == "m" else f"{rms:.3g} {signal_unit}"
    amplitude = result.amplitude
    share = f" ({100 * rms / amplitude:.2g} % of the initial amplitude)" if amplitude > 0 else ""
    if result.kind == "polynomial":
        terms = []
        for n in reversed(range(len(POWER_TERMS))):
            c = der.get(POWER_TERMS[n])
            if c is not None:
                power = POWERS[n]
                terms.append(f"({plus_minus(c['value'], c['ci95'][1] - c['value'])}){(' ' + power) if power else ''}")
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
    why = result.convergence.get("short") or result.optimizer["status"]
    status = "" if result.converged else f"; NOT CONVERGED ({why})"
    return f"{text}; residual RMS {rms_text}{share}{status}"
