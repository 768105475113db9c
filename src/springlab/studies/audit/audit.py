"""`springlab audit MODEL`: which integrator and timestep any MuJoCo model needs, how close to blowing up
it is, and what accuracy each setting buys for its compute.

1. Linear analysis at the operating point (springlab.exact.linearize): modes [Hz], damping ratios, the
   physically unstable ones, the fastest.
2. Stability limits per integrator (springlab.studies.audit.limits): predicted from the modes, measured on
   MuJoCo's one-step map, confirmed by runs of the nonlinear model just below and above; the margin of
   the model's own timestep; constraint time constants shorter than 2 dt.
3. Accuracy vs cost (springlab.studies.audit.sweep): every integrator over a timestep grid from the perturbed
   operating point, batched, against the exact solution of the linearization (linear models) or a
   converged RK4 reference; observed orders, the Pareto front, and the cheapest setting meeting tol,
   verified by a run of its own.

`audit(model_or_path, ...)` returns an `Audit`: its facts as attributes (`audit.recommendation.dt`,
`audit.own.stable`, `audit.stability["rk4"].limit_dt_measured_s`, ...), immutable; `Audit.to_dict()` is
audit.json and `Audit.to_pandas()` the sweep's table.
"""

from __future__ import annotations

import dataclasses
import math
import os
import pathlib
import time as _time
from collections.abc import Mapping, Sequence
from types import MappingProxyType
from typing import TYPE_CHECKING, Any

import mujoco
import numpy as np

from springlab import display, scenes, tables
from springlab.errors import BadInputError, DivergedError
from springlab.exact.constraints import ConstraintState
from springlab.exact.linearize import Linearization
from springlab.exact.model_at_point import ModelAtPoint
from springlab.exact.operating_point import OperatingPoint
from springlab.runs import compare
from springlab.runs.run import prepare
from springlab.sim.batch import Job
from springlab.sim.simulate import (
    INTEGRATORS,
    Setup,
    Trajectory,
    beyond_mujoco_limits,
    integrator_id,
    quiet_mujoco,
    simulate,
)
from springlab.studies.convergence import Run, observed_order, pareto_front
from springlab.studies.executor import Executor

from .limits import ConstraintFlag, Limit, RunProbe, Watch, constraint_flags, stability_limits, watch
from .ship import Runner, ship
from .sweep import (
    GRID_DECADES,
    GRID_POINTS,
    MAX_SAMPLES,
    REFERENCE_FRACTION,
    ExactReference,
    Reference,
    SweepRun,
    checkpoint_spacing,
    converged_reference,
    cost_per_step,
    default_grid,
    linearity_change,
    linearity_tolerance,
    reference_step,
    run_error,
    sweep_runs,
)

#: defaults of the command line and the API
DEFAULT_TOL = 1e-3
DEFAULT_DURATION = 1.0
DEFAULT_PERTURB = 1e-3
#: a recommended timestep keeps this fraction of its integrator's measured stability limit
RECOMMEND_LIMIT_FRACTION = 0.9
#: the default grid's largest timestep: this multiple of the largest confirmed limit (runs beyond show the blow-up)
GRID_TOP_OVER_LIMIT = 1.2
#: the default grid's finest timestep takes at most this many steps over the duration (never exit 2 for the grid)
GRID_MAX_STEPS = 100_000
#: a degree of freedom "moved" when the fine run from the start changes it by more than this x perturb
MOTION_FRACTION = 1e-2
#: the operating point is "at rest" when its drift, |qvel| T + |qacc| T^2 / 2 over the duration T, stays
#: within this x perturb (the motion the audit itself starts)
REST_FRACTION = 1.0
_NAMES = {value: name for name, value in INTEGRATORS.items()}

if TYPE_CHECKING:
    import pandas
    from matplotlib.figure import Figure


@dataclasses.dataclass(frozen=True)
class OwnSetting:
    """The model's own setting (its integrator and timestep) as the audit found it.

    Attributes
    ----------
    integrator
        the model's integrator.
    dt
        its timestep [s].
    stable
        no run of it blew up: its sweep run over the duration, and (where its timestep is at or above a
        confirmed limit, or the limit comes from runs) a brute-force run at it. Never False from an
        unconfirmed figure.
    error
        its run's error [-] (None: it diverged).
    margin
        its integrator's `limit_dt_s` / dt [-] (None: no limit).
    wall_time_s
        steps x its integrator's measured cost per step [s].
    margin_confirmed
        whether runs confirm the limit behind `margin` (None: no limit).
    """

    integrator: str
    dt: float
    stable: bool
    error: float | None
    margin: float | None
    wall_time_s: float
    margin_confirmed: bool | None = None

    def to_dict(self) -> dict[str, Any]:
        """audit.json's "own_setting": {"integrator", "dt", "stable", "error", "margin", "wall_time_s",
        "margin_confirmed"}."""
        return dataclasses.asdict(self)


@dataclasses.dataclass(frozen=True)
class Excitation:
    """How the audit's start moves the model, and whether the motion reached every degree of freedom.

    Attributes
    ----------
    qpos
        every degree of freedom is moved by between perturb / 2 and perturb [m or rad] (seeded signs).
    qvel
        ... and given a velocity of between qvel / 2 and qvel [m/s or rad/s] (perturb / duration).
    ctrl
        every actuator's control is offset by this fraction of its half range (1 where unlimited) [-]
        and held (None: no actuator, or a scene's scenario start).
    moved
        degrees of freedom the fine run from the start changes by more than MOTION_FRACTION x perturb.
    still
        the names of those it does not (they are not verified by any error).
    source
        "perturbed operating point" or "scenario start".
    """

    qpos: float
    qvel: float
    ctrl: float | None
    moved: int
    still: tuple[str, ...]
    source: str

    @property
    def any_motion(self) -> bool:
        """Whether anything moved at all (else nothing was verified)."""
        return self.moved > 0

    def to_dict(self) -> dict[str, Any]:
        """audit.json's "excitation": {"qpos", "qvel", "ctrl", "moved", "still", "source"}."""
        return {
            "qpos": self.qpos,
            "qvel": self.qvel,
            "ctrl": self.ctrl,
            "moved": self.moved,
            "still": list(self.still),
            "source": self.source,
        }


