"""The printer-head design study: how fast can the carriage be positioned, and which properties matter?

The chapter's two design questions (section 5.7), answered by simulation:
the `move` scenario of the `printer_head` scene (a bang-bang point-to-point move
at the motor's force limit, then the residual belt vibration) is run for every
combination of four properties,

    belt_stiffness k [N/m], carriage_mass m_c [kg], damping_ratio zeta [-], drive_force F [N],

each on a log-symmetric grid around the scene's default (default x span^u,
u in [-1, 1], the default in the middle), with the motor-side mass, move
distance and positioning band held at the scene's values. For each
configuration the positioning time is the move time plus the settling time
(until the carriage stays inside +-band of the target for good).

How the runs are made (one `mujoco.batch.Batch`, a timestep per configuration, chunked
rollouts that stop once settling is certified): see :mod:`springlab.studies.design.moves`.

Sensitivities: the elasticity d ln T / d ln p of positioning time T with
respect to each property p, (1) by least squares of ln T on all ln p over the
whole grid (global, the ranking), and (2) by central differences between the
grid neighbours of the default (local). The properties are ranked by |global
elasticity|, and the positioning time is plotted over the two most
influential ones, the other two at their defaults (springlab.plots.design).

The analytic estimate beside every simulated time:

    T ~= 2 sqrt(D M / F) + ln(A / band) / (zeta omega_n)

the minimum bang-bang move time plus the time for the residual vibration's
envelope A e^(-zeta omega_n t) to shrink into the band, with A the exact
envelope of the carriage's residual vibration after the (grid-aligned) move
(for a release at rest from a0, A = a0 / sqrt(1 - zeta^2): the chapter's
ln(1 / (band / a0 sqrt(1 - zeta^2))) / (zeta omega_n)). A worst-case form needs
no simulation at all: the residual envelope is at most 4 F m_c m_m / (M^2 k)
(the residual stretch of an undamped belt is 4 sin^2(omega_n T / 4) times the
static stretch F m_c / (M k)), so

    T_worst = 2 sqrt(D M / F) + ln(4 F m_c m_m / (M^2 k band)) / (zeta omega_n).
"""

from __future__ import annotations

import dataclasses
import math
import pathlib
from collections.abc import Mapping
from typing import Any

import numpy as np

from springlab import files, scenes
from springlab.errors import BadInputError, ParameterError, UnknownNameError
from springlab.scenes.base import Parameter
from springlab.scenes.printer_head.scene import (
    PrinterHead,
    belt_damping_ratio,
    belt_omega,
    minimum_move_time,
    move_residual_stretch,
    residual_envelope,
    settling_estimate,
    worst_case_envelope,
)
from springlab.studies.executor import Executor

# re-exported: sobol and users reach the batched runs' constants and simulate_moves through design
from .moves import CHUNK_CONFIGURATIONS, MAX_DURATION, OMEGA_DT, config_parameters, run_moves, simulate_moves  # noqa: F401

#: the scenes that have a design study
STUDIES = ("printer_head",)

#: the swept properties, in order, with units
PROPERTIES: Mapping[str, str] = {
    "belt_stiffness": "N/m",
    "carriage_mass": "kg",
    "damping_ratio": "-",
    "drive_force": "N",
}

#: each property spans default x SPANS^[-1, 1]: softer/narrower to steel-cord belts (x/4..x4),
#: a bare head to a head with large cartridges (x/2..x2), belt rubber to an added damper
#: (x/3..x3), a weaker motor to a stronger one (x/4..x4)
SPANS: Mapping[str, float] = {
    "belt_stiffness": 4.0,
    "carriage_mass": 2.0,
    "damping_ratio": 3.0,
    "drive_force": 4.0,
}

#: default grid points per property (7^4 = 2401 configurations)
DEFAULT_LEVELS = 7
#: default grid points per property of the dense plane over the two most influential properties
#: (31^2 = 961 more configurations; 0: plot the coarse grid's slice instead)
PLANE_LEVELS = 31


