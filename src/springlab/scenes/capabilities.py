"""What a scene can do for the studies, declared on its `Scene` and read by them (a study never names a scene).

Each capability is a small frozen data object, with hooks where a scene's own physics must answer
(implemented in the scene's folder). The studies hold the general machinery and read only these.
"""

from __future__ import annotations

import ast
import dataclasses
from collections.abc import Callable, Hashable, Mapping
from typing import Any, ClassVar, Protocol, TypeAlias, TypeVar

import mujoco
import numpy as np

from springlab.sim.simulate import Trajectory

from .declarations import Scenario

T = TypeVar("T")


class CaseView(Protocol):
    """What a capability hook reads of the case it is given: a springlab.scenes.base.Case.

    A Protocol, not the class: the scenes' base declares its capabilities with the types below, so this
    module cannot import it back.
    """

    @property
    def scenario(self) -> Scenario:
        """The scenario."""
        ...

    @property
    def params(self) -> dict[str, float]:
        """Parameter name -> value (SI), resolved."""
        ...

    @property
    def model(self) -> mujoco.MjModel:
        """The compiled model."""
        ...

    def memo(self, key: Hashable, compute: Callable[[], T]) -> T:
        """`compute()` once per case (Case.memo)."""
        ...


# -- fit: identification from a recorded signal (springlab.studies.fit) ----------------------------------

#: the fit's names of the observed coordinate's state at the record's start
INITIAL_STATE_NAMES = ("x0", "v0")


@dataclasses.dataclass(frozen=True)
class OscillatorFit:
    """A scene one coordinate x of which rings as one mode: m x'' + d x' + k (x - x_eq) = F.

    `springlab fit` identifies the mode's k, d (and m where the scene has it as a parameter), or
    its omega_n, zeta, from a record of x, x' or x''; the identifiability rules, the start, the
    optimization and the cross-check against the closed form are the study's.

    Attributes
    ----------
    joint
        the measured joint, the coordinate x (records carry `<joint>_pos` [m], `_vel` [m/s] or `_acc` [m/s^2]).
    scenarios
        the scenarios a record can be fitted with; the first is the default.
    mass, stiffness, damping
        the scene's parameter names of the mode's m [kg], k [N/m], d [N s/m]; `mass` None: the mode's
        mass is derived from other parameters by `mode_mass` and cannot be freed.
    default_free
        the free names when the user names none.
    signals
        the signal kinds it fits: 'pos', 'vel', 'acc'.
    rest
        the scene parameter holding x_eq [m], the coordinate's unforced rest position (None: 0).
    step_forces
        scenario -> the scene parameter holding the constant force F [N] it applies from t = 0 (a step
        response); every other scenario is a free decay (F = 0).
    mode_mass
        hook: the scene's parameters -> the mode's mass m [kg] (None: the parameter `mass`).
    initial_state
        hook: (the candidate's Case, x0 [m], v0 [m/s]) -> (qpos, qvel) with the coordinate at x0, v0
        (None: the joint set, the rest of the scene at qpos0 and at rest).
    release
        hook for a scene whose initial state is not its parameters x0, v0 (its runs start at rest):
        (the identified scene's run parameters, x0 [m]) -> the run parameters that start it at rest at
        x0 (None: x0 and v0 are parameters of the scene).
    """

    kind: ClassVar[str] = "oscillator"

    joint: str
    scenarios: tuple[str, ...]
    mass: str | None = "mass"
    stiffness: str = "stiffness"
    damping: str = "damping"
    default_free: tuple[str, ...] = ("omega_n", "zeta", "x0", "v0", "offset")
    signals: tuple[str, ...] = ("pos", "vel", "acc")
    rest: str | None = None
    step_forces: Mapping[str, str] = dataclasses.field(default_factory=dict)
    mode_mass: Callable[[Mapping[str, float]], float] | None = None
    initial_state: Callable[[CaseView, float, float], tuple[np.ndarray, np.ndarray]] | None = None
    release: Callable[[Mapping[str, float], float], dict[str, float]] | None = None

    def __post_init__(self) -> None:
        if self.mass is None and self.mode_mass is None:
            raise ValueError("an OscillatorFit without a mass parameter needs a mode_mass hook")