@dataclasses.dataclass(frozen=True)
class PointReport:
    """The operating point as the audit found it: what constrains it, whether it is at rest, and what
    constrains the motion from the start.

    Attributes
    ----------
    settle_s
        how long the model was left to settle before (None: not settled) [s].
    at_point
        the constraints, contacts and dry friction active at the operating point.
    along_motion
        those active at any step of a fine run from the start (`limits.watch`).
    at_rest
        |qvel| T + |qacc| T^2 / 2 (T the duration) within REST_FRACTION x perturb: an equilibrium.
    drift_m
        that drift [m or rad].
    linear_map
        whether MuJoCo's one-step map is the dynamics (nothing of `along_motion` is active), so the
        limits come from it; otherwise they come from nonlinear runs.
    """

    settle_s: float | None
    at_point: ConstraintState
    along_motion: ConstraintState
    at_rest: bool
    drift_m: float
    linear_map: bool

    def to_dict(self) -> dict[str, Any]:
        """audit.json's "operating_point_state": {"settle_s", "at_point", "along_motion", "at_rest",
        "drift_m", "linear_map"}."""
        return {
            "settle_s": self.settle_s,
            "at_point": self.at_point.to_dict(),
            "along_motion": self.along_motion.to_dict(),
            "at_rest": self.at_rest,
            "drift_m": self.drift_m,
            "linear_map": self.linear_map,
        }


@dataclasses.dataclass(frozen=True)
class Recommendation:
    """The cheapest swept setting meeting the tolerance, verified by a run of its own (all None but
    `tolerance` and `verified` = False where none does).

    Attributes
    ----------
    integrator
        its integrator (None: no swept setting meets the tolerance).
    dt
        its timestep [s].
    error
        the verification run's error [-].
    tolerance
        the tolerance it meets [-].
    verified
        whether a run of its own met the tolerance.
    wall_time_s
        steps x its integrator's measured cost per step [s].
    """

    integrator: str | None
    dt: float | None
    error: float | None
    tolerance: float
    verified: bool
    wall_time_s: float | None

    def to_dict(self) -> dict[str, Any]:
        """audit.json's "recommendation": {"integrator", "dt", "error", "tolerance", "verified", "wall_time_s"}."""
        return dataclasses.asdict(self)


@dataclasses.dataclass(frozen=True)
class Linearity:
    """How far the linearization moves along the motion: the linear-or-not verdict's measure.

    Attributes
    ----------
    change
        max relative change of A over states of the motion [-] (inf: the probe run diverged).
    tolerance
        the largest change for which the linearization's exact solution is the reference [-].
    """

    change: float
    tolerance: float

    def to_dict(self) -> dict[str, Any]:
        """audit.json's "linearity": {"change", "tolerance"}."""
        return dataclasses.asdict(self)


@dataclasses.dataclass(frozen=True)
class ReferenceUsed:
    """The reference the sweep's errors are measured against.

    Attributes
    ----------
    kind
        what it is, for people.
    error_estimate
        its own estimated error [-] (0 for the exact solution).
    dt
        its timestep [s] (None for the exact solution).
    converged
        error_estimate within REFERENCE_FRACTION x tol.
    compared_at
        where the runs are compared with it, for people.
    common_time_spacing_s
        the common multiple of the swept timesteps [s]: every run has a step there.
    """

    kind: str
    error_estimate: float
    dt: float | None
    converged: bool
    compared_at: str
    common_time_spacing_s: float

    def to_dict(self) -> dict[str, Any]:
        """audit.json's "reference"."""
        return dataclasses.asdict(self)


@dataclasses.dataclass(frozen=True)
class Timings:
    """Wall time of each stage of the audit [s]."""

    linearization_and_limits_s: float
    sweep_s: float
    reference_s: float
    total_s: float

    def to_dict(self) -> dict[str, float]:
        """audit.json's "timings_s"."""
        return dataclasses.asdict(self)


#: what audit.json says counts as numerically unstable
STABILITY_CRITERION = (
    "numerically unstable: the measured one-step map amplifies a mode more than the exact flow"
    " exp(lambda dt) does, by more than 1e-4 per step"
)


