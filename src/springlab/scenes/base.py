"""What every scene provides, and the shared machinery to build and check it.

A scene is one MJCF file under models/ and one module of the same name under
springlab/scenes/. The module subclasses `Scene` and says:

* its parameters (SI, with units and valid ranges) and which MJCF values they
  read back from the compiled model as defaults;
* its scenarios (named questions, with parameter presets and a duration);
* how parameters edit the model (MjSpec edits, so the physics stays in MJCF);
* the initial state and the open-loop control sequence of a scenario;
* the exact reference where one exists, and the scenario's named quantities.

Its hooks take a `Case`: one scenario with its resolved parameters and its compiled model, the
object every study and every hook shares. Everything a study repeats for "this scenario at these
parameters" is a method of it: the initial state and controls of a run (`setup`), the run at an
integrator, dt and duration (`simulate`, through springlab.sim), the exact reference, the checks,
the quantities, the modes. What depends only on the case is computed once and kept on it
(`Case.memo`): the parameters are resolved once, the model compiled once, and a scene's exact
precomputations (its mode shapes, its read-back constants) are shared by its hooks.

>>> from springlab import scenes
>>> case = scenes.get("slider").case("free", {"mass": 2.0})
>>> trajectory = case.simulate("rk4", 1e-3, 1.0)
>>> reference = case.reference(trajectory.time, dt=1e-3)

Data flows one way: parameters -> MjModel -> Trajectory -> (reference, errors)
-> summary, plots and video.
"""

from __future__ import annotations

import collections
import dataclasses
import functools
import hashlib
import threading
from collections.abc import Callable, Hashable, Mapping
from typing import TYPE_CHECKING, Any, TypeVar

import mujoco
import numpy as np

from springlab.answer import Answer, compose
from springlab.errors import ParameterError, UnknownNameError
from springlab.exact.limits import stability_limit
from springlab.sim import model_files
from springlab.sim.simulate import Setup, Trajectory, check_timing, configured, integrator_id, quiet_mujoco, simulate

from .capabilities.design import DesignSpec
from .capabilities.drawing import Drawing
from .capabilities.figure import FigureHook
from .capabilities.fit import FitSpec
from .capabilities.frequency import FrequencySpec
from .capabilities.friction import DryFrictionSpec
from .capabilities.interactive import InteractiveSpec
from .capabilities.oscillator import OscillatorSpec
from .capabilities.random_load import RandomLoadSpec
from .capabilities.refine import RefinableSpec
from .declarations import Check, Parameter, Reference, Scenario

if TYPE_CHECKING:
    from springlab.sim.batch import Job

T = TypeVar("T")

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


#: (qpos (n, nq), qvel (n, nv)) -> (n,) bool: an event that ends a run early (Scene.stop_condition)
StopCondition = Callable[[np.ndarray, np.ndarray], np.ndarray]
#: (x, v) -> (dx/dt, dv/dt) of a one-joint scene's unforced motion (Scene.phase_field)
PhaseField = Callable[[np.ndarray, np.ndarray], tuple[np.ndarray, np.ndarray]]


#: the sentence an answer closes with where the run is compared with an exact trajectory: the measured agreement
#: beside the exact answer (a template over a run's facts, springlab.runs.run.evaluate)
FOLLOWS_EXACT = (
    " MuJoCo's run ({integrator}, dt = {dt_s:g ~s}) stays within {max_rel_error:.1e} of the exact solution"
    " (relative to its largest value)."
)