@dataclasses.dataclass(frozen=True)
class PolynomialFit:
    """A scene that drives one coordinate along x(t) = sum_n c_n t^n / n! (n <= 3), c_n its n-th derivative at t = 0.

    `springlab fit` identifies the coefficients (the scene's parameters) from a record of x, x' or x'',
    choosing the degree or taking `--degree`; differentiation loses c_0 from velocity data and c_0, c_1
    from acceleration data.

    Attributes
    ----------
    joint
        the measured joint, the coordinate x.
    scenarios
        the scenarios a record can be fitted with; the first is the default.
    coefficients
        the scene's parameter names of c_0 [m], c_1 [m/s], ... in ascending power: two to four of
        them, the first two x0 and v0 (the fit's names of the initial state).
    signals
        the signal kinds it fits: 'pos', 'vel', 'acc'.
    """

    kind: ClassVar[str] = "polynomial"

    joint: str
    scenarios: tuple[str, ...]
    coefficients: tuple[str, ...]
    signals: tuple[str, ...] = ("pos", "vel", "acc")

    def __post_init__(self) -> None:
        names = self.coefficients
        if not 2 <= len(names) <= 4 or names[:2] != INITIAL_STATE_NAMES:
            raise ValueError(f"a PolynomialFit has 2 to 4 coefficients starting with x0, v0; got {', '.join(names)}")


#: what `Scene.fit` may declare (None: the scene cannot be fitted)
FitSpec: TypeAlias = OscillatorFit | PolynomialFit


# -- the unit oscillator (springlab.studies.stability, springlab.studies.extremes) -------------------------


@dataclasses.dataclass(frozen=True)
class OscillatorSpec:
    """A scene that is the textbook's one-mode mass-spring-damper m x'' + d x' + k x = 0 (`Scene.oscillator`).

    springlab.studies.stability and springlab.studies.extremes run it as a unit oscillator and at
    extreme values: they pick the scene that declares this and set its parameters by these names.
    The declaring scene has one degree of freedom in its free scenario, an exact reference for it,
    and joint damping (which MuJoCo's euler, implicit and implicitfast treat implicitly).

    Attributes
    ----------
    mass, stiffness, damping
        names of the scene's parameters m [kg], k [N/m] and d [N s/m].
    x0, v0
        names of its initial position [m] and velocity [m/s] parameters.
    free
        the scenario in which it is released from (x0, v0) without forcing.
    joint
        its one joint: the model's qpos[0] and qvel[0], and the reference's column.
    """

    mass: str
    stiffness: str
    damping: str
    x0: str
    v0: str
    free: str
    joint: str

    def parameters(
        self,
        *,
        mass: float | None = None,
        stiffness: float | None = None,
        damping: float | None = None,
        x0: float | None = None,
        v0: float | None = None,
    ) -> dict[str, float]:
        """The scene's parameter overrides for m [kg], k [N/m], d [N s/m], x0 [m] and v0 [m/s], by its names
        (a value left None is left out: the scene's default holds)."""
        values = {self.mass: mass, self.stiffness: stiffness, self.damping: damping, self.x0: x0, self.v0: v0}
        return {name: value for name, value in values.items() if value is not None}

    def constants(self, model: mujoco.MjModel) -> tuple[float, float, float]:
        """(m [kg], k [N/m], d [N s/m]) read back from the compiled model: the mass of the joint's body, the
        joint's stiffness and its degree of freedom's damping."""
        joint = model.joint(self.joint)
        dof = int(joint.dofadr[0])
        mass = float(model.body_mass[int(model.jnt_bodyid[joint.id])])
        return mass, float(model.jnt_stiffness[joint.id]), float(model.dof_damping[dof])


# -- design: the design question a scene answers (springlab.studies.design) --------------------------


@dataclasses.dataclass(frozen=True)
class DesignProperty:
    """A property the design study varies, log-uniformly about its value at the scene's parameters.

    Attributes
    ----------
    name
        the property's name (a scene parameter, or a property derived from several, e.g. a damping ratio).
    unit
        SI unit, '-' for none.
    span
        the study spans default x span^[-1, 1] [-] (> 1).
    label
        axis label with symbol and unit, e.g. 'belt stiffness k [N/m]'.
    parameter
        the scene parameter that sets the property when it is not one itself ('' when it is); then
        `DesignHooks.parameters_for` converts a value of it into that parameter.
    description
        the property in words, e.g. 'damping ratio' (messages).
    minimum
        the lowest value a derived property may be given [its unit] (None: unbounded).
    """

    name: str
    unit: str
    span: float
    label: str
    parameter: str = ""
    description: str = ""
    minimum: float | None = None

    @property
    def derived(self) -> bool:
        """Whether the property is derived from a scene parameter rather than being one."""
        return bool(self.parameter) and self.parameter != self.name

    @property
    def source(self) -> str:
        """The scene parameter that sets the property (its own name when it is one)."""
        return self.parameter or self.name