@dataclasses.dataclass(frozen=True, repr=False)
class Audit(display.Shown):
    """An audit of one model (see the module docstring); `to_dict()` is audit.json and `audit --json`.

    Attributes
    ----------
    model
        where the model came from (path, scene name or "<MjModel>").
    linear
        the linearization at the operating point (its `point`, `modes`, `fastest`).
    start
        the perturbed start of the sweep runs.
    duration
        simulated time of every run [s].
    tol
        tolerance of the recommendation [-].
    perturb
        size of the initial perturbation [m or rad].
    stability
        integrator -> `Limit` (predicted / measured / confirmed stability limit [s], margin [-]).
    own
        the model's own setting (`OwnSetting`).
    constraints
        constraint settings the own timestep breaks (solref timeconst < 2 dt).
    is_linear, linearity
        the linearity verdict and its measure (`Linearity`).
    reference
        the reference of the sweep (`ReferenceUsed`).
    runs
        the sweep, per integrator, largest dt first (`SweepRun`; `to_pandas()` is their table).
    orders
        integrator -> observed order (None: no clean power law, e.g. contacts).
    pareto
        runs no other beats in both error and wall time.
    recommendation
        the cheapest setting meeting tol, verified (`Recommendation`).
    timings
        wall time of each stage [s] (`Timings`).
    point_state
        what constrains the operating point and the motion, whether it is at rest (`PointReport`).
    excitation
        how the start moves the model and what moved (`Excitation`).
    """

    model: str
    linear: Linearization
    start: Setup
    duration: float
    tol: float
    perturb: float
    stability: Mapping[str, Limit]
    own: OwnSetting
    constraints: tuple[ConstraintFlag, ...]
    is_linear: bool
    linearity: Linearity
    reference: ReferenceUsed
    runs: tuple[SweepRun, ...]
    orders: Mapping[str, float | None]
    pareto: tuple[SweepRun, ...]
    recommendation: Recommendation
    timings: Timings
    point_state: PointReport
    excitation: Excitation

    @property
    def own_ok(self) -> bool:
        """The model's own setting is stable and meets tol (exit 0 of the CLI; otherwise 1)."""
        return bool(self.own.stable) and self.own.error is not None and self.own.error <= self.tol

    @property
    def mode_count(self) -> str:
        """'6 modes (2 rigid)': how the text and audit.png count the modes (a complex pair is one mode)."""
        modes = self.linear.modes
        rigid = sum(m.kind == "rigid" for m in modes)
        return f"{len(modes)} mode{'s' if len(modes) != 1 else ''}" + (f" ({rigid} rigid)" if rigid else "")

    @property
    def message(self) -> str:
        """A few lines for people (what `springlab audit` prints): modes, what holds the operating point,
        the own setting's margin and error, the recommendation, warnings (not at rest, no motion, broken
        constraints, an unconverged reference)."""
        lines = []
        fastest = self.linear.fastest
        unstable = sum(m.physically_unstable for m in self.linear.modes)
        motion = "linear" if self.is_linear else "nonlinear"
        head = f"{self.model}: {self.mode_count}"
        if fastest is not None:
            zeta = "" if fastest.damping_ratio is None else f", zeta {fastest.damping_ratio + 0.0:.3g}"  # no -0
            head += f", fastest {fastest.frequency_hz:.4g} Hz ({fastest.kind}{zeta})"
        else:
            head += ", all rigid"
        if unstable:
            head += f"; {unstable} physically unstable (the model's own dynamics, not the integrator)"
        lines.append(f"{head}; {motion} along the motion")
        state = self.point_state
        where = self.linear.point.label
        lines.append(f"at {where}: {state.at_point.describe()}; along the motion: {state.along_motion.describe()}")
        if not state.at_rest:
            lines.append(
                f"warning: the operating point is not at rest (it drifts {state.drift_m:.2g} m or rad over"
                f" {self.duration:g} s, more than --perturb {self.perturb:g}): the modes are those of the motion"
                " through it, not of an equilibrium; "
                + (
                    "settling longer may bring it to rest"
                    if state.settle_s
                    else "--settle SECONDS lets it come to rest first"
                )
            )
        if not state.linear_map:
            lines.append(
                "constraints, contacts or dry friction are active, so the linear map is not the dynamics:"
                " the stability limits come from nonlinear runs (bisection of blow-up), the predictions are estimates"
            )
        if state.along_motion.dry_friction:
            lines.append(
                f"dry friction ({len(state.along_motion.dry_friction)}: {state.along_motion.dry_friction[0]}...):"
                " sticking and slipping are not in the modes; limits and errors are measured by runs"
            )
        own = self.own
        limit = self.stability[own.integrator]
        figure = limit.limit_dt_s
        how = f"{limit.method}, {'confirmed by runs' if limit.confirmed else 'UNCONFIRMED'}"
        if not own.stable:
            stable = "is UNSTABLE: a run of it blows up"
            if figure is not None and limit.confirmed:
                stable += f" (limit {figure:.3g} s, {how})"
        elif figure is None:
            bounded = limit.runs_bounded_dt_s
            stable = "has no stability limit up to the duration"
            if limit.method == "nonlinear runs" and bounded is not None:
                stable = f"has no stability limit: no run blew up up to {bounded:.3g} s"
            if fastest is None and limit.method != "nonlinear runs":
                stable += " (every mode is rigid: no time scale for a timestep to miss)"
        elif limit.confirmed:
            stable = f"is stable with margin {figure / own.dt:.3g}x (limit {figure:.3g} s, {how})"
        else:
            stable = f"is stable (its run stays bounded); limit {figure:.3g} s UNCONFIRMED by runs, no margin claimed"
        error = "not compared" if own.error is None else f"{own.error:.2g}"
        meets = "" if own.error is None else (" (meets tol)" if own.error <= self.tol else " (misses tol)")
        lines.append(
            f"your setting, {own.integrator} at {own.dt * 1e3:.3g} ms, {stable};"
            f" its error over {self.duration:g} s is {error}{meets}"
        )
        excitation = self.excitation
        if not excitation.any_motion:
            lines.append("no motion: nothing was verified (the fine run from the start barely moves)")
        elif excitation.still:
            names = ", ".join(excitation.still[:3]) + (" ..." if len(excitation.still) > 3 else "")
            count = len(excitation.still)
            lines.append(
                f"note: {count} degree{'s' if count != 1 else ''} of freedom barely moved ({names}): no error covers"
                f" {'them' if count != 1 else 'it'}"
            )
        pick = self.recommendation
        if not excitation.any_motion:
            pass
        elif pick.integrator is None or pick.dt is None or pick.error is None or pick.wall_time_s is None:
            lines.append(f"no swept setting meets tol {self.tol:g} (verified runs); try --dt lower or a longer grid")
        else:
            ratio = f" at {pick.wall_time_s / own.wall_time_s:.2g}x the cost of yours" if own.wall_time_s else ""
            lines.append(
                f"cheapest meeting tol {self.tol:g}: {pick.integrator} at {pick.dt * 1e3:.3g} ms, error"
                f" {pick.error:.2g}{ratio} (verified by a run)"
            )
        unconfirmed = [n for n, lim in self.stability.items() if lim.limit_dt_s is not None and not lim.confirmed]
        if unconfirmed:
            lines.append(f"unconfirmed limits (not used for any verdict): {', '.join(unconfirmed)}")
        if self.constraints:
            names = ", ".join(f"{c.element} ({c.timeconst_s:g} s)" for c in self.constraints[:3])
            more = f" and {len(self.constraints) - 3} more" if len(self.constraints) > 3 else ""
            lines.append(f"solref time constants shorter than 2 dt (MuJoCo stiffens nothing, it clamps): {names}{more}")
        if not self.reference.converged:
            lines.append(
                f"note: the RK4 reference did not converge to 1% of tol (estimate {self.reference.error_estimate:.2g});"
                " errors below that are not resolved"
            )
        return "\n".join(lines)

    def _shown(self) -> display.Summary:
        """The audit as a notebook shows it: whether the model's own setting meets tol, then the numbers."""
        own, pick = self.own, self.recommendation
        return display.Summary(
            "Audit",
            self.model,
            f"own setting {'meets' if self.own_ok else 'misses'} tol {self.tol:g}",
            self.own_ok,
            self.message.split("\n")[0],
            (
                display.Fact("own setting", f"{own.integrator} at dt = {own.dt:g} s"),
                display.Fact("own error", own.error),
                display.Fact("stability margin", own.margin),
                display.Fact("modes", self.mode_count),
                display.Fact(
                    "recommended", f"{pick.integrator} at dt = {display.number(pick.dt)} s" if pick.integrator else None
                ),
                display.Fact("recommended error", pick.error),
                display.Fact("wall time", self.timings.total_s, "s"),
            ),
            display.table(
                ("integrator", "limit dt [s]", "method"),
                [(name, limit.limit_dt_s, limit.method) for name, limit in self.stability.items()],
            ),
        )

    def plot(self) -> Figure:
        """The modes, the stability limits against the own setting, and error against cost (`springlab.plots.audit.audit_figure`).

        Returns
        -------
        matplotlib.figure.Figure
            a bare Figure (no pyplot): Jupyter shows it inline; `.savefig(path)` writes it.
        """
        return display.plot(self)

    def to_dict(self) -> dict[str, Any]:
        """audit.json and `springlab audit --json`: the model, its operating point, modes, stability limits,
        own setting, sweep and recommendation, plus linearity, orders, pareto, reference, constraints and timings."""
        fastest = self.linear.fastest
        return {
            "model": self.model,
            "operating_point": self.linear.point.to_dict(),
            "operating_point_state": self.point_state.to_dict(),
            "perturb": self.perturb,
            "excitation": self.excitation.to_dict(),
            "duration_s": self.duration,
            "linear": self.is_linear,
            "linearity": self.linearity.to_dict(),
            "modes": [m.to_dict() for m in self.linear.modes],
            "fastest_mode": fastest.to_dict() if fastest else None,
            "stability": {name: limit.to_dict() for name, limit in self.stability.items()},
            "stability_criterion": STABILITY_CRITERION,
            "own_setting": self.own.to_dict(),
            "constraints_broken": [c.to_dict() for c in self.constraints],
            "reference": self.reference.to_dict(),
            "sweep": [r.to_dict() for r in self.runs],
            "orders": dict(self.orders),
            "pareto": [r.to_dict() for r in self.pareto],
            "recommendation": self.recommendation.to_dict(),
            "timings_s": self.timings.to_dict(),
        }

    def to_pandas(self) -> pandas.DataFrame:
        """The sweep as a DataFrame, one row per (integrator, dt): the rows of `to_dict()["sweep"]`
        (integrator, dt [s], steps, error [-], wall_time_s [s], diverged); pandas is optional."""
        return tables.to_pandas([r.to_dict() for r in self.runs])