@dataclasses.dataclass
class Plane:
    """Positioning time on a dense grid of the two most influential properties, the others at default.

    Attributes
    ----------
    x_name, y_name
        the properties along x and y (y the most influential).
    x, y
        their grid values, (nx,) and (ny,).
    positioning_time_s, estimate_s
        (ny, nx) simulated and estimated positioning time [s].
    steps
        physics steps taken.
    wall_time_s
        wall time of the batched simulation [s].
    """

    x_name: str
    y_name: str
    x: np.ndarray
    y: np.ndarray
    positioning_time_s: np.ndarray
    estimate_s: np.ndarray
    steps: int
    wall_time_s: float


@dataclasses.dataclass
class Study:
    """A finished design sweep; arrays are per configuration, (n,).

    Attributes
    ----------
    base
        the scene parameters the sweep starts from (SI).
    grids
        property -> its grid levels (the default in the middle).
    values
        property -> per-configuration value.
    move_time_s
        realized bang-bang move time [s].
    settling_time_s
        time after the move until the carriage stays in the band [s] (inf: never).
    positioning_time_s
        move + settling [s].
    residual_amplitude_m
        largest carriage deviation from the target after the move [m].
    estimate_s
        analytic estimate of positioning time [s] (module docstring).
    worst_case_estimate_s
        the phase-independent upper estimate [s].
    natural_frequency_hz
        belt mode [Hz].
    dt_s
        timestep of each simulation [s].
    steps
        physics steps taken in total.
    wall_time_s
        wall time of the batched simulation [s].
    nthread
        threads each batch ran on.
    executor
        where the chunks ran ('local', '2 local dask workers', ...).
    plane
        the dense plane over the two most influential properties (None: not run).
    """

    base: dict[str, float]
    grids: dict[str, np.ndarray]
    values: dict[str, np.ndarray]
    move_time_s: np.ndarray
    settling_time_s: np.ndarray
    positioning_time_s: np.ndarray
    residual_amplitude_m: np.ndarray
    estimate_s: np.ndarray
    worst_case_estimate_s: np.ndarray
    natural_frequency_hz: np.ndarray
    dt_s: np.ndarray
    steps: int
    wall_time_s: float
    nthread: int
    executor: str = "local"
    plane: Plane | None = None

    @property
    def size(self) -> int:
        """Number of configurations."""
        return len(self.positioning_time_s)

    @property
    def levels(self) -> int:
        """Grid points per property."""
        return len(next(iter(self.grids.values())))

    def default_index(self) -> int:
        """Index of the configuration at every property's default (the grid centre)."""
        centre = self.levels // 2
        return int(np.ravel_multi_index((centre,) * len(self.grids), (self.levels,) * len(self.grids)))

    def elasticities(self) -> dict[str, float]:
        """Global elasticity d ln T / d ln p [-] per property: least squares over the grid."""
        return _regression(self.values, self.positioning_time_s)[0]

    def regression_r2(self) -> float:
        """Coefficient of determination [-] of the log-log fit."""
        return _regression(self.values, self.positioning_time_s)[1]

    def local_elasticities(self, times: np.ndarray | None = None) -> dict[str, float]:
        """Elasticity [-] at the default by central differences between grid neighbours."""
        times = self.positioning_time_s if times is None else times
        shape = (self.levels,) * len(self.grids)
        grid_times = np.log(times).reshape(shape)
        centre = self.levels // 2
        out = {}
        for axis, name in enumerate(self.grids):
            index: list[int | slice] = [centre] * len(shape)
            index[axis] = centre + 1
            upper = grid_times[tuple(index)]
            index[axis] = centre - 1
            lower = grid_times[tuple(index)]
            levels = np.log(self.grids[name])
            out[name] = float((upper - lower) / (levels[centre + 1] - levels[centre - 1]))
        return out

    def ranking(self) -> list[str]:
        """Properties by decreasing |global elasticity|."""
        elasticity = self.elasticities()
        return sorted(elasticity, key=lambda name: -abs(elasticity[name]))