@dataclasses.dataclass(frozen=True)
class MoveRuns:
    """What a design simulation returns: per configuration, (n,) arrays of a move and its settling.

    Attributes
    ----------
    move_time_s
        realized move time [s].
    settling_time_s
        time after the move until the positioned body stays inside its band for good [s] (inf: never).
    positioning_time_s
        move + settling [s].
    residual_amplitude_m
        largest deviation from the target after the move [m].
    dt_s
        timestep of each simulation [s].
    steps
        physics steps each simulation took.
    nthread
        threads the simulations ran on.
    """

    move_time_s: np.ndarray
    settling_time_s: np.ndarray
    positioning_time_s: np.ndarray
    residual_amplitude_m: np.ndarray
    dt_s: np.ndarray
    steps: np.ndarray
    nthread: int


@dataclasses.dataclass(frozen=True)
class MoveEstimates:
    """The closed-form side of a design study: per configuration, (n,) arrays.

    Attributes
    ----------
    estimate_s
        analytic estimate of the positioning time [s].
    worst_case_estimate_s
        an upper estimate that needs no simulation [s].
    natural_frequency_hz
        the mode that rings after the move [Hz].
    """

    estimate_s: np.ndarray
    worst_case_estimate_s: np.ndarray
    natural_frequency_hz: np.ndarray


class DesignHooks(Protocol):
    """The closed-form and simulation pieces a scene's design question needs (implemented by the scene).

    `base` is the scene's resolved parameters (SI); `values` maps each varied property to its (n,)
    values per configuration (the properties not in it stay at their value in `base`).
    """

    def defaults(self, base: Mapping[str, float]) -> dict[str, float]:
        """Every declared property's value [its unit] at the parameters `base`.

        Parameters
        ----------
        base
            the scene's parameters (SI).

        Returns
        -------
        dict[str, float]
            property name -> value.
        """
        ...

    def parameters_for(self, name: str, value: float, base: Mapping[str, float]) -> dict[str, float]:
        """The scene parameters [SI] that give the derived property `name` the value `value` at `base`.

        Parameters
        ----------
        name
            a derived property (`DesignProperty.derived`).
        value
            its value [its unit].
        base
            the other parameters (SI).

        Returns
        -------
        dict[str, float]
            scene parameter -> value, to resolve the scene with.
        """
        ...

    def simulate(
        self, case: CaseView, values: Mapping[str, np.ndarray], *, omega_dt: float, nthread: int, max_duration: float
    ) -> MoveRuns:
        """Simulate the move of every configuration (a module-level object: it runs on dask workers too).

        Parameters
        ----------
        case
            the scene's design scenario at `base`, the scene's parameters (SI): `case.params`.
        values
            property -> (n,) values.
        omega_dt
            omega_n dt [-] of every simulation.
        nthread
            threads (0: one per CPU).
        max_duration
            simulated time [s] after which an unsettled configuration is given up (settling inf).

        Returns
        -------
        MoveRuns
            per-configuration results, in the order of `values`.
        """
        ...

    def estimates(self, base: Mapping[str, float], values: Mapping[str, np.ndarray], dt: np.ndarray) -> MoveEstimates:
        """The analytic estimates of every configuration, each on its simulation's timestep `dt` [s].

        Parameters
        ----------
        base
            the scene's parameters (SI).
        values
            property -> (n,) values.
        dt
            (n,) timesteps [s] the simulations used.

        Returns
        -------
        MoveEstimates
            per-configuration estimates.
        """
        ...

    def setting(self, base: Mapping[str, float]) -> str:
        """The fixed task in a few words, for a chart's title, e.g. '25.4 mm to +-10 um'.

        Parameters
        ----------
        base
            the scene's parameters (SI).

        Returns
        -------
        str
            the words.
        """
        ...

    def answer(self, summary: Mapping[str, Any]) -> str:
        """The design question answered in words, from the study's `to_dict()`.

        Parameters
        ----------
        summary
            the study's `to_dict()`.

        Returns
        -------
        str
            one paragraph.
        """
        ...


