"""What every scene provides, and the shared machinery to build and check it.

A scene is one MJCF file under models/ and one module of the same name under
springlab/scenes/. The module subclasses `Scene` and says:

* its parameters (SI, with units and valid ranges) and which MJCF values they
  read back from the compiled model as defaults;
* its scenarios (named questions, with parameter presets and a duration);
* how parameters edit the model (MjSpec edits, so the physics stays in MJCF);
* the initial state and the open-loop control sequence of a scenario;
* the exact reference where one exists, and the scenario's named quantities.

Data flows one way: parameters -> MjModel -> Trajectory -> (reference, errors)
-> summary, plots and video.
"""

from __future__ import annotations

import dataclasses
import functools
import math
from collections.abc import Callable, Mapping
from typing import Any

import mujoco
import numpy as np

from springlab.errors import ParameterError, UnknownNameError
from springlab.exact.limits import stability_limit
from springlab.sim import model_files
from springlab.sim.simulate import Setup, Trajectory, quiet_mujoco

from .capabilities import (
    DesignSpec,
    DryFrictionSpec,
    FigureHook,
    FitSpec,
    FrequencySpec,
    InteractiveSpec,
    OscillatorSpec,
    RefinableSpec,
)

#: smallest body mass [kg] and principal inertia [kg m^2] MuJoCo compiles: its mjMINVAL
#: (1e-15); a moving body below it fails `MjSpec.compile` ("must be larger than mjMINVAL")
MIN_MASS = float(mujoco.mjMINVAL)
#: why a mass-like parameter stops at MIN_MASS, for its error message
MIN_MASS_REASON = "MuJoCo cannot compile a body whose mass or principal inertia is below its mjMINVAL = 1e-15"


@functools.lru_cache(maxsize=64)
def parsed_spec(path: str) -> mujoco.MjSpec:
    """The MjSpec of an MJCF file, parsed once per process and path; callers edit a `.copy()`, never this.

    Why: parsing the XML costs about 1.5 ms, a copy of the parsed spec 0.02 ms, and every
    `springlab run` (and every configuration of a sweep) builds its model from a fresh spec.
    """
    with quiet_mujoco():
        return mujoco.MjSpec.from_file(path)


@dataclasses.dataclass(frozen=True)
class Parameter:
    """A scene parameter in SI units.

    Attributes
    ----------
    name
        as used by `--set NAME=VALUE` and keyword arguments.
    unit
        SI unit, e.g. 'kg', 'N/m', 'N s/m', 'm', 'm/s', 'Hz', '-' for none.
    description
        one line.
    minimum
        lowest valid value (None: unbounded).
    minimum_inclusive
        whether `minimum` itself is valid.
    maximum
        highest valid value (None: unbounded).
    default
        default value, or None when it is read back from the model.
    reason
        why the range is what it is (added to the error message), e.g. MIN_MASS_REASON.
    """

    name: str
    unit: str
    description: str
    minimum: float | None = None
    minimum_inclusive: bool = True
    maximum: float | None = None
    default: float | None = None
    reason: str = ""

    def valid_range(self) -> str:
        """Human-readable valid range, e.g. '> 0 kg'."""
        unit = "" if self.unit == "-" else f" {self.unit}"
        parts = []
        if self.minimum is not None:
            parts.append(f"{'>=' if self.minimum_inclusive else '>'} {self.minimum:g}")
        if self.maximum is not None:
            parts.append(f"<= {self.maximum:g}")
        return (" and ".join(parts) or "any finite value") + unit

    def check(self, value: Any) -> float:
        """Return `value` as a float, or raise ParameterError saying what is valid."""
        try:
            number = float(value)
        except (TypeError, ValueError):
            raise ParameterError(f"{self.name} must be a number {self.valid_range()}, got {value!r}") from None
        low_ok = self.minimum is None or number > self.minimum or (self.minimum_inclusive and number == self.minimum)
        high_ok = self.maximum is None or number <= self.maximum
        if not math.isfinite(number) or not low_ok or not high_ok:
            why = f" ({self.reason})" if self.reason else ""
            raise ParameterError(f"{self.name} must be a finite number {self.valid_range()}{why}, got {value!r}")
        return number


