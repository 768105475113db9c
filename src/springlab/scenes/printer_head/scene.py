"""printer_head: an inkjet carriage driven through a flexible belt (chapter section 5.7).

Two slide joints along the rail, displacements from rest [m]: `carriage` (q_c,
mass m_c) and `motor` (q_m, the belt's drive point on the motor pulley; the
motor's reflected inertia J/r^2 is its mass m_m). The belt is a fixed tendon of
length s = q_m - q_c with stiffness k [N/m] and damping c [N s/m]; the motor
pushes the drive point with force F(t) [N]:

    m_c q_c'' = k s + c s'            m_m q_m'' = F - k s - c s'

With M = m_c + m_m and mu = m_c m_m / M this splits exactly into

* the rigid-body motion of the centre of mass X = (m_c q_c + m_m q_m) / M:
  M X'' = F (no stiffness to ground: K is singular);
* one flexible mode, the belt stretch: mu s'' + c s' + k s = (m_c / M) F,
  natural frequency omega_n = sqrt(k / mu), damping ratio c / (2 sqrt(k mu)).

The carriage is q_c = X - (m_m / M) s: it follows the centre of mass and
vibrates with the belt at a fraction m_m / M of its stretch.

Parameters (SI): carriage_mass [kg], motor_mass [kg], belt_stiffness [N/m],
belt_damping [N s/m], drive_force [N] (the motor's force limit),
move_distance [m], positioning_band [m] (half-width of the band around the
target), deflection [m] (belt stretch at t = 0, centre of mass at rest at 0).
All but `deflection` default to models/printer_head.xml and are read back from
the compiled model; the XML says where each default comes from.

Scenarios, each with its exact solution (analytic.linear_response):

* `step_force`: F = drive_force from rest: constant control, exact for every
  integrator.
* `move` (default): a point-to-point move of move_distance D, bang-bang (the
  minimum-time profile under a force limit: +F for the first half, -F for the
  second), then the residual vibration. The minimum move time at full force is
  2 sqrt(D M / F); the switch times are put on the step grid (half-move time
  rounded up to n dt) and the force lowered to M D / (n dt)^2 so the centre of
  mass still stops exactly at D. A piecewise-constant control switched on step
  boundaries is exact for every integrator, so RK4 keeps its order. The
  realized move time and force are reported.
* `settle`: release at rest from a deflected belt (default: the stretch the
  belt has while the motor accelerates at full force, F m_c / (M k)).

The residual vibration of an undamped belt after the move is 4 sin^2(omega_n T / 4)
times the static stretch F m_c / (M k) (superposed steps +F, -2F, +F at 0, T/2,
T): it vanishes when each half-move lasts a whole number of belt periods
(`half_move_belt_periods`), which is why positioning time depends on the belt
stiffness in stripes, not smoothly.

Quantities: the flexible mode's `natural_frequency_hz` and `damping_ratio` from
M, C, K, and the same from MuJoCo's linearization of its own step map at the
run's integrator and dt (`linearized_*`: eigenvalues lambda of the one-step
Jacobian, s = ln(lambda) / dt); `move_time_s`, `residual_amplitude_m` (largest
carriage deviation from the target after the move), `settling_time_s` (time
after the move ends, or after release, from which the carriage stays inside
+-positioning_band for good); both read the motion between the samples too
(the cubic Hermite interpolant of position and velocity, springlab.exact.events:
read at the samples a peak reads low by (omega_n dt)^2 / 8 of the amplitude, and
a peak that passes the band by less than that went unseen, the settling time
early by half a belt period), `positioning_time_s` = move + settling, and the
analytic estimates: `settling_time_estimate_s` = ln(A / band) / (zeta omega_n),
A the envelope of the exact residual vibration after the move, and
`positioning_time_estimate_s` = `move_time_s` (the move this run makes, on the
step grid: known exactly) + that settling estimate. "For good" is certified, not assumed: after the force is
off the belt's energy E = mu s'^2/2 + k s^2/2 cannot grow, so the carriage
stays within |X - target| + (m_m / M) sqrt(2 E / k) of the target for ever;
a run that ends before that bound is inside the band reports
settled_for_good = False and settling_time_s = inf.

Measured on mujoco 4.0 (tests/scenes/printer_head/test_printer_head_integrators.py): RK4 treats the
belt like any force; `euler` treats TENDON damping explicitly (unlike joint
damping), so its stability limit on the belt mode is omega dt < 2 sqrt(zeta^2 +
1) - 2 zeta, below the joint-damping limit 2 sqrt(zeta^2 + 1) + 2 zeta;
`implicit` and `implicitfast` solve with M + h diag(C): the damping on each
joint's own row is implicit, the belt's coupling term explicit. Their limit lies
between the two (2.026 at the defaults, zeta = 0.030), and they do not conserve
momentum: the centre of mass moves as under a force (1 - 2 h c / M) F and a
move stops 2 h c D / M short (52 um at the defaults and dt = 0.1 ms, five times
the band: never settled). `discrete` makes the belt spring implicit and has no
limit. `stability_limit` computes the limit from MuJoCo's own step map, so
divergence advice is right for every integrator.

Code layout: this module is the scene; each scenario carries its variant
(`Scenario.variant`: `Move`, `StepForce`, `Settle`), which gives its force
segments and its own quantities, in moves.py with the formulas of the move and
the settling; design.py declares the design question (`design`) and implements
the hooks the design study calls (the batched moves, the analytic estimates).
"""