@dataclasses.dataclass(frozen=True)
class DesignSpec:
    """The design question a scene answers: how fast can a move be made, and which properties matter.

    The study (springlab.studies.design) sweeps `properties` on a log grid around their defaults,
    simulates the `scenario`'s move of every configuration through `hooks.simulate`, estimates each
    through `hooks.estimates`, and ranks the properties by their effect on the figure of merit,
    the positioning time (move + settling); the Sobol study varies `sobol`, in that order.

    Attributes
    ----------
    question
        the question in words.
    scenario
        the scene's scenario whose move is studied (its parameters are the study's starting point).
    properties
        the swept properties, in grid order.
    fixed
        scene parameters held at their values and reported beside the results.
    hooks
        the scene's closed-form and simulation pieces (`DesignHooks`).
    merit
        the figure of merit in words (titles and lines).
    extra
        properties only the Sobol study varies.
    sobol
        the Sobol study's inputs, in order (names of `properties` or `extra`).
    """

    question: str
    scenario: str
    properties: tuple[DesignProperty, ...]
    fixed: tuple[str, ...]
    hooks: DesignHooks
    merit: str = "positioning time"
    extra: tuple[DesignProperty, ...] = ()
    sobol: tuple[str, ...] = ()

    def get(self, name: str) -> DesignProperty:
        """The declared property (swept or extra) called `name`.

        Raises
        ------
        KeyError
            no such property is declared.
        """
        for prop in (*self.properties, *self.extra):
            if prop.name == name:
                return prop
        raise KeyError(name)

    @property
    def names(self) -> tuple[str, ...]:
        """The swept properties' names, in grid order."""
        return tuple(p.name for p in self.properties)


# -- dry friction: MuJoCo's regularised friction against exact Coulomb answers -------------------------

#: dry friction of a joint (MuJoCo's `frictionloss`): a force bounded by F whatever the load
JOINT_FRICTION = "joint"
#: contact friction: mu times the normal force, inside MuJoCo's friction cone
CONTACT_FRICTION = "contact"


@dataclasses.dataclass(frozen=True)
class SolverSetting:
    """A MuJoCo setting a scene takes as a parameter, and the values the friction-settings study tries.

    Attributes
    ----------
    name
        the scene parameter that sets it (e.g. a solref time constant [s]).
    values
        the values swept, in order; MuJoCo's default among them.
    mujoco_default
        MuJoCo's own default value.
    acts_on
        the kinds of dry friction it changes (JOINT_FRICTION, CONTACT_FRICTION), from MuJoCo's
        documentation and source; the declaring scene's tests check each claim on MuJoCo itself.
        The study sweeps a setting only in the cases whose friction it acts on.
    label
        the setting in words with its unit, e.g. 'solref time constant [s]'.
    names
        value -> word, for a setting that is a choice (e.g. 0: 'pyramidal', 1: 'elliptic').
    floor_in_dt
        MuJoCo raises a value below this many timesteps to it (solref's `refsafe`: 2); the study
        skips such values, which would repeat the run at the raised value (None: no such rule).
    """

    name: str
    values: tuple[float, ...]
    mujoco_default: float
    acts_on: tuple[str, ...]
    label: str
    names: Mapping[float, str] = dataclasses.field(default_factory=dict)
    floor_in_dt: float | None = None

    def __post_init__(self) -> None:
        unknown = set(self.acts_on) - {JOINT_FRICTION, CONTACT_FRICTION}
        if unknown or not self.acts_on:
            raise ValueError(f"a SolverSetting acts on {JOINT_FRICTION!r} and/or {CONTACT_FRICTION!r}")
        if self.mujoco_default not in self.values:
            raise ValueError(f"the values of {self.name} must include MuJoCo's default {self.mujoco_default:g}")

    def word(self, value: float) -> str:
        """The value as the study prints it: its name for a choice, else the number."""
        return self.names.get(value, f"{value:g}")