# -- the model -----------------------------------------------------------------


@dataclasses.dataclass
class _Source:
    label: str
    model: mujoco.MjModel
    start: Setup | None = None  # a shipped scene's scenario start
    duration: float | None = None
    origin: tuple[str, str] | None = None  # ("path", file) or ("scene", name): what dask workers rebuild it from


def load(model_or_path: Any) -> _Source:
    """A compiled model from an MjModel, a path to an MJCF / URDF, or a shipped scene name.

    A scene is built with its default scenario and parameters; its scenario's initial state is the
    sweep's start (as `springlab tradeoff` runs it) and its duration the default.

    Raises
    ------
    BadInputError
        no such file or scene, or MuJoCo cannot compile it (its message, one line).
    """
    if isinstance(model_or_path, mujoco.MjModel):
        return _Source("<MjModel>", model_or_path)
    if not isinstance(model_or_path, (str, os.PathLike)):
        raise BadInputError(f"model must be an MjModel, a path to an MJCF file or a scene name, got {model_or_path!r}")
    text = os.fspath(model_or_path)
    path = pathlib.Path(text)
    if not path.exists() and text in scenes.SCENES:
        scene, chosen, params = prepare(text, None, {})
        model = scene.build(params, chosen)
        steps = max(1, round(chosen.duration / model.opt.timestep))
        setup = scene.setup(model, params, chosen, steps, model.opt.timestep)
        return _Source(f"scene {text!r} (scenario {chosen.name!r})", model, setup, chosen.duration, ("scene", text))
    if not path.is_file():
        raise BadInputError(f"no such model file or scene {text!r}; scenes: {', '.join(sorted(scenes.SCENES))}")
    try:
        with quiet_mujoco():
            model = mujoco.MjModel.from_xml_path(str(path))
    except Exception as error:  # MuJoCo raises ValueError with its compiler's message
        message = " ".join(str(error).split())
        raise BadInputError(f"cannot load {text!r}: {message}") from None
    return _Source(text, model, origin=("path", text))