# -- grids -----------------------------------------------------------------------


def base_parameters(overrides: Mapping[str, Any] | None = None) -> dict[str, float]:
    """The printer_head `move` parameters the sweep starts from (MJCF defaults < overrides).

    The design table's property `damping_ratio` [-] is accepted too: it sets the
    belt damping c = 2 zeta sqrt(k m_c m_m / (m_c + m_m)) of the other values.

    Raises
    ------
    UnknownNameError, ParameterError
        as for `springlab run`, and for damping_ratio given together with belt_damping.
    """
    scene = scenes.get("printer_head")
    overrides = dict(overrides or {})
    for name in overrides:
        if name != "damping_ratio" and name not in scene.parameters:
            raise UnknownNameError(
                "parameter of the printer_head design study", name, [*scene.parameters, "damping_ratio"]
            )
    ratio = overrides.pop("damping_ratio", None)
    if ratio is None:
        return scene.resolve(scene.scenario("move"), overrides)
    if "belt_damping" in overrides:
        raise ParameterError("give damping_ratio or belt_damping, not both (damping_ratio sets the belt damping)")
    ratio = Parameter("damping_ratio", "-", "belt damping ratio", minimum=0.0).check(ratio)
    base = scene.resolve(scene.scenario("move"), overrides)
    reduced = base["carriage_mass"] * base["motor_mass"] / (base["carriage_mass"] + base["motor_mass"])
    overrides["belt_damping"] = 2.0 * ratio * math.sqrt(base["belt_stiffness"] * reduced)
    return scene.resolve(scene.scenario("move"), overrides)


def default_properties(base: Mapping[str, float]) -> dict[str, float]:
    """The swept properties' values at `base`: damping ratio from the belt damping."""
    m_c, m_m = base["carriage_mass"], base["motor_mass"]
    return {
        "belt_stiffness": base["belt_stiffness"],
        "carriage_mass": m_c,
        "damping_ratio": belt_damping_ratio(base["belt_damping"], base["belt_stiffness"], m_c, m_m),
        "drive_force": base["drive_force"],
    }


def make_grids(base: Mapping[str, float], levels: int = DEFAULT_LEVELS) -> dict[str, np.ndarray]:
    """Property -> `levels` values, default x span^u for u evenly in [-1, 1].

    Raises
    ------
    BadInputError
        `levels` is not an odd integer >= 3 (the default must be a grid point).
    """
    if not isinstance(levels, (int, np.integer)) or levels < 3 or levels % 2 == 0:
        raise BadInputError(f"levels must be an odd integer >= 3 (the default is the middle one), got {levels!r}")
    defaults = default_properties(base)
    if defaults["damping_ratio"] <= 0:
        raise BadInputError("the design study needs belt_damping > 0 (it sweeps the damping ratio around it)")
    exponents = np.linspace(-1.0, 1.0, levels)
    return {name: defaults[name] * SPANS[name] ** exponents for name in PROPERTIES}


def configurations(grids: Mapping[str, np.ndarray]) -> dict[str, np.ndarray]:
    """Full factorial of the grids: property -> (n,) values, the last property fastest."""
    mesh = np.meshgrid(*grids.values(), indexing="ij")
    return {name: axis.ravel() for name, axis in zip(grids, mesh)}


# -- the analytic estimate ---------------------------------------------------------


