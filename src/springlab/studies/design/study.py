"""The design study: how fast can a scene's move be made, and which of its properties matter?

A scene declares the design question it answers (`Scene.design`, a
springlab.scenes.capabilities.design.DesignSpec); this study reads the declaration and
never names a scene. The printer head's is the chapter's (section 5.7): the
`move` scenario (a bang-bang point-to-point move at the motor's force limit,
then the residual belt vibration) for every combination of four properties,

    belt_stiffness k [N/m], carriage_mass m_c [kg], damping_ratio zeta [-], drive_force F [N],

each on a log-symmetric grid around the scene's default (default x span^u,
u in [-1, 1], the default in the middle), with the declared `fixed` parameters
(motor-side mass, move distance and positioning band) held at the scene's
values. For each configuration the positioning time is the move time plus the
settling time (until the positioned body stays inside +-band of the target for
good).

How the runs are made is the scene's (`DesignSpec.hooks.simulate`; the printer
head's: one `mujoco.batch.Batch` per chunk, a timestep per configuration,
rollouts that stop once settling is certified, springlab.scenes.printer_head.design);
:mod:`springlab.studies.design.moves` cuts the configurations into chunks on the executor.

Sensitivities: the elasticity d ln T / d ln p of positioning time T with
respect to each property p, (1) by least squares of ln T on all ln p over the
whole grid (global, the ranking), and (2) by central differences between the
grid neighbours of the default (local). The properties are ranked by |global
elasticity|, and the positioning time is plotted over the two most
influential ones, the others at their defaults (springlab.plots.design).

Beside every simulated time, the scene's analytic estimate
(`DesignSpec.hooks.estimates`; the printer head's: the minimum bang-bang move
time plus the time for the residual vibration's exact envelope to decay into
the band, and a worst case that needs no simulation at all).
"""

from __future__ import annotations

import dataclasses
import functools
from collections.abc import Mapping
from typing import TYPE_CHECKING, Any

import numpy as np

from springlab import display, files, tables
from springlab.answer import Answer
from springlab.errors import BadInputError
from springlab.files import Output
from springlab.scenes.base import Scene
from springlab.scenes.capabilities.design import DesignSpec
from springlab.scenes.declarations import keyword_parameters
from springlab.studies import answers
from springlab.studies.executor import Executor

from . import moves
from .moves import OMEGA_DT, base_parameters, declaration, design_scenes
from .sobol import SobolStudy, check_base_samples, run_sobol

if TYPE_CHECKING:
    import pandas
    from matplotlib.figure import Figure

__all__ = [
    "DEFAULT_LEVELS",
    "OMEGA_DT",
    "PLANE_LEVELS",
    "Plane",
    "Study",
    "base_parameters",
    "configurations",
    "declaration",
    "dense_plane",
    "design",
    "design_scenes",
    "make_grids",
    "run_study",
]

#: default grid points per property (7^4 = 2401 configurations of the printer head)
DEFAULT_LEVELS = 7
#: default grid points per property of the dense plane over the two most influential properties
#: (31^2 = 961 more configurations; 0: plot the coarse grid's slice instead)
PLANE_LEVELS = 31
#: the options renamed in issue 32, old keyword -> new
RENAMED = {"seed": "sobol_seed"}
#: the per-configuration columns of configurations.csv after the properties, in order
_COLUMNS = (
    "natural_frequency_hz",
    "dt_s",
    "move_time_s",
    "settling_time_s",
    "positioning_time_s",
    "residual_amplitude_m",
    "estimate_s",
    "worst_case_estimate_s",
)