@dataclasses.dataclass(frozen=True)
class FrictionMeasure:
    """An error the study reports for a case: a quantity of the scenario against its exact value.

    The run's quantities carry both (DESIGN: each with its exact value beside it, `<quantity>_exact`).

    Attributes
    ----------
    quantity
        its name in the run's quantities, ending in its unit (e.g. 'stop_position_m').
    label
        what it is in words.
    scale
        None: the error is |value - exact| / |exact|; a name: the error is |value - exact| / |scale|,
        the scale being that quantity (or parameter) of the run (e.g. the initial amplitude);
        '' : the error is |value - exact| in the quantity's unit (an exact value of 0: a creep velocity).
    """

    quantity: str
    label: str
    scale: str | None = None

    @property
    def exact(self) -> str:
        """The name of its exact value in the quantities."""
        return f"{self.quantity}_exact"


@dataclasses.dataclass(frozen=True)
class FrictionCase:
    """A scenario of the declaring scene with an exact answer under dry friction.

    Attributes
    ----------
    scenario
        the scenario's name.
    friction
        JOINT_FRICTION or CONTACT_FRICTION: which of MuJoCo's friction models it exercises.
    question
        what it asks, in words.
    measures
        the errors reported beside the trajectory's (FrictionMeasure).
    """

    scenario: str
    friction: str
    question: str
    measures: tuple[FrictionMeasure, ...] = ()

    def __post_init__(self) -> None:
        if self.friction not in (JOINT_FRICTION, CONTACT_FRICTION):
            raise ValueError(f"a FrictionCase's friction is {JOINT_FRICTION!r} or {CONTACT_FRICTION!r}")


@dataclasses.dataclass(frozen=True)
class DryFrictionSpec:
    """A scene whose dry friction MuJoCo regularises, with exact Coulomb answers (`Scene.dry_friction`).

    springlab.studies.friction_settings sweeps the declared MuJoCo settings, integrators and timesteps
    over each case, against the exact answers the scene's runs carry: error vs cost, the Pareto front,
    the cheapest setting meeting a tolerance (verified by a run), and the model error of each setting,
    what is left as dt -> 0 (read at the smallest timestep, where it must have converged).

    Attributes
    ----------
    cases
        the scenarios, in order.
    settings
        the MuJoCo settings a user can change, each a scene parameter.
    dts
        the timesteps swept [s], at least two, largest first (a measured convergence).
    integrators
        the integrators swept (default: MuJoCo's five).
    """

    cases: tuple[FrictionCase, ...]
    settings: tuple[SolverSetting, ...]
    dts: tuple[float, ...]
    integrators: tuple[str, ...] = ("euler", "implicit", "implicitfast", "rk4", "discrete")

    def __post_init__(self) -> None:
        if len(self.dts) < 2 or any(b >= a for a, b in zip(self.dts, self.dts[1:])):
            raise ValueError("a DryFrictionSpec sweeps at least two timesteps, largest first")

    def case(self, scenario: str) -> FrictionCase:
        """The declared case of `scenario`.

        Raises
        ------
        KeyError
            no case of that scenario is declared.
        """
        for case in self.cases:
            if case.scenario == scenario:
                return case
        raise KeyError(scenario)

    def settings_of(self, friction: str) -> tuple[SolverSetting, ...]:
        """The settings that act on `friction` (JOINT_FRICTION or CONTACT_FRICTION)."""
        return tuple(s for s in self.settings if friction in s.acts_on)


# -- refinable: a scene whose model size is a parameter (springlab.studies.refine) ------------------------


@dataclasses.dataclass(frozen=True)
class RefinedQuestion:
    """A quantity a run of the scene measures that converges, as the model is refined, to a continuum value.

    The refine study reads three of the run's quantities: the measured value (`name`), the same quantity
    of the discretized model solved exactly (`exact`: the gap to it is the integration error) and of the
    continuum (`continuum`: the gap between the two exact values is the discretization error).

    Attributes
    ----------
    name
        the measured quantity, e.g. 'mode_1_frequency_hz'.
    scenario
        the scenario whose runs measure it.
    description
        the question in words, e.g. 'the first torsional frequency'.
    exact
        the quantity holding the discretized model's exact value.
    continuum
        the quantity holding the continuum's exact value.
    """

    name: str
    scenario: str
    description: str
    exact: str
    continuum: str