def _start(
    model: mujoco.MjModel, point: OperatingPoint, perturb: float, duration: float, source: _Source
) -> tuple[Setup, float | None, str]:
    """The sweep's start, the control offset [-] (None: none) and where the start comes from.

    A scene's scenario state where it differs from the operating point; else the operating point moved
    by between perturb / 2 and perturb [m or rad] along every degree of freedom, given a velocity of
    between perturb / duration / 2 and perturb / duration [m/s or rad/s] along every one (so a model with
    no position-dependent force moves too), and, for an actuated model, every control offset by perturb
    x its half range (1 where unlimited), held. Signs and sizes are seeded, so audits repeat."""
    if source.start is not None and source.start.qpos is not None:
        qvel = np.asarray(source.start.qvel if source.start.qvel is not None else point.qvel, float)
        qpos = np.asarray(source.start.qpos, float)
        if np.any(qpos != point.qpos) or np.any(qvel != point.qvel):  # a scenario driven by inputs alone does not
            return Setup(qpos, qvel, point.act, point.ctrl), None, "scenario start"  # move here: perturb it
    rng = np.random.default_rng(0)

    def pattern(size: int) -> np.ndarray:
        return rng.uniform(0.5, 1.0, size) * rng.choice([-1.0, 1.0], size)

    qpos = point.qpos.copy()
    mujoco.mj_integratePos(model, qpos, perturb * pattern(model.nv), 1.0)
    qvel = point.qvel + perturb / duration * pattern(model.nv)
    ctrl = point.ctrl.copy()
    offset = None
    if model.nu and perturb > 0:
        offset = perturb
        low, high = model.actuator_ctrlrange[:, 0], model.actuator_ctrlrange[:, 1]
        limited = np.asarray(model.actuator_ctrllimited, bool) & (high > low)
        half = np.where(limited, 0.5 * (high - low), 1.0)
        ctrl = ctrl + perturb * half * pattern(model.nu)
        ctrl = np.where(limited, np.clip(ctrl, low, high), ctrl)
    return Setup(qpos, qvel, point.act.copy(), ctrl), offset, "perturbed operating point"


def _check_perturbation(model: mujoco.MjModel, point: OperatingPoint, perturb: float, start: Setup) -> None:
    """BadInputError when `perturb` [m or rad] leaves the model's valid range: a rotation of pi or more, more
    than half of a limited joint's range, or a start MuJoCo itself rejects (past 1e10)."""
    rotational = {int(mujoco.mjtJoint.mjJNT_HINGE), int(mujoco.mjtJoint.mjJNT_BALL), int(mujoco.mjtJoint.mjJNT_FREE)}
    if perturb >= math.pi and any(int(t) in rotational for t in model.jnt_type):
        raise BadInputError(
            f"--perturb {perturb:g} rad turns a joint by half a revolution or more; a perturbation must be"
            " small (default 1e-3): use a value below pi"
        )
    for j in range(model.njnt):
        if model.jnt_limited[j] and int(model.jnt_type[j]) in (
            int(mujoco.mjtJoint.mjJNT_HINGE),
            int(mujoco.mjtJoint.mjJNT_SLIDE),
        ):
            span = float(model.jnt_range[j, 1] - model.jnt_range[j, 0])
            if perturb >= span / 2:
                name = model.joint(j).name or str(j)
                raise BadInputError(
                    f"--perturb {perturb:g} is at least half the range of joint {name!r} ({span:g}); use a value below"
                    f" {span / 2:g}"
                )
    bad = beyond_mujoco_limits(model, start.qpos, start.qvel, start.act, start.control)
    if bad is not None:
        raise BadInputError(f"--perturb {perturb:g} gives {bad} at the start, past MuJoCo's limit; use a smaller one")


def _drift(point_state: ConstraintState, duration: float) -> float:
    """How far the operating point moves by itself over `duration` [m or rad]: |qvel| T + |qacc| T^2 / 2."""
    return point_state.max_abs_qvel * duration + 0.5 * point_state.max_abs_qacc * duration**2