@dataclasses.dataclass(frozen=True, eq=False)
class Plane:
    """Positioning time on a dense grid of the two most influential properties, the others at default.

    Immutable: its arrays are read-only.

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

    def __post_init__(self) -> None:
        for name in ("x", "y", "positioning_time_s", "estimate_s"):
            object.__setattr__(self, name, moves.frozen_array(getattr(self, name)))

    def to_dict(self) -> dict[str, Any]:
        """The `plane` entry of design.json: x, y, levels, configurations, positioning_time_s (min, max), steps."""
        return files.json_ready(
            {
                "x": self.x_name,
                "y": self.y_name,
                "levels": len(self.x),
                "configurations": int(self.positioning_time_s.size),
                "positioning_time_s": {
                    "min": float(np.min(self.positioning_time_s)),
                    "max": float(np.max(self.positioning_time_s)),
                },
                "steps": self.steps,
                "wall_time_s": self.wall_time_s,
            }
        )


@dataclasses.dataclass(frozen=True, eq=False, repr=False)
class Study(display.Shown):
    """A finished design sweep; arrays are per configuration, (n,), and read-only.

    Attributes
    ----------
    scene
        the scene studied.
    design
        its design declaration (properties, units, spans, fixed parameters, hooks).
    base
        the scene parameters the sweep starts from (SI).
    grids
        property -> its grid levels (the default in the middle).
    values
        property -> per-configuration value.
    move_time_s
        realized move time [s].
    settling_time_s
        time after the move until the positioned body stays in the band [s] (inf: never).
    positioning_time_s
        move + settling [s].
    residual_amplitude_m
        largest deviation from the target after the move [m].
    estimate_s
        analytic estimate of positioning time [s] (the scene's hook).
    worst_case_estimate_s
        the phase-independent upper estimate [s].
    natural_frequency_hz
        the mode that rings after the move [Hz].
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
    sobol
        the Sobol indices of the same question (None: not run).
    """

    scene: str
    design: DesignSpec = dataclasses.field(repr=False)
    base: Mapping[str, float]
    grids: Mapping[str, np.ndarray]
    values: Mapping[str, np.ndarray]
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
    sobol: SobolStudy | None = None

    def __post_init__(self) -> None:
        object.__setattr__(self, "base", moves.frozen_mapping(self.base))
        for name in ("grids", "values"):
            arrays = {key: moves.frozen_array(v) for key, v in getattr(self, name).items()}
            object.__setattr__(self, name, moves.frozen_mapping(arrays))
        for name in ("settling_time_s", "residual_amplitude_m", "worst_case_estimate_s", *_COLUMNS):
            object.__setattr__(self, name, moves.frozen_array(getattr(self, name)))

    # -- facts -------------------------------------------------------------------------

    @property
    def size(self) -> int:
        """Number of configurations."""
        return len(self.positioning_time_s)

    @property
    def levels(self) -> int:
        """Grid points per property."""
        return len(next(iter(self.grids.values())))

    @property
    def default_index(self) -> int:
        """Index of the configuration at every property's default (the grid centre)."""
        centre = self.levels // 2
        return int(np.ravel_multi_index((centre,) * len(self.grids), (self.levels,) * len(self.grids)))

    @property
    def fastest_index(self) -> int:
        """Index of the configuration with the shortest positioning time."""
        return int(np.argmin(self.positioning_time_s))

    @functools.cached_property
    def defaults(self) -> Mapping[str, float]:
        """Every declared property's value [its unit] at `base` (the grid centre, for the swept ones)."""
        return moves.frozen_mapping(self.design.hooks.defaults(self.base))

    @property
    def setting(self) -> str:
        """The fixed task in words, e.g. '25.4 mm to +-10 um' (the scene's hook)."""
        return self.design.hooks.setting(self.base)

    @functools.cached_property
    def _fit(self) -> tuple[Mapping[str, float], float]:
        elasticities, r2 = _regression(self.design.names, self.values, self.positioning_time_s)
        return moves.frozen_mapping(elasticities), r2

    @property
    def elasticities(self) -> Mapping[str, float]:
        """Global elasticity d ln T / d ln p [-] per property: least squares over the grid."""
        return self._fit[0]

    @property
    def regression_r2(self) -> float:
        """Coefficient of determination [-] of the log-log fit."""
        return self._fit[1]

    @functools.cached_property
    def local_elasticities(self) -> Mapping[str, float]:
        """Elasticity [-] of positioning time at the default, by central differences between grid neighbours."""
        return moves.frozen_mapping(self._local(self.positioning_time_s))

    @functools.cached_property
    def local_elasticities_of_estimate(self) -> Mapping[str, float]:
        """The same [-] of the analytic estimate."""
        return moves.frozen_mapping(self._local(self.estimate_s))

    @functools.cached_property
    def ranking(self) -> tuple[str, ...]:
        """Properties by decreasing |global elasticity|."""
        elasticity = self.elasticities
        return tuple(sorted(elasticity, key=lambda name: -abs(elasticity[name])))

    @property
    def answer(self) -> str:
        """The design question answered in words, with the study's numbers (the scene's hook)."""
        return self.design.hooks.answer(self._facts())

    @property
    def columns(self) -> dict[str, np.ndarray]:
        """The per-configuration columns of configurations.csv: the properties, then the results (SI)."""
        out = {name: self.values[name] for name in self.design.names}
        out.update({name: getattr(self, name) for name in _COLUMNS})
        return out

    def _local(self, times: np.ndarray) -> dict[str, float]:
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

    # -- serialisation -------------------------------------------------------------------

    def _shown(self) -> display.Summary:
        """The design study as a notebook shows it: its answer first, then the fastest and default times."""
        fastest, default = self.fastest_index, self.default_index
        return display.Summary(
            "Study",
            f"{self.scene}: {self.setting}",
            "answer",
            None,
            self.answer,
            (
                display.Fact("configurations", self.size),
                display.Fact("fastest positioning time", float(self.positioning_time_s[fastest]), "s"),
                display.Fact("default positioning time", float(self.positioning_time_s[default]), "s"),
                display.Fact("ranking", " > ".join(self.ranking)),
                display.Fact("wall time", self.wall_time_s, "s"),
            ),
            display.table(
                ("property", "elasticity d ln T / d ln p [-]"), [(n, self.elasticities[n]) for n in self.ranking]
            ),
        )

    def plot(self) -> Figure:
        """Positioning time over the two most influential properties, and simulated against analytic times (`springlab.plots.design.design_figure`).

        Returns
        -------
        matplotlib.figure.Figure
            a bare Figure (no pyplot): Jupyter shows it inline; `.savefig(path)` writes it.
        """
        return display.plot(self)

    def to_dict(self) -> dict[str, Any]:
        """What `springlab design --json` prints and design.json holds (JSON-ready: inf and nan as None)."""
        return files.json_ready({**self.question_answer.to_dict(), **self._facts()})

    @property
    def question(self) -> str:
        """The design question the scene declares (`DesignSpec.question`)."""
        return self.design.question

    @property
    def question_answer(self) -> Answer:
        """The design question and the scene's answer (`answer`), with the positioning times it quotes [s]."""
        facts = self._facts()
        times = facts["positioning_time_s"]
        return answers.of_words(
            self.question,
            self.answer,
            {
                "default_positioning_time_s": facts["default"]["positioning_time_s"],
                "positioning_time_s_min": times["min"],
                "positioning_time_s_max": times["max"],
            },
        )

    def outputs(self) -> tuple[Output, ...]:
        """The files `springlab design --output DIR` writes (springlab.outputs.write): design.json (`to_dict()`,
        with `sobol` where the study has it), configurations.csv, design.png and, with a Sobol study, sobol.png."""
        written = (
            Output.json("design.json", self.to_dict()),
            Output("configurations.csv", files.csv_text(self.columns)),
            Output("design.png"),
        )
        return written if self.sobol is None else (*written, Output("sobol.png"))

    def _facts(self) -> dict[str, Any]:
        """to_dict's entries before JSON (an unsettled time still inf), for the answer's words."""
        names = self.design.names
        i = self.default_index
        finite = np.isfinite(self.positioning_time_s)
        ratio = self.estimate_s[finite] / self.positioning_time_s[finite]
        fastest = self.fastest_index
        out = {
            "scene": self.scene,
            "configurations": self.size,
            "levels": self.levels,
            "properties": {p.name: {"unit": p.unit, "grid": self.grids[p.name]} for p in self.design.properties},
            "fixed": {name: self.base[name] for name in self.design.fixed},
            "default": {
                "properties": {name: float(self.values[name][i]) for name in names},
                "natural_frequency_hz": float(self.natural_frequency_hz[i]),
                "move_time_s": float(self.move_time_s[i]),
                "settling_time_s": float(self.settling_time_s[i]),
                "positioning_time_s": float(self.positioning_time_s[i]),
                "residual_amplitude_m": float(self.residual_amplitude_m[i]),
                "estimate_s": float(self.estimate_s[i]),
                "worst_case_estimate_s": float(self.worst_case_estimate_s[i]),
            },
            "fastest": {
                "properties": {name: float(self.values[name][fastest]) for name in names},
                "positioning_time_s": float(self.positioning_time_s[fastest]),
                "move_time_s": float(self.move_time_s[fastest]),
            },
            "positioning_time_s": {
                "min": float(np.min(self.positioning_time_s)),
                "median": float(np.median(self.positioning_time_s)),
                "max": float(np.max(self.positioning_time_s)),
                "unsettled": int(np.sum(~finite)),
            },
            "elasticities": dict(self.elasticities),
            "regression_r2": self.regression_r2,
            "local_elasticities": dict(self.local_elasticities),
            "local_elasticities_of_estimate": dict(self.local_elasticities_of_estimate),
            "ranking": list(self.ranking),
            "estimate_over_simulation": {
                "median": float(np.median(ratio)),
                "p05": float(np.percentile(ratio, 5)),
                "p95": float(np.percentile(ratio, 95)),
            },
            "worst_case_covers": float(
                np.mean(self.worst_case_estimate_s[finite] >= self.positioning_time_s[finite] - self.dt_s[finite] * 2)
            ),
            "steps": self.steps,
            "wall_time_s": self.wall_time_s,
            "configurations_per_s": self.size / self.wall_time_s,
            "nthread": self.nthread,
            "executor": self.executor,
            "plane": None if self.plane is None else self.plane.to_dict(),
        }
        if self.sobol is not None:
            out["sobol"] = self.sobol.to_dict()
        return out

    def to_pandas(self) -> pandas.DataFrame:
        """One row per configuration, the columns of configurations.csv (SI; pandas needed)."""
        return tables.to_pandas(self.columns)


# -- grids -----------------------------------------------------------------------


def make_grids(scene: str | Scene, base: Mapping[str, float], levels: int = DEFAULT_LEVELS) -> dict[str, np.ndarray]:
    """Property -> `levels` values, default x span^u for u evenly in [-1, 1], for the declared properties.

    Raises
    ------
    BadInputError
        `levels` is not an odd integer >= 3 (the default must be a grid point), or a property's
        default is not > 0.
    """
    if not isinstance(levels, (int, np.integer)) or levels < 3 or levels % 2 == 0:
        raise BadInputError(f"levels must be an odd integer >= 3 (the default is the middle one), got {levels!r}")
    _, spec = declaration(scene)
    exponents = np.linspace(-1.0, 1.0, levels)
    return moves.spanned(spec.hooks.defaults(base), spec.properties, exponents)


def configurations(grids: Mapping[str, np.ndarray]) -> dict[str, np.ndarray]:
    """Full factorial of the grids: property -> (n,) values, the last property fastest."""
    mesh = np.meshgrid(*grids.values(), indexing="ij")
    return {name: axis.ravel() for name, axis in zip(grids, mesh)}


# -- the study -------------------------------------------------------------------------


def design(
    model: str | Scene,
    *,
    levels: int = DEFAULT_LEVELS,
    plane_levels: int = PLANE_LEVELS,
    nthread: int = 0,
    omega_dt: float = OMEGA_DT,
    executor: Executor | None = None,
    sobol: int | None = None,
    sobol_seed: int = 0,
    **parameters: float,
) -> Study:
    """Sweep a scene's declared properties, simulate every configuration, and estimate each analytically.

    `springlab design`; `run_study` is its name before issue 32.

    Parameters
    ----------
    model
        a scene that declares a design question (`Scene.design`), or its name (`design_scenes()`).
    levels
        odd number of grid points per property (levels^D configurations for D properties).
    plane_levels
        odd number of grid points per axis of the dense plane over the two most
        influential properties (plane_levels^2 more configurations), 0 for none.
    nthread
        batch threads (0: one per CPU).
    omega_dt
        omega_n dt [-] of every simulation.
    executor
        where the chunks run (None: locally on `nthread` threads); the numbers are the same.
    sobol
        also the Sobol indices with this many base samples N (a power of 2; `Study.sobol`), None: not.
    sobol_seed
        seed of the Sobol sequence and bootstrap (`seed` before issue 32: the printer head has a
        parameter seed).
    **parameters
        scene parameters to start from (SI), e.g. move_distance=0.2 [m]; a declared derived
        property too (the printer head's damping_ratio).

    Returns
    -------
    Study
        every configuration's simulated and estimated times, the ranking, the dense plane and the Sobol
        indices where asked; `to_dict()` is design.json.

    Raises
    ------
    UnknownNameError
        an unknown scene, a scene without a design question, or an unknown parameter.
    BadInputError
        bad levels, threads, Sobol samples or parameter values.
    TypeError
        an old keyword spelling (`scene=`, `seed=` where the scene has no parameter seed).
    """
    found, spec = declaration(model)
    overrides = keyword_parameters("design", parameters, declared=found.parameters, renamed=RENAMED)
    if not isinstance(nthread, (int, np.integer)) or nthread < 0:
        raise BadInputError(f"threads must be an integer >= 0 (0: one per CPU), got {nthread!r}")
    if not (isinstance(omega_dt, (int, float)) and 0 < omega_dt <= 1.0):
        raise BadInputError(f"omega_dt must be a number in (0, 1] (RK4 resolution), got {omega_dt!r}")
    if not isinstance(plane_levels, (int, np.integer)) or not (
        plane_levels == 0 or (plane_levels >= 3 and plane_levels % 2 == 1)
    ):
        raise BadInputError(f"plane levels must be 0 (no plane) or an odd integer >= 3, got {plane_levels!r}")
    if sobol is not None:
        check_base_samples(sobol, len(spec.sobol))
    base = base_parameters(found, overrides)
    grids = make_grids(found, base, levels)
    values = configurations(grids)
    executor = Executor(nthread=nthread, progress=False) if executor is None else executor
    simulated = moves.run_moves(found, base, values, omega_dt=omega_dt, executor=executor)
    runs = simulated.runs
    estimated = spec.hooks.estimates(base, values, runs.dt_s)
    study = Study(
        scene=found.name,
        design=spec,
        base=base,
        grids=grids,
        values=values,
        move_time_s=runs.move_time_s,
        settling_time_s=runs.settling_time_s,
        positioning_time_s=runs.positioning_time_s,
        residual_amplitude_m=runs.residual_amplitude_m,
        estimate_s=estimated.estimate_s,
        worst_case_estimate_s=estimated.worst_case_estimate_s,
        natural_frequency_hz=estimated.natural_frequency_hz,
        dt_s=runs.dt_s,
        steps=simulated.steps_total,
        wall_time_s=simulated.wall_time_s,
        nthread=runs.nthread,
        executor=simulated.executor,
    )
    plane = dense_plane(study, plane_levels, omega_dt=omega_dt, executor=executor) if plane_levels else None
    indices = None
    if sobol is not None:
        indices = run_sobol(found, sobol, sobol_seed=sobol_seed, omega_dt=omega_dt, executor=executor, **overrides)
    return dataclasses.replace(study, plane=plane, sobol=indices)


#: the design study's name before issue 32 (scripts and the command line call it)
run_study = design


def dense_plane(
    study: Study,
    levels: int = PLANE_LEVELS,
    *,
    omega_dt: float = OMEGA_DT,
    nthread: int = 0,
    executor: Executor | None = None,
) -> Plane:
    """Simulate the `levels` x `levels` plane of the study's two most influential properties.

    Each spans the study's range (default x span^[-1, 1]); the others stay at their defaults.
    """
    first, second = study.ranking[:2]
    defaults = study.defaults
    exponents = np.linspace(-1.0, 1.0, levels)
    axis = moves.spanned(defaults, (study.design.get(first), study.design.get(second)), exponents)
    y, x = np.meshgrid(axis[first], axis[second], indexing="ij")
    values = {name: np.full(y.size, defaults[name]) for name in study.design.names}
    values[first], values[second] = y.ravel(), x.ravel()
    executor = Executor(nthread=nthread, progress=False) if executor is None else executor
    simulated = moves.run_moves(
        study.scene, study.base, values, omega_dt=omega_dt, executor=executor, description="design plane"
    )
    estimated = study.design.hooks.estimates(study.base, values, simulated.runs.dt_s)
    return Plane(
        x_name=second,
        y_name=first,
        x=axis[second],
        y=axis[first],
        positioning_time_s=simulated.runs.positioning_time_s.reshape(y.shape),
        estimate_s=estimated.estimate_s.reshape(y.shape),
        steps=simulated.steps_total,
        wall_time_s=simulated.wall_time_s,
    )


def _regression(
    names: tuple[str, ...], values: Mapping[str, np.ndarray], times: np.ndarray
) -> tuple[dict[str, float], float]:
    """Least squares ln T = a + sum e_p ln p over the finite times: ({p: e_p}, R^2)."""
    finite = np.isfinite(times) & (times > 0)
    design = np.column_stack([np.ones(finite.sum())] + [np.log(values[p][finite]) for p in names])
    target = np.log(times[finite])
    coefficients, *_ = np.linalg.lstsq(design, target, rcond=None)
    residual = target - design @ coefficients
    r2 = 1.0 - float(residual @ residual) / float(np.sum((target - target.mean()) ** 2))
    return {p: float(e) for p, e in zip(names, coefficients[1:])}, r2


# -- files ---------------------------------------------------------------------------------