from __future__ import annotations

import math
from collections.abc import Mapping

import mujoco
import numpy as np

from springlab.errors import ParameterError
from springlab.exact import analytic
from springlab.exact.limits import stability_limit as joint_damping_stability_limit
from springlab.exact.linearize import one_step_map, operating_point
from springlab.exact.shaping import SHAPERS
from springlab.scenes.base import FOLLOWS_EXACT, MIN_MASS, MIN_MASS_REASON, Case, Parameter, Reference, Scenario, Scene
from springlab.scenes.capabilities.case import CaseView
from springlab.scenes.capabilities.fit import OscillatorFit
from springlab.scenes.capabilities.frequency import FrequencySpec
from springlab.sim.simulate import Setup, Trajectory, integrator_id

from . import control
from .design import DESIGN
from .feedback import Feedback
from .frequency import positioning
from .moves import BeltRun, Move, Settle, ShapedMove, StepForce, belt_matrices, move_profile
from .resonance_test import ResonanceTest

__all__ = ["SCENE", "PrinterHead", "linearized_mode", "step_matrix"]

#: relative round-off allowed in the centre-of-mass target (the bang-bang stops it at D exactly)
_TARGET_ROUNDOFF = 1e-12


def _quasi_static_deflection(params: dict[str, float], explicit: set[str]) -> dict[str, float]:
    """Scenario preset: the belt stretch [m] while the motor accelerates at full force."""
    m_c, m_m, k = params["carriage_mass"], params["motor_mass"], params["belt_stiffness"]
    return {"deflection": params["drive_force"] * m_c / ((m_c + m_m) * k)}


# -- what `springlab fit` asks of the scene (OscillatorFit hooks) ------------------------------------------------


def _belt_mode_mass(params: Mapping[str, float]) -> float:
    """The belt mode's mass mu = m_c m_m / (m_c + m_m) [kg]."""
    m_c, m_m = params["carriage_mass"], params["motor_mass"]
    return m_c * m_m / (m_c + m_m)