class Scene:
    """Base class of the scenes: one MJCF file under models/ and one module of the same name.

    Like scipy's `OdeSolver`, a new scene is a subclass that provides the following.

    1. Class attributes: `name` (also the MJCF stem: models/<name>.xml), `title` (the one-line
       question), `joints` (the reported joints, trajectory.csv's columns), `parameters`
       (name -> `Parameter`, SI with units and valid ranges), `scenarios` (name -> `Scenario`,
       each with its duration, presets and validated `dt`; a scene whose scenarios differ in their
       model gives each its `variant` instead of dispatching on names), `default_scenario`, and
       the validated default setting `integrator` and `dt` [s]; optionally `camera`; and `questions`
       (scenario -> the question it asks and its answer's template, `Scene.answer`: units a reader expects,
       the exact value beside MuJoCo's; `grid_notes(case, dt)` says what a step grid changes in the input).
    2. `model_defaults(model)`: the parameters whose defaults live in the MJCF, read back from the
       compiled model (the physics values have one home, the MJCF).
    3. `edit(spec, params, scenario)`: MjSpec edits that apply the parameters, so the physics
       stays in MJCF (no Python forces; time-varying inputs as MJCF-native generators or
       piecewise-constant controls switched on step boundaries, see springlab.sim.exciter).

    The hooks below take a `Case` : the scenario with its resolved parameters
    (`case.params`) and compiled model (`case.model`), made once by `Scene.case` and shared by every hook
    and run of it. What depends only on the case is computed once and kept on it (`case.memo`, and
    `case.physical()` for the constants of 5); a study calls the case's methods (`case.setup`,
    `case.simulate`, `case.reference`, ...), never the hooks directly.

    4. `setup(case, steps, dt)`: the initial state and open-loop controls (`Setup`) of a run of `steps`
       steps of `dt` [s]; raise ParameterError for a motion the scene's equations cannot describe when
       that is known before the run. A closed-loop scenario returns a `Setup` whose `controller`
       (springlab.sim.controller.Controller) reads the model's sensors every few steps and sets the controls,
       held in between, instead of open-loop controls: every runner (`Case.simulate`, the batched studies,
       the timing) runs it in MuJoCo's loop, so nothing else in a scene or study changes for it (the
       printer head's `feedback_motor`). Its sensors are the scene's own MjSpec edit (`edit`).
    5. `physical(model)`: the physical constants the scene's equations use, read back from the
       compiled model (SI; the order is the scene's, documented in its override).
    6. `modes(case)`: [(natural frequency [rad/s], damping ratio [-])] of every mode the integrator must
       resolve (forcing generators included), for stability advice.
    7. `reference(case, time, *, dt)`: the exact solution at `time` [s] where one exists (`Reference`;
       for a linear scene with its state matrix, so the tolerance is derived), else None and
       `checks(case, trajectory)`: scalar claims against independent references (`Check`; builders in
       springlab.scenes.checks).
    8. `quantities(case, trajectory)`: the scenario's named results, SI, names ending in their unit;
       peaks and event times interpolated between the samples to the run's order (springlab.exact.events).
    9. Optionally: `check_consistency(params, scenario)` (non-physical parameter combinations),
       `model_limits(case, trajectory)` (where a finished run leaves the scene's equations),
       `stop_condition(case)` (an event that ends a run early as a result), `stability_limit(case,
       integrator, omega, zeta)` (damping MuJoCo treats differently from joint damping),
       `phase_field(case)`/`equilibria(case)`/`separatrices(case)` (one-joint phase planes),
       `joint_columns(model, trajectory)` (joints that only some scenarios have), `drawing(case)` (what the
       pictures of a run show beyond the model's geoms and its MJCF drawing texts, e.g. the road a quarter
       car drives over: springlab.scenes.capabilities.drawing; the renderer never recognises a scene).
    10. Capabilities the studies read (springlab.scenes.capabilities): `fit`, how `springlab fit`
       identifies the scene from a record (an `OscillatorFit` or a `PolynomialFit`; None: it cannot);
       `design`, the design question the scene answers (`DesignSpec`: swept properties, fixed ones,
       the figure of merit and the hooks that simulate and estimate it; springlab.studies.design);
       `refinable`, the model's size is a parameter and which quantities converge to which continuum
       values (`RefinableSpec`; springlab.studies.refine); `figure`, the panels of the scene's own
       figure of a run (a `FigureHook`; springlab.plots.run.scene_figure).
    11. Optionally, `oscillator` (springlab.scenes.capabilities.oscillator.OscillatorSpec): the scene is the
       textbook's one-mode mass-spring-damper, the unit oscillator of `springlab stability`.
    12. Optionally, `dry_friction` (springlab.scenes.capabilities.friction.DryFrictionSpec): the scene's dry
       friction has exact Coulomb answers and takes MuJoCo's friction settings as parameters, which
       `springlab friction-settings` sweeps (springlab.studies.friction_settings).
    13. Optionally, `frequency` (springlab.scenes.capabilities.frequency.FrequencySpec, or a tuple of them, one per
       scenario, the first the default): the default input and response of `springlab frequency SCENE`, an
       MjSpec edit that makes the input a control, and what the response means for the scene's question.
    14. Optionally, `interactive` (springlab.scenes.capabilities.interactive.InteractiveSpec): the scenarios that run
       in the browser with real MuJoCo and the MJCF attributes the page writes (`springlab interactive`).
    15. Optionally, `random_load` (springlab.scenes.capabilities.random_load.RandomLoadSpec): a scenario under a seeded
       stationary random load whose RMS has an exact value and scatter (`springlab rms`:
       springlab.studies.random_load runs many seeds and finds the cheapest setting for an accurate RMS).

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
    #: scenario -> (the textbook question it answers, its answer in one or two sentences): the answer is a
    #: template over the run's parameters, quantities and facts (springlab.answer.compose: a field's spec may
    #: end in the unit a reader expects, "{settling_time_s:.3g ms}", "{creep_velocity_m_s:.2g ~m/s}"), or a
    #: function of those values returning the template (an answer that words a case differently)
    questions: dict[str, tuple[str, str | Callable[[Mapping[str, Any]], str]]] = {}
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
    #: a scenario under a seeded stationary random load: its RMS, exactly and from many seeds (None: none;
    #: springlab.studies.random_load reads it)
    random_load: RandomLoadSpec | None = None

    def answer(self, scenario: str, values: Mapping[str, Any]) -> Answer | None:
        """The question `scenario` asks and a run's answer to it, worded from `values` (None: the scene states none).

        Parameters
        ----------
        scenario
            the scenario's name.
        values
            the run's parameters, quantities and facts by name (SI).

        Returns
        -------
        Answer or None
            the one source of the sentence `springlab run` prints first, summary.json carries and the report
            shows. A run too short to produce a value the answer quotes says so instead of a sentence.
        """
        if scenario not in self.questions:
            return None
        question, template = self.questions[scenario]
        wording = template(values) if callable(template) else template
        try:
            return compose(question, wording, values)
        except KeyError as missing:
            return Answer(
                question,
                f"This run does not answer it: it produced no {missing.args[0]} (a longer --duration may).",
            )

    def grid_notes(self, case: Case, dt: float) -> list[str]:
        """What the step grid of `dt` [s] changes in the scenario's input, one line each (override; empty: nothing).

        E.g. a ramp of 2 s on a 12 ms grid lasts 2.004 s: the run and its exact reference both follow the
        realized input, and the verdict line says so up front.
        """
        return []

    # -- names ---------------------------------------------------------------

    def scenario(self, name: str | None) -> Scenario:
        """The scenario called `name` (None: the default one)."""
        name = self.default_scenario if name is None else name
        if name not in self.scenarios:
            raise UnknownNameError(f"scenario of {self.name}", name, self.scenarios)
        return self.scenarios[name]

    def setting(self, scenario: Scenario) -> tuple[str, float]:
        """(integrator, dt [s]): the validated default setting of `scenario` (its own, else the scene's)."""
        return scenario.integrator or self.integrator, scenario.dt or self.dt

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

    def editable_spec(self) -> mujoco.MjSpec:
        """The MjSpec `build` hands to `edit`: `model_spec()` (override where `edit` replaces most of the model and a
        spec without that part, kept per process, saves removing it on every compile)."""
        return self.model_spec()

    def build(self, params: dict[str, float], scenario: Scenario) -> mujoco.MjModel:
        """Compile the model for these parameters and scenario."""
        spec = self.editable_spec()
        self.edit(spec, params, scenario)
        with quiet_mujoco():
            try:
                return spec.compile()
            except ValueError as error:
                # a backstop: each parameter's range should catch this first (tests/cli/test_cli_inputs.py)
                reason = str(error).splitlines()[0].removeprefix("Error: ")
                raise ParameterError(
                    f"MuJoCo cannot compile {self.name} {scenario.name} with these parameters: {reason}"
                ) from None

    def case(self, scenario: str | Scenario | None = None, parameters: Mapping[str, Any] | None = None) -> Case:
        """The scenario at these parameters: resolved (`resolve`) and compiled (`build`) once, as a `Case`.

        Parameters
        ----------
        scenario
            a scenario or its name (None: the default one).
        parameters
            overrides, name -> value (SI); the rest are the scenario's and the MJCF's.

        Raises
        ------
        UnknownNameError
            a scenario or parameter this scene does not have.
        ParameterError
            a value outside its valid range, or a non-physical combination.
        """
        chosen = scenario if isinstance(scenario, Scenario) else self.scenario(scenario)
        return Case.compiled(self, chosen, self.resolve(chosen, parameters or {}))

    def setup(self, case: Case, steps: int, dt: float) -> Setup:
        """Initial state and controls of a run of `steps` steps of `dt` [s] (override)."""
        return Setup()

    def reference(self, case: Case, time: np.ndarray, *, dt: float) -> Reference | None:
        """Exact solution at `time` [s] of a run with timestep `dt` [s], or None where none exists (override).

        `dt` is explicit, never read back from `model.opt.timestep`: an input switched on the
        step grid (a bang-bang move, the end of a road bump) is placed on the run's own grid,
        and one model may serve runs at many timesteps (a sweep).
        """
        return None

    def quantities(self, case: Case, trajectory: Trajectory) -> dict[str, Any]:
        """Named results of the scenario, SI, names ending in their unit (override)."""
        return {}

    def physical(self, model: mujoco.MjModel) -> tuple[float, ...]:
        """The physical constants the scene's equations use, read back from the compiled model (SI).

        The order is the scene's (e.g. the slider's (mass [kg], stiffness [N/m], damping [N s/m]));
        none by default. `Case.physical` keeps them for the case.
        """
        return ()

    def modes(self, case: Case) -> list[tuple[float, float]]:
        """[(natural frequency [rad/s], damping ratio [-])] of the run, for stability advice."""
        return []

    def stability_limit(self, case: Case, integrator: str, omega: float, zeta: float) -> float:
        """Largest omega*dt [-] at which `integrator` is stable on the mode (omega [rad/s], zeta [-]).

        Default: simulate.stability_limit, which assumes the damping is joint damping;
        a scene whose damping MuJoCo treats differently (e.g. tendon damping) overrides this.
        """
        return stability_limit(integrator, zeta)

    def phase_field(self, case: Case) -> PhaseField | None:
        """For a scene with one reported joint: (x [m], v [m/s]) -> (dx/dt [m/s], dv/dt [m/s^2])
        of the unforced equations of motion, for phase-plane vector fields (None: no plane)."""
        return None

    def equilibria(self, case: Case) -> list[dict]:
        """Equilibria of the unforced motion: [{"x": position [m], "stable": bool}]."""
        return []

    def separatrices(self, case: Case) -> list[tuple[np.ndarray, np.ndarray]]:
        """Separatrix curves of the unforced phase plane: [(x [m], v [m/s]) arrays] (none by default)."""
        return []

    def checks(self, case: Case, trajectory: Trajectory) -> list[Check]:
        """Scalar claims `validate` holds an exact scenario to, beyond its compared columns (override)."""
        return []

    def model_limits(self, case: Case, trajectory: Trajectory) -> list[str]:
        """Where this run leaves the range the scene's equations describe, one line each (override).

        E.g. a linear tire that would have to pull on the road: the simulation may still match its
        exact reference, but neither describes the physical system any more. Any line makes the run
        not validated (`passed` False, exit 1) and is reported in summary.json's `model_limits`.
        """
        return []

    def drawing(self, case: Case) -> Drawing:
        """What the pictures of a run of `case` show beyond the model's own geoms and its MJCF drawing texts
        (springlab.scenes.capabilities.drawing; e.g. the road under a quarter car); nothing by default."""
        return Drawing()

    def stop_condition(self, case: Case) -> StopCondition | None:
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


#: how many references (grids of times) a case keeps (`Case.reference`)
KEPT_REFERENCES = 4
#: how many compiled cases (model and `Case.memo`) the process keeps, least recently used dropped first
COMPILED_CASES = 32
#: (scene, scenario, parameters) -> its Case: a repeated run, a study's repeated setting and every hook of
#: one parameter set share one compiled model and one set of exact precomputations (`Case.compiled`)
_COMPILED: collections.OrderedDict[Hashable, Case] = collections.OrderedDict()
_COMPILED_LOCK = threading.Lock()


@dataclasses.dataclass(frozen=True, eq=False, repr=False)
class Case:
    """A scenario of a scene with its resolved parameters and its compiled model.

    Immutable and cheap: a sweep builds thousands. Make one with `Scene.case` (names and overrides,
    resolved and checked) or `Case.compiled` (parameters already resolved); runs at any integrator, dt
    and duration share it, since `simulate` never modifies the model (it steps a copy).

    Attributes
    ----------
    scene
        the Scene.
    scenario
        the Scenario.
    params
        parameter name -> value (SI), resolved: MJCF defaults < scenario presets < overrides. Read, never
        written (the case and what it keeps were computed from them).
    model
        the compiled model of `params` and `scenario` (`Scene.build`), or that model with additions that
        leave its physics unchanged (e.g. the sensor a fit records).
    """

    scene: Scene
    scenario: Scenario
    params: dict[str, float]
    model: mujoco.MjModel
    #: what depends only on the case, computed once (`memo`)
    _memo: dict[Hashable, Any] = dataclasses.field(default_factory=dict, init=False, repr=False)

    def __post_init__(self) -> None:
        object.__setattr__(self, "params", dict(self.params))  # the caller's dict stays the caller's

    def __reduce__(self) -> tuple[Any, tuple[Any, ...]]:
        # the scenario travels by name (its presets may be closures); what the memo kept is recomputed there
        return (_case_of, (self.scene, self.scenario.name, self.params, self.model))

    def __repr__(self) -> str:
        return f"Case(scene={self.scene.name!r}, scenario={self.scenario.name!r}, params={self.params!r})"

    @classmethod
    def compiled(cls, scene: Scene, scenario: Scenario, params: Mapping[str, float]) -> Case:
        """The case of parameters already resolved (`Scene.resolve`): its model compiled (`Scene.build`).

        Kept per process for the last COMPILED_CASES parameter sets: the same scene, scenario and
        parameters give the same Case, so its compiled model and what its memo keeps (continuum roots,
        eigen-decompositions, matrix exponentials) are computed once. The model is shared: read it,
        or work on a `copy.copy` of it (as `springlab.sim.simulate.configured` does).

        Parameters
        ----------
        scene
            the Scene.
        scenario
            one of its scenarios.
        params
            every parameter the scenario uses, SI.

        Raises
        ------
        ParameterError
            MuJoCo cannot compile the model at these values.
        """
        values = dict(params)
        try:
            key: Hashable = (id(scene), id(scenario), tuple(sorted(values.items())))
            hash(key)
        except TypeError:  # a value that is no number: compile it, keep nothing
            return cls(scene, scenario, values, scene.build(values, scenario))
        with _COMPILED_LOCK:
            kept = _COMPILED.get(key)
            if kept is not None and kept.scene is scene and kept.scenario is scenario:
                _COMPILED.move_to_end(key)
                return kept
        case = cls(scene, scenario, values, scene.build(values, scenario))
        with _COMPILED_LOCK:
            _COMPILED[key] = case
            while len(_COMPILED) > COMPILED_CASES:
                _COMPILED.popitem(last=False)
        return case

    def memo(self, key: Hashable, compute: Callable[[], T]) -> T:
        """`compute()` the first time `key` is asked for, the kept value after: what depends only on the case.

        A scene keeps its exact precomputations here (e.g. the drill string's M, K and mode shapes), so its
        reference, checks, quantities and figure of one case compute them once.

        Parameters
        ----------
        key
            a name unique within the scene's hooks (any hashable: a name with the arguments it was computed for).
        compute
            the computation, called at most once per case (it must not depend on anything but the case).
        """
        if key not in self._memo:
            self._memo[key] = compute()
        return self._memo[key]

    # -- a run ------------------------------------------------------------------------

    def setup(self, steps: int, dt: float) -> Setup:
        """Initial state and open-loop controls of a run of `steps` steps of `dt` [s] (`Scene.setup`).

        Raises
        ------
        ParameterError
            a motion the scene's equations cannot describe, known before the run.
        """
        return self.scene.setup(self, steps, dt)

    def stop_condition(self) -> StopCondition | None:
        """The event that ends a run early (`Scene.stop_condition`; None: runs last their full duration)."""
        return self.memo("stop_condition", lambda: self.scene.stop_condition(self))

    def simulate(
        self,
        integrator: str,
        dt: float,
        duration: float,
        *,
        setup: Setup | None = None,
        stop: bool = True,
        keep: bool = False,
    ) -> Trajectory:
        """Run the case headless (springlab.sim.simulate): the model is not changed.

        Parameters
        ----------
        integrator
            one of MuJoCo's five ('euler', 'implicit', 'implicitfast', 'rk4', 'discrete').
        dt
            timestep [s].
        duration
            simulated time [s] (round(duration / dt) steps).
        setup
            initial state and controls (None: the scenario's own, `setup`).
        stop
            end the run at the scene's stop condition (False: run the full duration; a run that only
            needs the trajectory up to an event the scene has none of).
        keep
            keep the run on the case (`memo`) and return the kept one when asked again with the scenario's
            own setup: for the verification runs a verdict repeats (a run at dt/2 that measures the
            convergence), which depend on the case and the setting only. Read it, never write into it.

        Raises
        ------
        BadInputError
            dt or duration not a positive number, or too many steps.
        DivergedError
            the simulation blew up.
        """
        if keep and setup is None:
            key = ("simulate", integrator, float(dt), float(duration), stop)
            return self.memo(key, lambda: self.simulate(integrator, dt, duration, stop=stop))
        steps = check_timing(dt, duration)
        if setup is None:
            setup = self.setup(steps, dt)
        model, data = _work(self.model, integrator, dt)
        return simulate(
            model,
            data=data,
            prepared=True,
            integrator=integrator,
            dt=dt,
            duration=duration,
            qpos=setup.qpos,
            qvel=setup.qvel,
            act=setup.act,
            control=setup.control,
            stop=self.stop_condition() if stop else None,
            controller=setup.controller,
        )

    def job(self, integrator: str, dt: float, steps: int, *, setup: Setup | None = None) -> Job:
        """One simulation of a batch (springlab.sim.batch): this case at a setting, its stop condition included.

        Parameters
        ----------
        integrator
            one of MuJoCo's five.
        dt
            timestep [s].
        steps
            physics steps.
        setup
            initial state and controls (None: the scenario's own).
        """
        from springlab.sim.batch import Job  # here: importing the scenes must not load mujoco.batch

        return Job(
            self.model, integrator, dt, steps, self.setup(steps, dt) if setup is None else setup, self.stop_condition()
        )

    def joint_columns(self, trajectory: Trajectory) -> dict[str, tuple[np.ndarray, np.ndarray]]:
        """Reported joint -> (position, velocity) series of a run of this case (`Scene.joint_columns`)."""
        return self.scene.joint_columns(self.model, trajectory)

    # -- the exact side ---------------------------------------------------------------

    def physical(self) -> tuple[float, ...]:
        """The physical constants the scene's equations use, read back from the model (`Scene.physical`)."""
        return self.memo("physical", lambda: self.scene.physical(self.model))

    def reference(self, time: np.ndarray, *, dt: float) -> Reference | None:
        """The exact solution at `time` [s] of a run with timestep `dt` [s] (`Scene.reference`; None: none).

        Kept for the last few grids of times (a repeated run, the same run shown and checked): the
        reference depends on the case, the times and dt only. Read it, never write into it.
        """
        times = np.ascontiguousarray(time, dtype=float)
        key = ("reference", float(dt), times.shape, hashlib.blake2b(times.tobytes(), digest_size=16).digest())
        kept: collections.OrderedDict = self.memo("references", collections.OrderedDict)
        if key not in kept:
            kept[key] = self.scene.reference(self, time, dt=dt)
            while len(kept) > KEPT_REFERENCES:
                kept.popitem(last=False)
        return kept[key]

    def checks(self, trajectory: Trajectory) -> list[Check]:
        """The scalar claims a run of this case is held to (`Scene.checks`)."""
        return self.scene.checks(self, trajectory)

    def quantities(self, trajectory: Trajectory) -> dict[str, Any]:
        """The scenario's named results of a run (`Scene.quantities`; SI, names ending in their unit)."""
        return self.scene.quantities(self, trajectory)

    def model_limits(self, trajectory: Trajectory) -> list[str]:
        """Where a run leaves the scene's equations, one line each (`Scene.model_limits`; empty: nowhere)."""
        return self.scene.model_limits(self, trajectory)

    def grid_notes(self, dt: float) -> list[str]:
        """What a step grid of `dt` [s] changes in the scenario's input, one line each (`Scene.grid_notes`)."""
        return self.scene.grid_notes(self, dt)

    def modes(self) -> list[tuple[float, float]]:
        """[(natural frequency [rad/s], damping ratio [-])] of every mode a run must resolve (`Scene.modes`)."""
        return list(self.memo("modes", lambda: tuple(self.scene.modes(self))))

    def stability_limit(self, integrator: str, omega: float, zeta: float) -> float:
        """Largest omega dt [-] at which `integrator` is stable on the mode (omega [rad/s], zeta [-]).

        Kept per (integrator, omega, zeta): a scene may measure it (the printer head bisects MuJoCo's step map).
        """
        return self.memo(
            ("stability_limit", integrator, omega, zeta),
            lambda: self.scene.stability_limit(self, integrator, omega, zeta),
        )

    def phase_field(self) -> PhaseField | None:
        """(x, v) -> (dx/dt, dv/dt) of the unforced motion of a one-joint case (None: no phase plane)."""
        return self.scene.phase_field(self)

    def equilibria(self) -> list[dict]:
        """Equilibria of the unforced motion: [{"x": position [m], "stable": bool, ...}]."""
        return self.scene.equilibria(self)

    def separatrices(self) -> list[tuple[np.ndarray, np.ndarray]]:
        """Separatrix curves of the unforced phase plane: [(x [m], v [m/s]) arrays]."""
        return self.scene.separatrices(self)

    def drawing(self) -> Drawing:
        """What the pictures of a run of the case show beyond the model's own geoms (`Scene.drawing`)."""
        return self.scene.drawing(self)


#: per thread, the last few case models -> (its copy, its MjData) (`_work`)
_WORK = threading.local()
#: how many the slots hold per thread: a sweep's cases side by side (an MjData may be megabytes)
WORK_SLOTS = 2


def _work(model: mujoco.MjModel, integrator: str, dt: float) -> tuple[mujoco.MjModel, mujoco.MjData]:
    """A case model's copy set to `integrator` and `dt` [s], and an MjData of it, reused by this thread's next run.

    Copying a model and allocating its MjData (its arena: megabytes, zeroed) cost as much as a thousand steps
    of a small scene; a case's model is never written into (`Case.compiled`), so the copy stays right. One copy
    serves every setting of the case (a sweep's integrators and timesteps, a verdict's run at dt/2): a run sets
    its integrator and timestep on it, the only fields `configured` sets, and `simulate` resets the MjData
    before each run, so a run never sees the one before it.
    """
    slots: collections.OrderedDict | None = getattr(_WORK, "slots", None)
    if slots is None:
        slots = _WORK.slots = collections.OrderedDict()
    key = id(model)
    kept = slots.get(key)
    if kept is None or kept[0] is not model:
        work = configured(model, integrator, dt)
        kept = slots[key] = (model, work, mujoco.MjData(work))
        while len(slots) > WORK_SLOTS:
            slots.popitem(last=False)
    slots.move_to_end(key)
    work = kept[1]
    work.opt.integrator = integrator_id(integrator)
    work.opt.timestep = dt
    return work, kept[2]


def _case_of(scene: Scene, scenario: str, params: dict[str, float], model: mujoco.MjModel) -> Case:
    """A case unpickled (`Case.__reduce__`): its scenario found again by name on its scene."""
    return Case(scene, scene.scenario(scenario), params, model)