@dataclasses.dataclass(frozen=True)
class RefinableSpec:
    """The scene's model size is a parameter (`Scene.refinable`): how much model does a question need?

    springlab.studies.refine sweeps the size x integrator x timestep, measures each question's error
    against its continuum value and the cost of every run, and finds the cheapest verified setting.

    Attributes
    ----------
    size
        the parameter that sets the model's size (an integer, e.g. 'n_elements').
    description
        what the size counts, in words (e.g. 'lumped elements').
    sizes
        the sizes the study sweeps by default, ascending.
    questions
        the questions, the first the default.
    order
        the expected order of the discretization error in the size (error ~ size^-order).
    switch_time
        a parameter [s] every timestep of the study divides (an input switched on the step grid at that
        time, e.g. the end of a ramp), so all runs of a size solve the same problem; '' for none.
    """

    size: str
    description: str
    sizes: tuple[int, ...]
    questions: tuple[RefinedQuestion, ...]
    order: float
    switch_time: str = ""

    def question(self, name: str | None) -> RefinedQuestion:
        """The question measuring `name` (None: the first).

        Raises
        ------
        KeyError
            no question measures that quantity.
        """
        if name is None:
            return self.questions[0]
        for question in self.questions:
            if question.name == name:
                return question
        raise KeyError(name)


# -- figure: what a scene adds to its runs' figures (springlab.plots.run.scene_figure) ----------------------


@dataclasses.dataclass(frozen=True)
class Curve:
    """One curve of a declared panel.

    Attributes
    ----------
    label
        legend text.
    x, y
        the points, in the panel's units.
    kind
        'simulated' (solid), 'exact' (dashed) or 'continuum' (dotted).
    """

    label: str
    x: np.ndarray
    y: np.ndarray
    kind: str = "simulated"


@dataclasses.dataclass(frozen=True)
class Panel:
    """One panel of a scene's own figure.

    Attributes
    ----------
    title
        one line.
    xlabel, ylabel
        axis labels with units.
    curves
        what is drawn.
    marks
        vertical lines: (x, label), e.g. an exact event time.
    """

    title: str
    xlabel: str
    ylabel: str
    curves: tuple[Curve, ...]
    marks: tuple[tuple[float, str], ...] = ()


#: hook: (the case that ran, its trajectory) -> the panels of the run's own figure
FigureHook: TypeAlias = Callable[[CaseView, Trajectory], tuple[Panel, ...]]


# -- frequency: the frequency response of a scene (springlab.studies.frequency) ----------------------------

#: hook: (the scenario's MjSpec after the scene's own edits, its parameters) -> None; edits the spec so the
#: declared input exists as an actuator (e.g. a road height as a control), the physics otherwise unchanged
FrequencyEdit: TypeAlias = Callable[[mujoco.MjSpec, Mapping[str, float]], None]


#: hook: (the compiled model, the scenario's parameters, H: f [Hz] -> the exact complex response, the resonances
#: found in the band as dicts {"frequency_hz", "magnitude", "damping_ratio", "natural_frequency_hz",
#: "pole_damping_ratio"}, the band (fmin, fmax) [Hz]) -> (named answers, SI, names ending in their unit;
#: verdict lines): what the response means for the scene's own question (e.g. where a suspension isolates)
FrequencyInterpret: TypeAlias = Callable[
    [
        mujoco.MjModel,
        Mapping[str, float],
        Callable[[np.ndarray], np.ndarray],
        tuple[Mapping[str, Any], ...],
        tuple[float, float],
    ],
    tuple[dict[str, Any], tuple[str, ...]],
]


@dataclasses.dataclass(frozen=True)
class FrequencySpec:
    """The frequency response a scene answers by default (`springlab frequency SCENE`).

    Attributes
    ----------
    scenario
        the scenario whose model is analysed when the user names none.
    input
        the default input: an actuator or joint name of that model (after `edit`).
    response
        the default response: a joint name ('JOINT' position, 'JOINT:vel', 'JOINT:acc').
    description
        the question in words, e.g. 'road height to body heave: the transmissibility'.
    edit
        MjSpec edit applied after the scene's own (None: none), e.g. the car's road height as a control.
    interpret
        what the default input -> response means for the scene's question (None: nothing beyond the
        resonances), e.g. the single-mass car's isolation frequency or the printer head's shortest move.
    input_unit
        the declared input's unit where it is an actuator ('' : MuJoCo's actuator unit, unknown), e.g. 'm'
        for the car's road height, so the plot's |H| reads in physical units.

    A scene answering several frequency questions declares a tuple of specs, one per scenario, the first
    the default (`Scene.frequency`).
    """

    scenario: str
    input: str
    response: str
    description: str
    edit: FrequencyEdit | None = None
    interpret: FrequencyInterpret | None = None
    input_unit: str = ""