@dataclasses.dataclass(frozen=True)
class Scenario:
    """A named question a scene answers.

    Attributes
    ----------
    name
        scenario name.
    description
        one line.
    duration
        default simulated time [s].
    presets
        parameter values this scenario sets (user overrides win).
    derive
        optional function(params, explicitly_set_names) -> extra values,
        for presets that depend on other parameters (e.g. damping from a ratio).
    exact
        whether an exact reference exists (validated by `validate`).
    dt
        the scenario's validated timestep [s] (None: the scene's `dt`).
    variant
        for a scene whose scenarios differ in their model (e.g. the car: 1 DOF,
        pitch/heave, quarter car), the object that carries what differs; the scene's
        hooks delegate to it instead of dispatching on scenario names (None: unused).
    """

    name: str
    description: str
    duration: float
    presets: Mapping[str, float] = dataclasses.field(default_factory=dict)
    derive: Callable[[dict[str, float], set[str]], dict[str, float]] | None = None
    exact: bool = True
    dt: float | None = None
    variant: Any = None


@dataclasses.dataclass
class Reference:
    """The exact solution of a scenario at the trajectory's times.

    Attributes
    ----------
    pos, vel
        joint name -> exact position [m or rad] and velocity [m/s or rad/s].
    system
        for linear scenes, the matrix A [1/s] of the autonomous system
        z' = A z that generated the reference (forcing included as generator
        states); None otherwise. Used to derive the error bound.
    states
        (n, dim) exact z(t), or None.
    rows
        joint name -> (row of its position, row of its velocity) in z.
    tolerance
        for scenes without `system`, the relative tolerance [-] every
        compared column is held to, and `tolerance_basis` says why.
    switches
        for a linear scene whose input is switched on a step boundary:
        [(time [s], A after it)], in time order; `system` holds before the first.
        The states z(t) stay continuous across a switch.
    input_error
        column -> exact max absolute difference [m or m/s] between the
        responses to the input the model realizes and the true input, added to
        that column's tolerance (`tolerance_basis` says where it comes from).
    scales
        column -> the scale [m or m/s] its max_rel is relative to where the exact motion
        has none (max |ref| = 0: a block held at rest); otherwise max |ref| is.
    """

    pos: dict[str, np.ndarray]
    vel: dict[str, np.ndarray]
    system: np.ndarray | None = None
    states: np.ndarray | None = None
    rows: dict[str, tuple[int, int]] = dataclasses.field(default_factory=dict)
    tolerance: float | None = None
    tolerance_basis: str = ""
    switches: list[tuple[float, np.ndarray]] = dataclasses.field(default_factory=list)
    input_error: dict[str, float] = dataclasses.field(default_factory=dict)
    scales: dict[str, float] = dataclasses.field(default_factory=dict)


@dataclasses.dataclass(frozen=True)
class Check:
    """A validated scalar claim of a scenario: a measured value against an independent reference.

    For scenes without an exact trajectory (non-linear ones), `validate` holds a
    scenario to its checks instead of (or besides) the compared columns.

    Attributes
    ----------
    name
        what is checked, ending in its unit like a quantity, e.g. 'period_s'.
    value
        measured from the simulation (in the name's unit).
    reference
        the independent expectation (closed form, quadrature, ...).
    tolerance
        bound on `error` [-]: relative, or absolute in the name's unit
        when the reference is 0.
    basis
        why the tolerance is what it is (one line).
    certifies_error
        whether `error` is an error of a physical result, which a PASS
        without a requested tolerance certifies only up to springlab.runs.compare.CERTIFIED_CAP
        (False for a diagnostic, e.g. an observed order of convergence against the
        integrator's).
    follows_tol
        a relative error [-] held to the run's own tolerance: the requested tolerance when
        there is one (`tolerance` then gives way to it), else `tolerance`.
    """

    name: str
    value: float
    reference: float
    tolerance: float
    basis: str
    certifies_error: bool = True
    follows_tol: bool = False

    @property
    def error(self) -> float:
        """|value - reference| / |reference|, or |value - reference| when the reference is 0."""
        difference = abs(float(self.value) - float(self.reference))
        return difference / abs(float(self.reference)) if self.reference != 0 else difference

    @property
    def passed(self) -> bool:
        """Whether the error is within the tolerance (False for a non-finite value)."""
        return bool(math.isfinite(self.error) and self.error <= self.tolerance)

    def to_dict(self) -> dict[str, Any]:
        """The summary.json form: name, value, reference, error, tolerance, basis, passed."""
        return {
            "name": self.name,
            "value": float(self.value),
            "reference": float(self.reference),
            "error": self.error,
            "tolerance": float(self.tolerance),
            "basis": self.basis,
            "passed": self.passed,
        }