def _excitation(
    model: mujoco.MjModel, start: Setup, probe: Trajectory | DivergedError, perturb: float
) -> tuple[int, tuple[str, ...]]:
    """(degrees of freedom moved, names of those that did not) by the fine run `probe` from `start`: a DOF
    moved when its position changes by more than MOTION_FRACTION x perturb (a scene's start: x 1e-9)."""
    if isinstance(probe, DivergedError):
        return model.nv, ()  # it moved, to the point of blowing up
    rows = np.unique(np.linspace(0, len(probe.time) - 1, min(len(probe.time), 400)).astype(int))
    change = np.zeros(model.nv)
    dq = np.zeros(model.nv)
    origin = probe.qpos[0]
    for row in rows:
        mujoco.mj_differentiatePos(model, dq, 1.0, origin, probe.qpos[row])
        change = np.maximum(change, np.abs(dq))
    threshold = MOTION_FRACTION * max(perturb, 1e-9)
    still = []
    for dof in np.flatnonzero(change <= threshold):
        joint = int(model.dof_jntid[dof])
        name = model.joint(joint).name or f"joint {joint}"
        multi = int(model.jnt_type[joint]) in (int(mujoco.mjtJoint.mjJNT_FREE), int(mujoco.mjtJoint.mjJNT_BALL))
        still.append(f"{name} (dof {dof})" if multi else name)
    return int(np.count_nonzero(change > threshold)), tuple(still)


# -- options -------------------------------------------------------------------


def parse_dts(spec: Any) -> list[float] | None:
    """--dt: None, a list of seconds, "a,b,c", or a range "LOW:HIGH:N" (N log-spaced values, each snapped to
    HIGH / m for an integer m so that they share checkpoints); returned largest first."""
    if spec is None:
        return None
    if isinstance(spec, str):
        text = spec.strip()
        try:
            if ":" in text:
                low_text, high_text, count_text = text.split(":")
                low, high, count = float(low_text), float(high_text), int(count_text)
                if not (0 < low < high and math.isfinite(high) and count >= 2):
                    raise ValueError
                values = sorted({high / round(high / v) for v in np.geomspace(low, high, count)}, reverse=True)
            else:
                values = [float(v) for v in text.split(",") if v.strip()]
        except ValueError:
            raise BadInputError(
                f"--dt must be seconds 'a,b,c' or a range 'LOW:HIGH:N' with 0 < LOW < HIGH, N >= 2; got {spec!r}"
            ) from None
    else:
        values = [float(v) for v in spec]
    if not values or any(not (math.isfinite(v) and v > 0) for v in values):
        raise BadInputError(f"every dt must be a finite number > 0 s, got {spec!r}")
    return sorted(set(values), reverse=True)


def _check_number(name: str, value: Any, *, allow_zero: bool = False) -> float:
    ok = isinstance(value, (int, float)) and not isinstance(value, bool) and math.isfinite(value)
    if not ok or value < 0 or (value == 0 and not allow_zero):
        bound = ">= 0" if allow_zero else "> 0"
        raise BadInputError(f"{name} must be a finite number {bound}, got {value!r}")
    return float(value)


def _integrators(names: Any) -> list[str]:
    if names is None:
        return list(INTEGRATORS)
    if isinstance(names, str):
        names = [n.strip() for n in names.split(",") if n.strip()]
    names = list(dict.fromkeys(names))
    for name in names:
        integrator_id(name)
    if not names:
        raise BadInputError(f"--integrators needs at least one of {', '.join(INTEGRATORS)}")
    return names


# -- the audit -----------------------------------------------------------------