# -- interactive: the scene in the browser (springlab.render.interactive) ---------------------------------


def formula(expression: str, values: Mapping[str, float]) -> float:
    """The value of an `InteractiveSpec` formula: + - * / and parentheses over names and numbers.

    The page evaluates the same text in JavaScript with the same precedence and left-to-right order, so
    both sides round alike (IEEE double arithmetic); names are the scene's parameters and `g` [m/s^2].

    Parameters
    ----------
    expression
        e.g. "clearance + mass * g / stiffness".
    values
        name -> value (SI).
    """

    def walk(node: ast.AST) -> float:
        if isinstance(node, ast.Expression):
            return walk(node.body)
        if isinstance(node, ast.Constant) and isinstance(node.value, (int, float)):
            return float(node.value)
        if isinstance(node, ast.Name):
            return float(values[node.id])
        if isinstance(node, ast.UnaryOp) and isinstance(node.op, ast.USub):
            return -walk(node.operand)
        if isinstance(node, ast.BinOp) and isinstance(node.op, (ast.Add, ast.Sub, ast.Mult, ast.Div)):
            left, right = walk(node.left), walk(node.right)
            op = node.op
            if isinstance(op, ast.Add):
                return left + right
            if isinstance(op, ast.Sub):
                return left - right
            return left * right if isinstance(op, ast.Mult) else left / right
        raise ValueError(f"not a formula of + - * / over names and numbers: {expression!r}")

    return walk(ast.parse(expression, mode="eval"))


@dataclasses.dataclass(frozen=True)
class MjcfEdit:
    """One value written into the MJCF text, the browser's form of a line of `Scene.edit`.

    The page edits the scene's MJCF file as text (an XML attribute) and recompiles it, so the model it
    steps is the one `Scene.build` makes; tests/test_interactive.py compiles both and compares them.

    Attributes
    ----------
    value
        what is written: a parameter name or a `formula` over parameters and `g` (e.g. a spring's
        relaxed length from the mass and stiffness), evaluated in the page as they move.
    tag, name
        the element `<tag name="name">` of the MJCF file.
    attribute
        the attribute written (the value in full precision).
    child
        write into this child element of it instead (e.g. a body's `inertial`); None: the element itself.
    """

    value: str
    tag: str
    name: str
    attribute: str
    child: str | None = None


@dataclasses.dataclass(frozen=True)
class InteractiveSpec:
    """A scene whose scenarios run in the browser with real MuJoCo (`springlab interactive`).

    The page's exact solution is the one-mode oscillator m x'' + d x' + k x = F (F constant from t = 0,
    through an actuator's control, as `Scene.setup` holds it), about a rest position (`rest`: a constant
    load such as gravity on a preloaded spring), ported to JavaScript; it is the kind every declaring
    scene shares (`kind`). The sliders move mass, stiffness and the damping ratio (the damping follows).

    Attributes
    ----------
    joint
        the oscillating joint, x; its qpos and qvel are the page's x and v.
    scenarios
        the scenarios the page can run: those whose model is the MJCF with `edits` applied (no
        MjSpec-built parts such as a harmonic exciter); the first is the default.
    edits
        the parameters written into the MJCF text.
    mass, stiffness, damping
        the scene's parameter names of m [kg], k [N/m], d [N s/m].
    x0, v0
        `formula`s of x(0) [m] and v(0) [m/s] as `Scene.setup` computes them.
    force
        `formula` of the constant force F [N] on the joint (None: none).
    actuator
        the actuator whose control holds F.
    rest
        `formula` of the rest position [m] the free motion decays to, where a constant load is
        balanced by a preloaded spring (None: 0); the reference is then rest + the free response from
        x0 - rest, as the scene's.
    ranges
        parameter -> (low, high) of its slider, where it is inside the scene's model (default: a decade
        either side of the scenario's value).
    """

    kind: ClassVar[str] = "oscillator"

    joint: str
    scenarios: tuple[str, ...]
    edits: tuple[MjcfEdit, ...]
    mass: str = "mass"
    stiffness: str = "stiffness"
    damping: str = "damping"
    x0: str = "x0"
    v0: str = "v0"
    force: str | None = None
    actuator: str | None = None
    rest: str | None = None
    ranges: Mapping[str, tuple[float, float]] = dataclasses.field(default_factory=dict)