class Scene:
    """Base class of the scenes: one MJCF file under models/ and one module of the same name.

    Like scipy's `OdeSolver`, a new scene is a subclass that provides the following.

    1. Class attributes: `name` (also the MJCF stem: models/<name>.xml), `title` (the one-line
       question), `joints` (the reported joints, trajectory.csv's columns), `parameters`
       (name -> `Parameter`, SI with units and valid ranges), `scenarios` (name -> `Scenario`,
       each with its duration, presets and validated `dt`; a scene whose scenarios differ in their
       model gives each its `variant` instead of dispatching on names), `default_scenario`, and
       the validated default setting `integrator` and `dt` [s]; optionally `camera`.
    2. `model_defaults(model)`: the parameters whose defaults live in the MJCF, read back from the
       compiled model (the physics values have one home, the MJCF).
    3. `edit(spec, params, scenario)`: MjSpec edits that apply the parameters, so the physics
       stays in MJCF (no Python forces; time-varying inputs as MJCF-native generators or
       piecewise-constant controls switched on step boundaries, see springlab.sim.exciter).
    4. `setup(model, params, scenario, steps, dt)`: the initial state and open-loop controls
       (`Setup`); raise ParameterError for a motion the scene's equations cannot describe
       when that is known before the run.
    5. `physical(model)`: the physical constants the scene's equations use, read back from the
       compiled model (SI; the order is the scene's, documented in its override).
    6. `modes(model, params, scenario)`: [(natural frequency [rad/s], damping ratio [-])] of every
       mode the integrator must resolve (forcing generators included), for stability advice.
    7. `reference(model, params, scenario, time)`: the exact solution at `time` [s] where one
       exists (`Reference`; for a linear scene with its state matrix, so the tolerance is
       derived), else None and `checks(...)`: scalar claims against independent references
       (`Check`; builders in springlab.scenes.checks).
    8. `quantities(model, params, scenario, trajectory)`: the scenario's named results, SI,
       names ending in their unit; peaks and event times interpolated between the samples to
       the run's order (springlab.exact.events).
    9. Optionally: `check_consistency` (non-physical parameter combinations), `model_limits`
       (where a finished run leaves the scene's equations), `stop_condition` (an event that
       ends a run early as a result), `stability_limit` (damping MuJoCo treats differently from
       joint damping), `phase_field`/`equilibria`/`separatrices` (one-joint phase planes),
       `joint_columns` (joints that only some scenarios have).
    10. Capabilities the studies read (springlab.scenes.capabilities): `fit`, how `springlab fit`
       identifies the scene from a record (an `OscillatorFit` or a `PolynomialFit`; None: it cannot);
       `design`, the design question the scene answers (`DesignSpec`: swept properties, fixed ones,
       the figure of merit and the hooks that simulate and estimate it; springlab.studies.design);
       `refinable`, the model's size is a parameter and which quantities converge to which continuum
       values (`RefinableSpec`; springlab.studies.refine); `figure`, the panels of the scene's own
       figure of a run (a `FigureHook`; springlab.plots.run.scene_figure).
    11. Optionally, `oscillator` (springlab.scenes.capabilities.OscillatorSpec): the scene is the
       textbook's one-mode mass-spring-damper, the unit oscillator of `springlab stability`.
    12. Optionally, `dry_friction` (springlab.scenes.capabilities.DryFrictionSpec): the scene's dry
       friction has exact Coulomb answers and takes MuJoCo's friction settings as parameters, which
       `springlab friction-settings` sweeps (springlab.studies.friction_settings).
    13. Optionally, `frequency` (springlab.scenes.capabilities.FrequencySpec, or a tuple of them, one per
       scenario, the first the default): the default input and response of `springlab frequency SCENE`, an
       MjSpec edit that makes the input a control, and what the response means for the scene's question.
    14. Optionally, `interactive` (springlab.scenes.capabilities.InteractiveSpec): the scenarios that run
       in the browser with real MuJoCo and the MJCF attributes the page writes (`springlab interactive`).

    The module exposes the instance as `SCENE`; springlab.scenes discovers it. Tests check each
    claim against a reference built in the test (closed form, expm, scipy's DOP853 at tight
    rtol), never against the scene's own reference.
    """

    #: scene name, also the MJCF file stem under models/.
    name: str = ""
    #: one-line question the scene answers.
    title: str = ""
    #: joints whose pos/vel are reported (columns of trajectory.csv).
    joints: tuple[str, ...] = ()
    parameters: Mapping[str, Parameter] = {}
    scenarios: Mapping[str, Scenario] = {}
    default_scenario: str = ""
    #: the validated default setting.
    integrator: str = "rk4"
    dt: float = 1e-3
    #: named camera for rendering.
    camera: str | None = None
    #: scenario -> (the textbook question it answers, the answer as one sentence): the answer is a
    #: str.format template over the run's quantities and parameters, e.g. "... {period_s:.3g} s ..."
    questions: dict[str, tuple[str, str]] = {}
    #: how `springlab fit` identifies the scene from a recorded signal (None: it cannot be fitted)
    fit: FitSpec | None = None
    #: the scene is the textbook's one-mode mass-spring-damper: its parameter, scenario and joint names
    #: (None: it is not one)
    oscillator: OscillatorSpec | None = None
    #: the design question the scene answers (None: none; springlab.studies.design reads it)
    design: DesignSpec | None = None
    #: exact dry-friction cases and MuJoCo's friction settings as parameters (None: none;
    #: springlab.studies.friction_settings reads it)
    dry_friction: DryFrictionSpec | None = None
    #: the model's size is a parameter: how much model a question needs (None: fixed size;
    #: springlab.studies.refine reads it)
    refinable: RefinableSpec | None = None
    #: the panels of the scene's own figure of a run (None: none; springlab.plots.run.scene_figure draws it)
    figure: FigureHook | None = None
    #: the default input and response of its frequency response (None: the user names them;
    #: springlab.studies.frequency reads it)
    frequency: FrequencySpec | tuple[FrequencySpec, ...] | None = None
    #: the scenarios that run in the browser and how the page edits the MJCF (None: none;
    #: springlab.render.interactive reads it)
    interactive: InteractiveSpec | None = None

    def question_and_answer(self, scenario: str, quantities: dict, parameters: dict) -> tuple[str, str] | None:
        """(question, answer sentence) of a scenario's run, or None where the scene states none."""
        if scenario not in self.questions:
            return None
        question, template = self.questions[scenario]
        try:
            return question, template.format_map({**parameters, **quantities})
        except (KeyError, ValueError, TypeError, IndexError):  # a quantity the run did not produce
            return question, ""

    # -- names ---------------------------------------------------------------

    def scenario(self, name: str | None) -> Scenario:
        """The scenario called `name` (None: the default one)."""
        name = self.default_scenario if name is None else name
        if name not in self.scenarios:
            raise UnknownNameError(f"scenario of {self.name}", name, self.scenarios)
        return self.scenarios[name]

    def model_spec(self) -> mujoco.MjSpec:
        """A fresh MjSpec of this scene's MJCF: a copy of the parsed file (parsed once per process)."""
        return parsed_spec(str(model_files.path(self.name))).copy()

    # -- parameters ----------------------------------------------------------

    def model_defaults(self, model: mujoco.MjModel) -> dict[str, float]:
        """Parameter defaults read back from the compiled MJCF (override)."""
        return {}

    @functools.cache  # noqa: B019 - scenes are module-level singletons, never freed
    def _mjcf_defaults(self) -> dict[str, float]:
        with quiet_mujoco():
            return self.model_defaults(self.model_spec().compile())

    def resolve(self, scenario: Scenario, overrides: Mapping[str, Any]) -> dict[str, float]:
        """Final parameter values: MJCF defaults < scenario presets < overrides.

        Raises
        ------
        UnknownNameError
            an override names no parameter of this scene.
        ParameterError
            a value is not a finite number in its valid range.
        """
        for name in overrides:
            if name not in self.parameters:
                raise UnknownNameError(f"parameter of {self.name}", name, self.parameters)
        checked = {name: self.parameters[name].check(v) for name, v in overrides.items()}
        values = {p.name: p.default for p in self.parameters.values() if p.default is not None}
        values.update(self._mjcf_defaults())
        values.update(scenario.presets)
        values.update(checked)
        if scenario.derive is not None:
            derived = scenario.derive(dict(values), set(checked))
            values.update({k: v for k, v in derived.items() if k not in checked})
        values = {name: self.parameters[name].check(v) for name, v in values.items()}
        self.check_consistency(values, scenario)
        return values

    def check_consistency(self, params: dict[str, float], scenario: Scenario) -> None:
        """Raise ParameterError for combinations that are non-physical (override)."""

    # -- model and run -------------------------------------------------------

    def edit(self, spec: mujoco.MjSpec, params: dict[str, float], scenario: Scenario) -> None:
        """Apply parameters to the spec (override)."""

    def build(self, params: dict[str, float], scenario: Scenario) -> mujoco.MjModel:
        """Compile the model for these parameters and scenario."""
        spec = self.model_spec()
        self.edit(spec, params, scenario)
        with quiet_mujoco():
            try:
                return spec.compile()
            except ValueError as error:
                # a backstop: each parameter's range should catch this first (tests/test_cli_inputs.py)
                reason = str(error).splitlines()[0].removeprefix("Error: ")
                raise ParameterError(
                    f"MuJoCo cannot compile {self.name} {scenario.name} with these parameters: {reason}"
                ) from None

    def setup(
        self, model: mujoco.MjModel, params: dict[str, float], scenario: Scenario, steps: int, dt: float
    ) -> Setup:
        """Initial state and controls of a run (override)."""
        return Setup()

    def reference(
        self, model: mujoco.MjModel, params: dict[str, float], scenario: Scenario, time: np.ndarray, *, dt: float
    ) -> Reference | None:
        """Exact solution at `time` [s] of a run with timestep `dt` [s], or None where none exists (override).

        `dt` is explicit, never read back from `model.opt.timestep`: an input switched on the
        step grid (a bang-bang move, the end of a road bump) is placed on the run's own grid,
        and one model may serve runs at many timesteps (a sweep).
        """
        return None

    def quantities(
        self,
        model: mujoco.MjModel,
        params: dict[str, float],
        scenario: Scenario,
        trajectory: Trajectory,
    ) -> dict[str, Any]:
        """Named results of the scenario, SI, names ending in their unit (override)."""
        return {}

    def physical(self, model: mujoco.MjModel) -> tuple[float, ...]:
        """The physical constants the scene's equations use, read back from the compiled model (SI).

        The order is the scene's (e.g. the slider's (mass [kg], stiffness [N/m], damping [N s/m]));
        none by default.
        """
        return ()

    def modes(self, model: mujoco.MjModel, params: dict[str, float], scenario: Scenario) -> list[tuple[float, float]]:
        """[(natural frequency [rad/s], damping ratio [-])] of the run, for stability advice."""
        return []

    def stability_limit(
        self,
        model: mujoco.MjModel,
        params: dict[str, float],
        scenario: Scenario,
        integrator: str,
        omega: float,
        zeta: float,
    ) -> float:
        """Largest omega*dt [-] at which `integrator` is stable on the mode (omega [rad/s], zeta [-]).

        Default: simulate.stability_limit, which assumes the damping is joint damping;
        a scene whose damping MuJoCo treats differently (e.g. tendon damping) overrides this.
        """
        return stability_limit(integrator, zeta)

    def phase_field(
        self, model: mujoco.MjModel, params: dict[str, float], scenario: Scenario
    ) -> Callable[[np.ndarray, np.ndarray], tuple[np.ndarray, np.ndarray]] | None:
        """For a scene with one reported joint: (x [m], v [m/s]) -> (dx/dt [m/s], dv/dt [m/s^2])
        of the unforced equations of motion, for phase-plane vector fields (None: no plane)."""
        return None

    def equilibria(self, model: mujoco.MjModel, params: dict[str, float], scenario: Scenario) -> list[dict]:
        """Equilibria of the unforced motion: [{"x": position [m], "stable": bool}]."""
        return []

    def separatrices(
        self, model: mujoco.MjModel, params: dict[str, float], scenario: Scenario
    ) -> list[tuple[np.ndarray, np.ndarray]]:
        """Separatrix curves of the unforced phase plane: [(x [m], v [m/s]) arrays] (none by default)."""
        return []

    def checks(
        self,
        model: mujoco.MjModel,
        params: dict[str, float],
        scenario: Scenario,
        trajectory: Trajectory,
    ) -> list[Check]:
        """Scalar claims `validate` holds an exact scenario to, beyond its compared columns (override)."""
        return []

    def model_limits(
        self,
        model: mujoco.MjModel,
        params: dict[str, float],
        scenario: Scenario,
        trajectory: Trajectory,
    ) -> list[str]:
        """Where this run leaves the range the scene's equations describe, one line each (override).

        E.g. a linear tire that would have to pull on the road: the simulation may still match its
        exact reference, but neither describes the physical system any more. Any line makes the run
        not validated (`passed` False, exit 1) and is reported in summary.json's `model_limits`.
        """
        return []

    def stop_condition(
        self, model: mujoco.MjModel, params: dict[str, float], scenario: Scenario
    ) -> Callable[[np.ndarray, np.ndarray], np.ndarray] | None:
        """An event that ends a run early: (qpos (n, nq), qvel (n, nv)) -> (n,) bool, True once it
        has happened (e.g. a mass escaping to infinity in finite time). The run is cut at the first
        such step and is a result, not a divergence. None: runs last their full duration."""
        return None

    def joint_columns(self, model: mujoco.MjModel, trajectory: Trajectory) -> dict[str, tuple[np.ndarray, np.ndarray]]:
        """Reported joint name -> (position, velocity) series of a trajectory."""
        columns = {}
        for joint in self.joints:
            j = model.joint(joint)
            columns[joint] = (trajectory.qpos[:, j.qposadr[0]], trajectory.qvel[:, j.dofadr[0]])
        return columns