def estimates(
    base: Mapping[str, float], values: Mapping[str, np.ndarray], dt: np.ndarray
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(estimate [s], worst-case estimate [s], natural frequency [Hz]) per configuration.

    estimate: realized move time + ln(A / band) / (zeta omega_n), A the exact
    residual envelope after the grid-aligned move; worst case: the minimum move
    time 2 sqrt(D M / F) + ln(4 F m_c m_m / (M^2 k band)) / (zeta omega_n).
    """
    n = len(dt)
    estimate, worst, frequency = np.empty(n), np.empty(n), np.empty(n)
    m_m, band = base["motor_mass"], base["positioning_band"]
    for i in range(n):
        params = config_parameters(base, values, i)
        m_c, k, force = params["carriage_mass"], params["belt_stiffness"], params["drive_force"]
        total = m_c + m_m
        omega = float(belt_omega(k, m_c, m_m))
        zeta = float(values["damping_ratio"][i])
        frequency[i] = omega / (2 * math.pi)
        half_steps, _ = PrinterHead.move_profile(params, float(dt[i]))
        stretch, rate = move_residual_stretch(params, float(dt[i]))
        envelope = residual_envelope(stretch, rate, m_c, m_m, omega, zeta)
        estimate[i] = 2 * half_steps * dt[i] + settling_estimate(envelope, band, zeta, omega)
        worst_envelope = worst_case_envelope(force, m_c, m_m, k)
        worst[i] = minimum_move_time(params["move_distance"], total, force) + settling_estimate(
            worst_envelope, band, zeta, omega
        )
    return estimate, worst, frequency


# -- the study -------------------------------------------------------------------------


def run_study(
    scene: str = "printer_head",
    *,
    levels: int = DEFAULT_LEVELS,
    plane_levels: int = PLANE_LEVELS,
    nthread: int = 0,
    omega_dt: float = OMEGA_DT,
    executor: Executor | None = None,
    **overrides: Any,
) -> Study:
    """Sweep the four properties, simulate every configuration, and estimate each analytically.

    Parameters
    ----------
    scene
        the scene to study (only 'printer_head' has a design study).
    levels
        odd number of grid points per property (levels^4 configurations).
    plane_levels
        odd number of grid points per axis of the dense plane over the two most
        influential properties (plane_levels^2 more configurations), 0 for none.
    nthread
        batch threads (0: one per CPU).
    omega_dt
        omega_n dt [-] of every simulation.
    executor
        where the chunks run (None: locally on `nthread` threads); the numbers are the same.
    **overrides
        printer_head parameters to start from (SI), e.g. move_distance=0.2 [m].

    Raises
    ------
    UnknownNameError
        an unknown scene or parameter.
    BadInputError
        bad levels, threads or parameter values.
    """
    if scene not in STUDIES:
        raise UnknownNameError("design study", str(scene), STUDIES)
    if not isinstance(nthread, (int, np.integer)) or nthread < 0:
        raise BadInputError(f"threads must be an integer >= 0 (0: one per CPU), got {nthread!r}")
    if not (isinstance(omega_dt, (int, float)) and 0 < omega_dt <= 1.0):
        raise BadInputError(f"omega_dt must be a number in (0, 1] (RK4 resolution), got {omega_dt!r}")
    if not isinstance(plane_levels, (int, np.integer)) or not (
        plane_levels == 0 or (plane_levels >= 3 and plane_levels % 2 == 1)
    ):
        raise BadInputError(f"plane levels must be 0 (no plane) or an odd integer >= 3, got {plane_levels!r}")
    base = base_parameters(overrides)
    grids = make_grids(base, levels)
    values = configurations(grids)
    executor = Executor(nthread=nthread, progress=False) if executor is None else executor
    runs = run_moves(base, values, omega_dt=omega_dt, executor=executor)
    estimate, worst, frequency = estimates(base, values, runs["dt_s"])
    study = Study(
        base=base,
        grids=grids,
        values=values,
        move_time_s=runs["move_time_s"],
        settling_time_s=runs["settling_time_s"],
        positioning_time_s=runs["positioning_time_s"],
        residual_amplitude_m=runs["residual_amplitude_m"],
        estimate_s=estimate,
        worst_case_estimate_s=worst,
        natural_frequency_hz=frequency,
        dt_s=runs["dt_s"],
        steps=runs["steps_total"],
        wall_time_s=runs["wall_time_s"],
        nthread=runs["nthread"],
        executor=runs["executor"],
    )
    if plane_levels:
        study.plane = dense_plane(study, plane_levels, omega_dt=omega_dt, executor=executor)
    return study


def dense_plane(
    study: Study,
    levels: int = PLANE_LEVELS,
    *,
    omega_dt: float = OMEGA_DT,
    nthread: int = 0,
    executor: Executor | None = None,
) -> Plane:
    """Simulate the `levels` x `levels` plane of the study's two most influential properties.

    Each spans the study's range (default x SPANS^[-1, 1]); the other two stay at their defaults.
    """
    first, second = study.ranking()[:2]
    defaults = default_properties(study.base)
    exponents = np.linspace(-1.0, 1.0, levels)
    axis = {name: defaults[name] * SPANS[name] ** exponents for name in (first, second)}
    y, x = np.meshgrid(axis[first], axis[second], indexing="ij")
    values = {name: np.full(y.size, defaults[name]) for name in PROPERTIES}
    values[first], values[second] = y.ravel(), x.ravel()
    executor = Executor(nthread=nthread, progress=False) if executor is None else executor
    runs = run_moves(study.base, values, omega_dt=omega_dt, executor=executor, description="design plane")
    estimate, _, _ = estimates(study.base, values, runs["dt_s"])
    return Plane(
        x_name=second,
        y_name=first,
        x=axis[second],
        y=axis[first],
        positioning_time_s=runs["positioning_time_s"].reshape(y.shape),
        estimate_s=estimate.reshape(y.shape),
        steps=runs["steps_total"],
        wall_time_s=runs["wall_time_s"],
    )


def _regression(values: Mapping[str, np.ndarray], times: np.ndarray) -> tuple[dict[str, float], float]:
    """Least squares ln T = a + sum e_p ln p over the finite times: ({p: e_p}, R^2)."""
    finite = np.isfinite(times) & (times > 0)
    design = np.column_stack([np.ones(finite.sum())] + [np.log(values[p][finite]) for p in PROPERTIES])
    target = np.log(times[finite])
    coefficients, *_ = np.linalg.lstsq(design, target, rcond=None)
    residual = target - design @ coefficients
    r2 = 1.0 - float(residual @ residual) / float(np.sum((target - target.mean()) ** 2))
    return {p: float(e) for p, e in zip(PROPERTIES, coefficients[1:])}, r2


def summary(study: Study) -> dict[str, Any]:
    """The study as a JSON-ready dict (what `springlab design --json` prints)."""
    i = study.default_index()
    finite = np.isfinite(study.positioning_time_s)
    ratio = study.estimate_s[finite] / study.positioning_time_s[finite]
    fastest = int(np.argmin(study.positioning_time_s))
    return {
        "scene": "printer_head",
        "configurations": study.size,
        "levels": study.levels,
        "properties": {name: {"unit": PROPERTIES[name], "grid": study.grids[name]} for name in PROPERTIES},
        "fixed": {name: study.base[name] for name in ("motor_mass", "move_distance", "positioning_band")},
        "default": {
            "properties": {name: float(study.values[name][i]) for name in PROPERTIES},
            "natural_frequency_hz": float(study.natural_frequency_hz[i]),
            "move_time_s": float(study.move_time_s[i]),
            "settling_time_s": float(study.settling_time_s[i]),
            "positioning_time_s": float(study.positioning_time_s[i]),
            "residual_amplitude_m": float(study.residual_amplitude_m[i]),
            "estimate_s": float(study.estimate_s[i]),
            "worst_case_estimate_s": float(study.worst_case_estimate_s[i]),
        },
        "fastest": {
            "properties": {name: float(study.values[name][fastest]) for name in PROPERTIES},
            "positioning_time_s": float(study.positioning_time_s[fastest]),
            "move_time_s": float(study.move_time_s[fastest]),
        },
        "positioning_time_s": {
            "min": float(np.min(study.positioning_time_s)),
            "median": float(np.median(study.positioning_time_s)),
            "max": float(np.max(study.positioning_time_s)),
            "unsettled": int(np.sum(~finite)),
        },
        "elasticities": study.elasticities(),
        "regression_r2": study.regression_r2(),
        "local_elasticities": study.local_elasticities(),
        "local_elasticities_of_estimate": study.local_elasticities(study.estimate_s),
        "ranking": study.ranking(),
        "estimate_over_simulation": {
            "median": float(np.median(ratio)),
            "p05": float(np.percentile(ratio, 5)),
            "p95": float(np.percentile(ratio, 95)),
        },
        "worst_case_covers": float(
            np.mean(study.worst_case_estimate_s[finite] >= study.positioning_time_s[finite] - study.dt_s[finite] * 2)
        ),
        "steps": study.steps,
        "wall_time_s": study.wall_time_s,
        "configurations_per_s": study.size / study.wall_time_s,
        "nthread": study.nthread,
        "executor": study.executor,
        "plane": None
        if study.plane is None
        else {
            "x": study.plane.x_name,
            "y": study.plane.y_name,
            "levels": len(study.plane.x),
            "configurations": int(study.plane.positioning_time_s.size),
            "positioning_time_s": {
                "min": float(np.min(study.plane.positioning_time_s)),
                "max": float(np.max(study.plane.positioning_time_s)),
            },
            "steps": study.plane.steps,
            "wall_time_s": study.plane.wall_time_s,
        },
    }


# -- files ---------------------------------------------------------------------------------


def write(study: Study, directory: str | pathlib.Path, extra: Mapping[str, Any] | None = None) -> list[pathlib.Path]:
    """Write design.json (the summary, plus `extra` entries such as `sobol`) and configurations.csv
    into `directory`; the chart, design.png, is springlab.plots.design.plot's (the caller draws it)."""
    folder = files.prepare_directory(directory)
    columns = {name: study.values[name] for name in PROPERTIES}
    columns.update(
        {
            "natural_frequency_hz": study.natural_frequency_hz,
            "dt_s": study.dt_s,
            "move_time_s": study.move_time_s,
            "settling_time_s": study.settling_time_s,
            "positioning_time_s": study.positioning_time_s,
            "residual_amplitude_m": study.residual_amplitude_m,
            "estimate_s": study.estimate_s,
            "worst_case_estimate_s": study.worst_case_estimate_s,
        }
    )
    written = files.write_text_files(
        folder,
        {
            "design.json": files.dumps({**summary(study), **(extra or {})}) + "\n",
            "configurations.csv": files.csv_text(columns),
        },
    )
    return written


def answer(study: Study) -> str:
    """The two design questions answered in words, with the study's numbers."""
    s = summary(study)
    d = s["default"]
    e = s["elasticities"]
    ranking = s["ranking"]
    base = study.base
    return (
        f"How fast? With the defaults (carriage {d['properties']['carriage_mass']:.3g} kg, motor side "
        f"{base['motor_mass']:.3g} kg, belt {d['properties']['belt_stiffness']:.3g} N/m at zeta = "
        f"{d['properties']['damping_ratio']:.3g}, belt mode {d['natural_frequency_hz']:.0f} Hz, "
        f"{d['properties']['drive_force']:.3g} N) a {base['move_distance'] * 1e3:.4g} mm move to "
        f"+-{base['positioning_band'] * 1e6:.3g} um takes {d['positioning_time_s'] * 1e3:.1f} ms: "
        f"{d['move_time_s'] * 1e3:.1f} ms of bang-bang move (the minimum at this force) and "
        f"{d['settling_time_s'] * 1e3:.1f} ms of settling (estimate {d['estimate_s'] * 1e3:.1f} ms total, "
        f"worst case {d['worst_case_estimate_s'] * 1e3:.1f} ms). Over the {s['configurations']} configurations "
        f"it ranges {s['positioning_time_s']['min'] * 1e3:.1f}-{s['positioning_time_s']['max'] * 1e3:.0f} ms. "
        f"Which properties? By elasticity d ln T / d ln p: " + ", ".join(f"{p} {e[p]:+.2f}" for p in ranking) + "."
    )