def _carriage_at(case: CaseView, x0: float, v0: float) -> tuple[np.ndarray, np.ndarray]:
    """(qpos, qvel) of `case` with the carriage at x0 [m], v0 [m/s] about the centre of mass at rest at 0.

    The carriage moves as -(m_m / M) of the belt's stretch, so the motor is at -(m_c / m_m) x0.
    """
    model, params = case.model, case.params
    qpos, qvel = model.qpos0.copy(), np.zeros(model.nv)
    ratio = params["carriage_mass"] / params["motor_mass"]
    for joint, q, v in (("carriage", x0, v0), ("motor", -ratio * x0, -ratio * v0)):
        qpos[model.joint(joint).qposadr[0]], qvel[model.joint(joint).dofadr[0]] = q, v
    return qpos, qvel


def _released_at(params: Mapping[str, float], x0: float) -> dict[str, float]:
    """Run parameters that start the carriage at rest at x0 [m]: the belt's deflection -x0 M / m_m."""
    total = params["carriage_mass"] + params["motor_mass"]
    return dict(params) | {"deflection": -x0 * total / params["motor_mass"]}


#: the loops' default gains and rate: the motor's (collocated) as in tests/scenes/printer_head/test_printer_feedback.py;
#: the carriage's lower, because across the belt the motor's gains are unstable (its boundary is 0.59 of them)
_LOOP_GAINS = {
    "motor": {"kp": 2000.0, "kd": 30.0, "ki": 0.0, "control_rate_hz": 5000.0},
    "carriage": {"kp": 500.0, "kd": 15.0, "ki": 0.0, "control_rate_hz": 5000.0},
}
#: the resonance test's defaults: a 50-400 Hz chirp of 1 N around the 195 Hz belt, an accelerometer read at
#: 2.5 kHz (an ADXL345 runs up to 3.2 kHz) with 0.5 m/s^2 of noise per reading, seed 0
_RESONANCE_TEST = {
    "sweep_low_hz": 50.0,
    "sweep_high_hz": 400.0,
    "sweep_force": 1.0,
    "accelerometer_rate_hz": 2500.0,
    "accelerometer_noise": 0.5,
    "seed": 0.0,
}