def audit(
    model_or_path: Any,
    *,
    keyframe: str | int | None = None,
    settle_s: float | None = None,
    tol: float = DEFAULT_TOL,
    integrators: Sequence[str] | str | None = None,
    dt: Sequence[float] | str | None = None,
    duration: float | None = None,
    perturb: float = DEFAULT_PERTURB,
    nthread: int = 0,
    executor: Executor | None = None,
) -> Audit:
    """Audit a model: modes, stability limits, accuracy vs cost, and the cheapest setting meeting `tol`.

    Parameters
    ----------
    model_or_path
        an MjModel, a path to an MJCF (or URDF MuJoCo loads), or a shipped scene name.
    keyframe
        operating point, keyframe name or index (default: the first keyframe, else qpos0 at rest).
    settle_s
        let the model move from there for this long [s] (its own integrator and timestep, controls held)
        and audit it where it comes to rest, or to its steady contact state (None: no settling).
    tol
        tolerance on the error of the module docstring [-], in (0, 1).
    integrators
        names to sweep (default all five), a list or "a,b".
    dt
        timesteps [s] to sweep (see `parse_dts`; default: a 12-point grid over up to 3 decades below 1.2x
        the largest confirmed stability limit, whose top is a multiple of the model's own timestep).
    duration
        simulated time of every run [s] (default 1 s; a scene: its scenario's).
    perturb
        size of the start's perturbation of the operating point [m or rad]; velocities get perturb /
        duration [m/s or rad/s], controls perturb x their half range (`_start`).
    nthread
        threads of the batched runs (0: one per CPU) when no executor is given.
    executor
        where the simulations run (the limit confirmations and brute-force runs, the sweep, the RK4
        reference's levels; springlab.studies.audit.ship): None or a local Executor, this process as always;
        `Executor(workers=N)` or `Executor(scheduler=ADDRESS)`, dask workers, which rebuild the model from
        its file's text and named files (or a scene by name; an MjModel passed in memory cannot be sent:
        BadInputError). The numbers are identical either way; linearization, timings and the
        verification run stay here.

    Returns
    -------
    The Audit. Raises BadInputError for bad input (nothing is computed).
    """
    stamps = {"start": _time.perf_counter()}
    tol = compare.check_tolerance(tol)
    if tol >= 1:
        raise BadInputError(f"tol must be a relative error in (0, 1), got {tol!r}")
    perturb = _check_number("perturb", perturb, allow_zero=True)
    if settle_s is not None:
        settle_s = _check_number("settle", settle_s, allow_zero=True)
    names = _integrators(integrators)
    dts = parse_dts(dt)
    source = load(model_or_path)
    duration = _check_number("duration", duration if duration is not None else source.duration or DEFAULT_DURATION)
    model = source.model
    at = ModelAtPoint.at(model, keyframe, settle_s=settle_s)
    point = at.point
    start, control_offset, start_source = _start(model, point, perturb, duration, source)
    _check_perturbation(model, point, perturb, start)
    distributed = executor is not None and executor.distributed
    run = Runner(executor, ship(source.origin, model) if distributed else None, nthread)
    if distributed:
        assert executor is not None  # distributed implies an executor
        _ = executor.client  # an unreachable scheduler is exit 2 now, not after the limit scan
    own_name, own_dt = _NAMES[int(model.opt.integrator)], float(model.opt.timestep)
    at_point = at.constraints
    seen: Watch = watch(model, start, duration)
    smooth = at_point.smooth and seen.along.smooth
    drift = _drift(at_point, duration)
    point_state = PointReport(
        settle_s=settle_s,
        at_point=at_point,
        along_motion=seen.along,
        at_rest=drift <= REST_FRACTION * max(perturb, 1e-12),
        drift_m=drift,
        linear_map=smooth,
    )
    linear = at.linear
    start_speed = float(np.max(np.abs(start.qvel), initial=0.0)) if start.qvel is not None else 0.0
    gravity = float(np.linalg.norm(model.opt.gravity))
    probe_runs = RunProbe(start, duration, max(seen.peak_speed, start_speed), gravity, duration / 10)
    limits = stability_limits(
        at, list(dict.fromkeys([*names, own_name])), duration, run=run, smooth=smooth, probe=probe_runs
    )
    stamps["limits"] = _time.perf_counter()

    if dts is None:
        # confirmed limits, and the largest timestep brute force found bounded where nothing blew up
        confirmed = [lim.confirmed_limit_s for lim in limits.values() if lim.confirmed_limit_s is not None]
        confirmed += [
            lim.runs_bounded_dt_s
            for lim in limits.values()
            if lim.limit_dt_s is None and lim.runs_blew_up_dt_s is None and lim.runs_bounded_dt_s is not None
        ]
        ceiling = min(GRID_TOP_OVER_LIMIT * max(confirmed), duration / 10) if confirmed else duration / 10
        ceiling = max(ceiling, 10 * duration / GRID_MAX_STEPS)  # never a grid too fine to run
        top = _grid_top(duration, ceiling, own_dt)
        decades = min(GRID_DECADES, math.log10(top * GRID_MAX_STEPS / duration))
        dts = default_grid(top, max(2, round(GRID_POINTS * decades / GRID_DECADES)), decades)
    spacing = checkpoint_spacing(dts, duration)
    run_duration = spacing * math.floor(duration / spacing * (1 + 1e-12))  # every run ends on a common time
    finest = min(dts)
    extra = [(own_name, own_dt), ("rk4", finest)]  # the own setting; the linearity probe and coarsest reference
    outcomes = sweep_runs(model, start, names, dts, run_duration, extra=extra, run=run)
    stamps["sweep"] = _time.perf_counter()

    probe = outcomes[("rk4", finest)]
    moved, still = _excitation(model, start, probe, perturb if start_source != "scenario start" else 0.0)
    excitation = Excitation(
        qpos=perturb if start_source != "scenario start" else 0.0,
        qvel=perturb / duration if start_source != "scenario start" else 0.0,
        ctrl=control_offset,
        moved=moved,
        still=still,
        source=start_source,
    )
    change = math.inf if isinstance(probe, DivergedError) else linearity_change(at, probe)
    threshold = linearity_tolerance(linear, tol, run_duration)
    is_linear = change <= threshold and smooth  # with constraints active the linear solution is no reference
    reference: Reference
    if is_linear:
        reference = ExactReference(at, start)
    else:
        step = reference_step(dts, spacing)
        coarse = probe if isinstance(probe, Trajectory) else None
        reference = converged_reference(at, start, step, run_duration, tol, coarse=coarse, run=run)
    stamps["reference"] = _time.perf_counter()

    runs = []
    middle = sorted(dts)[len(dts) // 2]
    costs = {name: cost_per_step(model, start, name, middle) for name in dict.fromkeys([*names, own_name])}
    for name in names:
        for dt_run in dts:
            error = run_error(at, outcomes[(name, dt_run)], reference)
            steps = round(run_duration / dt_run)
            runs.append(SweepRun(name, dt_run, steps, error, costs[name] * steps, error is None))
    orders = {name: _order([r for r in runs if r.integrator == name], reference.error_estimate) for name in names}
    own_outcome = outcomes[(own_name, own_dt)]
    own_error = run_error(at, own_outcome, reference)
    own_limit = limits[own_name]
    own = OwnSetting(
        integrator=own_name,
        dt=own_dt,
        stable=not isinstance(own_outcome, DivergedError) and not _blows_up(model, own_limit, own_dt, probe_runs, run),
        error=own_error,
        margin=own_limit.margin,
        wall_time_s=costs[own_name] * round(run_duration / own_dt),
        margin_confirmed=None if own_limit.limit_dt_s is None else bool(own_limit.confirmed),
    )
    if excitation.any_motion:
        recommendation = _recommend(at, start, runs, limits, tol, run_duration, reference)
    else:  # every setting reproduces a model that does not move: nothing to verify
        recommendation = Recommendation(None, None, None, tol, False, None)
    stamps["end"] = _time.perf_counter()
    return Audit(
        model=source.label,
        linear=linear,
        start=start,
        duration=run_duration,
        tol=tol,
        perturb=perturb,
        stability=MappingProxyType(limits),
        own=own,
        constraints=tuple(constraint_flags(model, own_dt)),
        is_linear=is_linear,
        linearity=Linearity(change, threshold),
        reference=ReferenceUsed(
            kind=reference.kind,
            error_estimate=reference.error_estimate,
            dt=reference.dt,
            converged=reference.error_estimate <= REFERENCE_FRACTION * tol,
            compared_at=f"every step of each run (every k-th for at most {MAX_SAMPLES})",
            common_time_spacing_s=spacing,
        ),
        runs=tuple(runs),
        orders=MappingProxyType(orders),
        pareto=tuple(_pareto(runs)),
        recommendation=recommendation,
        timings=Timings(
            linearization_and_limits_s=stamps["limits"] - stamps["start"],
            sweep_s=stamps["sweep"] - stamps["limits"],
            reference_s=stamps["reference"] - stamps["sweep"],
            total_s=stamps["end"] - stamps["start"],
        ),
        point_state=point_state,
        excitation=excitation,
    )


def _blows_up(model: mujoco.MjModel, limit: Limit, own_dt: float, probe: RunProbe, run: Runner) -> bool:
    """Whether a brute-force run at the model's own timestep blows up: read off the brute force's
    bracket when the limit came from runs (the own timestep is their first), else run it when the own
    timestep is at or above a confirmed limit; never from an unconfirmed figure alone."""
    if limit.method == "nonlinear runs":
        return limit.runs_bounded_dt_s is None or limit.runs_bounded_dt_s < own_dt
    confirmed = limit.confirmed_limit_s
    if confirmed is None or own_dt < confirmed:
        return False
    outcome = run([Job(model, limit.integrator, own_dt, probe.steps(own_dt), probe.start)])[0]
    return probe.blew_up(outcome, own_dt)


def _grid_top(duration: float, ceiling: float, own_dt: float) -> float:
    """The default grid's largest timestep [s]: duration / J for the fewest intervals J that keep it at most
    `ceiling` [s], with J dividing duration / own_dt when that is an integer (so the model's own timestep
    divides it and is compared at the same checkpoints)."""
    fewest = max(1, math.ceil(duration / ceiling * (1 - 1e-12)))
    own_steps = duration / own_dt
    if abs(own_steps - round(own_steps)) <= 1e-9 * own_steps and own_dt <= ceiling:
        steps = round(own_steps)
        divisors = [j for j in range(fewest, steps + 1) if steps % j == 0]
        return duration / divisors[0]
    return duration / fewest


def _as_runs(runs: list[SweepRun]) -> list[Run]:
    return [Run(r.integrator, r.dt, r.steps, r.error, r.wall_time_s, diverged=r.diverged) for r in runs]


def _order(runs: list[SweepRun], reference_error: float) -> float | None:
    """springlab.studies.tradeoff's observed order over the runs clear of the error floor.

    The floor: the reference's own error estimate, or where the errors stop falling at the fine end (from
    the finest run, coarser runs whose error is not at least sqrt(dt ratio) above the next finer one's: a
    first-order method rises by the full ratio). Runs within 10x the floor are left out: there the
    reference or round-off, not the integrator, sets the error.
    """
    # (dt [s], error [-]) of the runs with an error, finest first
    finest_first = sorted(((r.dt, r.error) for r in runs if r.error is not None and r.error > 0), key=lambda p: p[0])
    floor = reference_error
    for (finer_dt, finer_error), (coarser_dt, coarser_error) in zip(finest_first, finest_first[1:]):
        if coarser_error > finer_error * math.sqrt(coarser_dt / finer_dt):
            break
        floor = max(floor, finer_error, coarser_error)
    return observed_order([r for r in _as_runs(runs) if r.max_rel_error is None or r.max_rel_error > 10 * floor])


def _pareto(runs: list[SweepRun]) -> list[SweepRun]:
    front = {(r.integrator, r.dt) for r in pareto_front(_as_runs(runs))}
    chosen = [r for r in runs if (r.integrator, r.dt) in front]
    return sorted(chosen, key=lambda r: r.wall_time_s)


def _recommend(
    at: ModelAtPoint,
    start: Setup,
    runs: list[SweepRun],
    limits: Mapping[str, Limit],
    tol: float,
    duration: float,
    reference: Reference,
) -> Recommendation:
    """The cheapest swept setting meeting tol within RECOMMEND_LIMIT_FRACTION of its stability limit,
    verified by a run of its own (springlab.sim.simulate, not the batch). Meeting tol means error + the
    reference's own error estimate <= tol, so a reference that did not fully converge cannot pass a
    setting that misses tol."""
    budget = tol - reference.error_estimate
    candidates = sorted(
        (
            r
            for r in runs
            if r.error is not None
            and r.error <= budget
            and ((limit := limits[r.integrator].limit_dt_s) is None or r.dt <= RECOMMEND_LIMIT_FRACTION * limit)
        ),
        key=lambda r: r.wall_time_s,
    )
    for run in candidates:
        try:
            trajectory = simulate(
                at.model.__copy__(),
                integrator=run.integrator,
                dt=run.dt,
                duration=duration,
                qpos=start.qpos,
                qvel=start.qvel,
                act=start.act,
                control=start.control,
            )
        except DivergedError:
            continue
        error = run_error(at, trajectory, reference)
        if error is not None and error <= budget:
            return Recommendation(run.integrator, run.dt, error, tol, True, run.wall_time_s)
    return Recommendation(None, None, None, tol, False, None)