class PrinterHead(Scene):
    name = "printer_head"
    title = "inkjet carriage driven through a flexible belt: how fast can it be positioned?"
    joints = ("carriage", "motor")
    camera = "front"
    # RK4 at 0.1 ms: omega_n dt = 0.12 on the default belt mode (1225 rad/s);
    # predicted relative error about omega t (omega dt)^4 / 120 of the vibration
    # amplitude, i.e. below 1e-7 of the move distance.
    integrator = "rk4"
    dt = 1e-4
    default_scenario = "move"
    #: the design question it answers, read by springlab.studies.design (design.py)
    design = DESIGN
    #: `springlab frequency printer_head` (frequency.py): the belt's resonance and what it means for positioning
    frequency = FrequencySpec(
        "move",
        "drive",
        "carriage",
        "drive force to carriage position: the rigid body and the belt's resonance",
        interpret=positioning,
        input_unit="N",
    )
    #: the textbook question each scenario answers, and its answer as a sentence (Scene.questions)
    questions = {
        "move": (
            "How fast can the print head be positioned one inch away, to ±10 µm?",
            "The minimum-time move takes {move_time_s:.4g ms}; the {natural_frequency_hz:.4g} Hz belt ringing"
            " ({residual_amplitude_m:.3g µm} left) then settles in {settling_time_s:.3g ms}: positioned in"
            " {positioning_time_s:.4g ms} (the envelope's estimate: {positioning_time_estimate_s:.4g ms})."
            + FOLLOWS_EXACT,
        ),
        "step_force": (
            "What does a constant motor force do to the carriage and the belt?",
            "The carriage accelerates at {rigid_acceleration_m_s2:.4g} m/s² while the belt stretches to"
            " {max_belt_stretch_m:.3g µm}, twice its static {static_belt_stretch_m:.3g µm} less the damping, ringing"
            " at {natural_frequency_hz:.4g} Hz." + FOLLOWS_EXACT,
        ),
        "settle": (
            "Released from the belt stretch of full acceleration, how long does the carriage take to settle?",
            "It rings at {natural_frequency_hz:.4g} Hz with ζ = {damping_ratio:.3g} from {initial_deviation_m:.3g µm}"
            " and stays within ±{settling_band_m:.3g µm} after {settling_time_s:.3g ms} (the envelope's estimate:"
            " {settling_time_estimate_s:.3g ms})." + FOLLOWS_EXACT,
        ),
        **{
            f"move_{name}": (
                f"How fast is the print head positioned one inch away, to ±10 µm, when the move is shaped by a"
                f" {name.upper()} input shaper?",
                "The shaper adds {shaper_duration_s:.3g ms} and leaves {residual_vibration:.3g %} of the belt's"
                " vibration ({residual_amplitude_m:.3g ~m}, exact {residual_amplitude_m_exact:.3g ~m}): positioned"
                " in {positioning_time_s:.5g ms} (exact {positioning_time_s_exact:.5g ms}).",
            )
            for name in SHAPERS
        },
        **{
            f"feedback_{encoder}": (
                f"How fast does a sampled PD/PID loop on the {encoder} encoder position the print head, and how"
                " much gain margin does it have?",
                "At {control_period_s:.3g ms} per sample the loop has {gain_margin_db:.3g} dB of gain margin and"
                " {phase_margin_deg:.3g}° of phase margin (it loses stability at {critical_gain:.4g} times its"
                " gains); the carriage overshoots by {overshoot_m:.3g µm} (exact {overshoot_m_exact:.3g µm}) and is"
                " positioned in {positioning_time_s:.5g ms} (exact {positioning_time_s_exact:.5g ms}).",
            )
            for encoder in control.ENCODERS
        },
        "resonance_test": (
            "What belt frequency does a resonance test with the carriage accelerometer measure, and which shaper"
            " does it choose?",
            "The belt resonates at {belt_frequency_hz_measured:.6g} Hz (95 % interval"
            " {belt_frequency_ci95_width_hz:.3g} Hz wide; the model's {natural_frequency_hz:.6g} Hz), ζ ="
            " {belt_damping_ratio_measured:.3g} (the model's {damping_ratio:.3g}); it chooses {chosen_shaper}, whose"
            " move MuJoCo positions in {chosen_shaper_positioning_time_s:.5g ms} (exact"
            " {chosen_shaper_positioning_time_s_exact:.5g ms}).",
        ),
    }
    parameters = {
        p.name: p
        for p in (
            Parameter(
                "carriage_mass",
                "kg",
                "mass of the carriage with the print head",
                minimum=MIN_MASS,
                reason=MIN_MASS_REASON,
            ),
            Parameter(
                "motor_mass",
                "kg",
                "motor-side mass: rotor+pulley inertia J / r^2",
                minimum=MIN_MASS,
                reason=MIN_MASS_REASON,
            ),
            Parameter(
                "belt_stiffness",
                "N/m",
                "belt stiffness k between drive point and carriage",
                minimum=0.0,
                minimum_inclusive=False,
            ),
            Parameter("belt_damping", "N s/m", "belt damping c", minimum=0.0),
            Parameter("drive_force", "N", "the motor's force limit on the belt", minimum=0.0, minimum_inclusive=False),
            Parameter("move_distance", "m", "point-to-point move distance D", minimum=0.0, minimum_inclusive=False),
            Parameter(
                "positioning_band",
                "m",
                "half-width of the band around the target",
                minimum=0.0,
                minimum_inclusive=False,
            ),
            Parameter("deflection", "m", "belt stretch at t = 0 (centre of mass at rest at 0)", default=0.0),
            # the shaped moves' (default: the belt mode's own, Scenario.derive)
            Parameter(
                "shaper_frequency_hz", "Hz", "input shaper's design frequency", minimum=0.0, minimum_inclusive=False
            ),
            Parameter("shaper_damping_ratio", "-", "input shaper's design damping ratio", minimum=0.0, maximum=0.99),
            # the feedback loops'
            Parameter("kp", "N/m", "proportional gain of the sampled loop", minimum=0.0),
            Parameter("kd", "N s/m", "derivative gain (backward difference on the encoder)", minimum=0.0),
            Parameter("ki", "N/(m s)", "integral gain", minimum=0.0),
            Parameter("control_rate_hz", "Hz", "controller sample rate", minimum=0.0, minimum_inclusive=False),
            Parameter(
                "planned_move_time",
                "s",
                "the set point's bang-bang path to move_distance, its force fed forward (0: a step)",
                minimum=0.0,
            ),
            # the resonance test's
            Parameter("sweep_low_hz", "Hz", "chirp start frequency", minimum=0.0, minimum_inclusive=False),
            Parameter("sweep_high_hz", "Hz", "chirp end frequency", minimum=0.0, minimum_inclusive=False),
            Parameter("sweep_force", "N", "chirp force amplitude", minimum=0.0, minimum_inclusive=False),
            Parameter("accelerometer_rate_hz", "Hz", "accelerometer sample rate", minimum=0.0, minimum_inclusive=False),
            Parameter(
                "accelerometer_noise", "m/s^2", "accelerometer noise, standard deviation per reading", minimum=0.0
            ),
            Parameter("seed", "-", "seed of the accelerometer noise's generator", minimum=0.0),
        )
    }
    #: `springlab fit`: the carriage rings with the belt mode of mass mu about the resting centre of mass (x_eq = 0)
    fit = OscillatorFit(
        "carriage",
        ("settle",),
        mass=None,
        stiffness="belt_stiffness",
        damping="belt_damping",
        default_free=("belt_stiffness", "belt_damping", "x0", "v0", "offset"),
        mode_mass=_belt_mode_mass,
        initial_state=_carriage_at,
        release=_released_at,
    )
    scenarios = {
        s.name: s
        for s in (
            Scenario(
                "move",
                "bang-bang move of move_distance at the force limit, then residual vibration",
                0.3,
                variant=Move(),
            ),
            Scenario(
                "step_force",
                "constant drive_force from rest: rigid-body motion + one belt mode",
                0.05,
                variant=StepForce(),
            ),
            Scenario(
                "settle",
                "release at rest from the belt stretch of full-force acceleration",
                0.2,
                derive=_quasi_static_deflection,
                variant=Settle(),
            ),
            *(
                Scenario(
                    f"move_{name}",
                    f"the move shaped by a {name.upper()} input shaper designed at the belt mode (default)",
                    0.3,
                    derive=ShapedMove(name).derive,
                    variant=ShapedMove(name),
                )
                for name in SHAPERS
            ),
            *(
                Scenario(
                    f"feedback_{encoder}",
                    f"sampled PD loop on the {encoder} encoder along the planned shortest path, feedforward",
                    0.3,
                    presets=gains,
                    derive=Feedback(encoder).derive,
                    variant=Feedback(encoder),
                )
                for encoder, gains in _LOOP_GAINS.items()
            ),
            Scenario(
                "resonance_test",
                "chirp through the motor, the carriage accelerometer's record fitted: the belt mode measured",
                2.0,
                presets=_RESONANCE_TEST,
                variant=ResonanceTest(),
            ),
        )
    }

    # -- model ---------------------------------------------------------------

    def model_defaults(self, model: mujoco.MjModel) -> dict[str, float]:
        m_c, m_m, k, c = self.physical(model)
        return {
            "carriage_mass": m_c,
            "motor_mass": m_m,
            "belt_stiffness": k,
            "belt_damping": c,
            "drive_force": float(model.actuator("drive").ctrlrange[1]),
            "move_distance": float(model.numeric("move_distance").data[0]),
            "positioning_band": float(model.numeric("positioning_band").data[0]),
        }

    def edit(self, spec: mujoco.MjSpec, params: dict[str, float], scenario: Scenario) -> None:
        spec.body("carriage").mass = params["carriage_mass"]
        spec.body("motor").mass = params["motor_mass"]
        belt = spec.tendon("belt")
        belt.stiffness = [params["belt_stiffness"], 0.0, 0.0]
        belt.damping = [params["belt_damping"], 0.0, 0.0]
        spec.actuator("drive").ctrlrange = [-params["drive_force"], params["drive_force"]]
        spec.numeric("move_distance").data = [params["move_distance"]]
        spec.numeric("positioning_band").data = [params["positioning_band"]]
        if scenario.variant.instruments:
            control.add_instruments(spec)  # sensors: no change to the physics

    def check_consistency(self, params: dict[str, float], scenario: Scenario) -> None:
        """Refuse parameters that belong to other scenarios' variants, and what the variant cannot run."""
        variant = scenario.variant
        others = {
            name for s in self.scenarios.values() for name in s.variant.parameters if name not in variant.parameters
        }
        stray = sorted(others & set(params))
        if stray:
            users = sorted(s.name for s in self.scenarios.values() if stray[0] in s.variant.parameters)
            raise ParameterError(
                f"{stray[0]} is a parameter of {', '.join(users)}, not of {scenario.name}"
                f" (its parameters: {', '.join(self.scenario_parameters(scenario))})"
            )
        variant.check(params)

    def scenario_parameters(self, scenario: Scenario) -> list[str]:
        """The parameters a scenario reads: the scene's own and its variant's."""
        shared = {name for s in self.scenarios.values() for name in s.variant.parameters}
        return [name for name in self.parameters if name not in shared or name in scenario.variant.parameters]

    @staticmethod
    def physical(model: mujoco.MjModel) -> tuple[float, float, float, float]:
        """(carriage mass [kg], motor-side mass [kg], belt stiffness [N/m], belt damping [N s/m]) of `model`."""
        belt = model.tendon("belt").id  # (MjModel's tendon view names these _stiffness, _damping)
        return (
            float(model.body("carriage").mass[0]),
            float(model.body("motor").mass[0]),
            float(model.tendon_stiffness[belt]),
            float(model.tendon_damping[belt]),
        )

    @staticmethod
    def matrices(model: mujoco.MjModel) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Mass [kg], damping [N s/m] and stiffness [N/m] matrices in (q_c, q_m) of `model`."""
        return belt_matrices(model)

    #: (steps per half-move n, force [N]) of the bang-bang move on a grid of dt [s] (moves.py)
    move_profile = staticmethod(move_profile)

    # -- the run and its exact solution: each scenario's variant gives them ---------------------

    def setup(self, case: Case, steps: int, dt: float) -> Setup:
        return case.scenario.variant.setup(case, steps, dt)

    def reference(self, case: Case, time: np.ndarray, *, dt: float) -> Reference:
        return case.scenario.variant.reference(case, time, dt)

    # -- the belt mode -------------------------------------------------------

    @staticmethod
    def belt_mode(model: mujoco.MjModel) -> tuple[float, float]:
        """(natural frequency omega_n [rad/s], damping ratio [-]) of the flexible mode from M, C, K."""
        m_c, m_m, k, c = PrinterHead.physical(model)
        reduced = m_c * m_m / (m_c + m_m)
        return analytic.natural_frequency(reduced, k), analytic.damping_ratio(reduced, k, c)

    def modes(self, case: Case) -> list[tuple[float, float]]:
        model = case.model
        return [self.belt_mode(model)]

    def stability_limit(self, case: Case, integrator: str, omega: float, zeta: float) -> float:
        """Largest omega_n dt [-] at which `integrator` is stable on this model's belt mode.

        Measured from MuJoCo's own step map (see `linearized_mode`) by bisection,
        because MuJoCo's integrators treat tendon damping differently from joint
        damping (module docstring). inf where no step up to omega dt = 100 is unstable.
        """
        model = case.model
        integrator_id(integrator)

        def unstable(omega_dt: float) -> bool:
            return linearized_mode(model, integrator, omega_dt / omega)[2] > 1.0 + 1e-9

        grid = np.linspace(0.05, 4.0, 80)
        first = next((h for h in grid if unstable(h)), None)
        if first is None:
            return math.inf if not unstable(100.0) else joint_damping_stability_limit(integrator, zeta)
        low, high = first - (grid[1] - grid[0]), first
        for _ in range(50):
            mid = 0.5 * (low + high)
            low, high = (low, mid) if unstable(mid) else (mid, high)
        return low

    # -- results -------------------------------------------------------------

    def quantities(self, case: Case, trajectory: Trajectory) -> dict:
        model, params, scenario = case.model, case.params, case.scenario
        m_c, m_m, k, c = self.physical(model)
        total, reduced = m_c + m_m, m_c * m_m / (m_c + m_m)
        omega_n, zeta = self.belt_mode(model)
        dt = trajectory.dt
        out: dict = {
            "natural_frequency_hz": omega_n / (2 * math.pi),
            "damping_ratio": zeta,
        }
        lin_omega, lin_zeta, _ = case.memo(
            ("linearized_mode", trajectory.integrator, dt), lambda: linearized_mode(model, trajectory.integrator, dt)
        )
        out["linearized_natural_frequency_hz"] = lin_omega / (2 * math.pi)
        out["linearized_damping_ratio"] = lin_zeta
        out["omega_n_rad_s"] = omega_n
        out["total_mass_kg"] = total
        out["reduced_mass_kg"] = reduced
        out["vibration_share"] = m_m / total  # carriage deviation per metre of belt stretch
        columns = case.joint_columns(trajectory)
        (q_c, v_c), (q_m, v_m) = columns["carriage"], columns["motor"]
        run = BeltRun(params, m_c, m_m, k, omega_n, zeta, dt, trajectory.time, q_c, v_c, q_m, v_m, case, trajectory)
        return scenario.variant.quantities(out, run)


def step_matrix(model: mujoco.MjModel, integrator: str, dt: float) -> np.ndarray:
    """MuJoCo's one-step Jacobian d(qpos, qvel)_{n+1} / d(qpos, qvel)_n at rest, (2 nv, 2 nv).

    springlab.exact.linearize.one_step_map at qpos0 at rest (controls zero): centred differences of
    the step, every integrator (RK4 included); `model` is not modified. The model is linear, so
    the differences are exact up to round-off.
    """
    return one_step_map(model, integrator, dt, operating_point(model))


def linearized_mode(model: mujoco.MjModel, integrator: str, dt: float) -> tuple[float, float, float]:
    """The belt mode as MuJoCo integrates it: (omega_n [rad/s], damping ratio [-], |lambda| [-]).

    The one-step Jacobian's eigenvalues are 1, 1 (the rigid-body motion) and the
    belt mode's pair lambda; s = ln(lambda) / dt are the continuous roots the
    integrator realizes, omega_n^2 = s1 s2 and 2 zeta omega_n = -(s1 + s2).
    |lambda| > 1 means the integrator is unstable at this dt.
    """
    eigenvalues = np.linalg.eigvals(step_matrix(model, integrator, dt))
    roots = np.log(eigenvalues.astype(complex)) / dt
    belt = roots[np.argsort(-np.abs(roots))[:2]]  # the rigid-body roots are 0
    omega_sq = float(np.real(belt[0] * belt[1]))
    omega = math.sqrt(max(omega_sq, 0.0))
    zeta = -float(np.real(belt[0] + belt[1])) / (2 * omega) if omega > 0 else math.nan
    radius = float(np.max(np.abs(eigenvalues[np.argsort(-np.abs(roots))[:2]])))
    return omega, zeta, radius


SCENE = PrinterHead()
