"""car: a car body on its suspension (chapter section 5.3, "Car suspension", Fig. 5.12).

One model, models/car.xml: the car body on the vertical slide joint `heave`,
whose position is the height of the car bottom above the ground [m]. Gravity
is on (the sag is the point). The scenarios that need more degrees of freedom
add them by MjSpec edits of that one model:

* `push_release` (the textbook problem) and `damped_release`: 1 DOF,
      m x'' + d x' + k (x - springref) = -m g,
  springref = clearance + m g / k, so the static equilibrium with the
  passengers in is x_s = clearance (0.10 m). Four passers-by push the car down
  with their weight F = push_mass g and let go at t = 0:
      x(t) = x_s + A cos(omega t),  A = -F / k,  omega = sqrt(k / m)
  (undamped; `damped_release` sets d = 2 zeta sqrt(k m) from `damping_ratio`).
  Sign convention: x up, so A < 0 means the car starts below x_s.
* `pitch_heave`: 2 DOF, `heave` plus a `pitch` hinge through the centre of
  mass about the car's lateral axis (+y, MuJoCo's right-hand rule: a positive
  pitch lowers the nose). The axle springs and dampers are *fixed tendons* on
  the joint coordinates, front length x - a theta and rear length x + b theta:
  exactly linear, so the stiffness matrix is exactly
      K = [[kf + kr, kr b - kf a], [kr b - kf a, kf a^2 + kr b^2]]
  (C likewise with cf, cr) and M = diag(m, I_pitch) (the hinge passes through
  the centre of mass, so there is no coupling or gravity torque). This is the
  textbook's small-angle pitch-plane model; a spatial tendon between body and
  ground would add the sin(theta) geometry (relative error theta^2 / 6, 2e-5
  at 0.01 rad) that the textbook model leaves out, and nothing else. The
  passers-by push at `push_position` (default: over the front axle) and let go.
  Natural frequencies and mode shapes come from MuJoCo's own linearization
  (mujoco.mjd_inverseFD: the continuous-time M = df/da, C = df/dv,
  K = df/dq of the inverse dynamics at the equilibrium) and are compared with
  the analytic 2x2 eigenproblem of M, K (and the state matrix with C).
* `road_bump`: the quarter car, one corner: sprung mass mass/4 on `heave`,
  suspension spring stiffness/4 and damper damping/4 (a fixed tendon
  heave - wheel), the unsprung mass on the slide joint `wheel` (height of the
  wheel centre above the flat road [m]) and the tire, a linear spring of
  `tire_stiffness` (no tire damping). The wheel reaches a half-sine bump
  r(t) = bump_height sin(pi speed t / bump_length) at t = 0 and leaves it at
  t_e = bump_length / speed; the car was at rest in static equilibrium before.
  The tire is linear both ways, so a run in which the tire force would turn
  negative (the wheel lifts off the road) is outside the model: its
  `model_limits` say when, and the run is not validated (exit 1). Peaks and
  the lift-off time are interpolated between the samples (springlab.exact.events).

How the bump input stays exact (MJCF-native, no Python force, rollout-ready):
the road height under the tire is the coordinate of an internal *exciter*: a
very heavy body on its own spring (natural frequency pi speed / bump_length),
started at t = 0 at 0 with velocity bump_height * omega, so it follows the
sine at the integrator's own order (RK4 stays fourth order; its back-reaction
is below 1e-12 relative because its spring is 1e12 times stiffer than the
tire load it carries; its slide axis is horizontal, so gravity does not act
on it). The tire is two gated springs, general actuators with affine gain
(force = gain(length) * ctrl): `tire_on_bump`, a spring between the exciter
and the wheel (transmission: the fixed tendon exciter - wheel), and
`tire_on_road`, a spring between the flat road and the wheel. Their controls
are piecewise constant, 1/0 while the wheel is on the bump and 0/1 after,
switched on the step boundary t_s nearest t_e: inputs switched on step
boundaries are exact. When t_e is a whole number of steps (the defaults:
0.5 s, at any dt dividing it) the realized input is the true half-sine. When it
is not, the realized bump lasts t_s instead of t_e (|t_s - t_e| <= dt / 2):
the reference stays the exact response to the true half-sine, and the
tolerance adds the exact difference between the responses to the realized
and the true input (computed from the exact linear solution of both), so the
stated tolerance proves itself either way.

Exact references: analytic.free_response (1 DOF), analytic.linear_response
(pitch_heave), and piecewise matrix exponentials of the quarter car's state
matrix with the bump generator's states (road_bump).

Code layout: this module is the scene (parameters, scenarios, the shared MjSpec
edits); each scenario carries its variant (`Scenario.variant`), which holds
what differs: release.py (push_release, damped_release),
pitch_heave.py, road_bump.py, with shared pieces in parts.py (all in this folder).

Sources for the realistic defaults: Gillespie, Fundamentals of Vehicle
Dynamics (SAE, 1992), ch. 5 "Ride": passenger cars have suspension damping
ratios of about 0.2-0.4 (default 0.3) and body bounce frequencies of about
1-1.5 Hz (road_bump's comfort suspension: 1.2 Hz). The textbook's
k = 1e6 N/m puts its car at 5 Hz, stiffer than a tire, which is why road_bump
presets the softer springs.
"""

from __future__ import annotations

import functools
from collections.abc import Mapping
from typing import Any

import mujoco
import numpy as np

from springlab.errors import ParameterError
from springlab.scenes.base import (
    FOLLOWS_EXACT,
    MIN_MASS,
    MIN_MASS_REASON,
    Case,
    Parameter,
    PhaseField,
    Reference,
    Scenario,
    Scene,
)
from springlab.scenes.capabilities.drawing import Drawing
from springlab.scenes.capabilities.fit import OscillatorFit
from springlab.scenes.capabilities.frequency import FrequencySpec
from springlab.scenes.capabilities.interactive import InteractiveSpec, MjcfEdit
from springlab.sim.simulate import Setup, Trajectory, quiet_mujoco

from .frequency import isolation, name_modes, push_at_the_front, road_under_the_car
from .parts import gravity
from .pitch_heave import FRONT_STIFFNESS_SHARE, PitchHeave, linearize, pitch_heave_defaults
from .release import Release, damping_from_ratio
from .road_bump import COMFORT_STIFFNESS, RoadBump, road_as_control

__all__ = ["SCENE", "Car", "linearize", "FRONT_STIFFNESS_SHARE", "COMFORT_STIFFNESS"]


def _released_at(params: Mapping[str, float], x0: float) -> dict[str, float]:
    """The fit's release hook (OscillatorFit.release): run parameters that start the car at rest at height x0 [m].

    The passers-by's push_mass [kg] holds it there, (clearance - x0) k / g; the damping is given, not its ratio.
    """
    overrides = dict(params)
    overrides["push_mass"] = (params["clearance"] - x0) * params["stiffness"] / SCENE.gravity()
    overrides.pop("damping_ratio", None)
    return overrides


class Car(Scene):
    name = "car"
    title = "car body on its suspension: sag, push-and-release, damping, pitch/heave, road bump"
    joints = ("heave", "pitch", "wheel")
    camera = "side"
    # RK4 throughout. Each scenario's dt is the largest of 1, 2, 2.5, 4, 5, 10 ms
    # whose predicted error bound (springlab.runs.compare) is <= 1e-6 relative, as for
    # the slider; road_bump's 0.5 s bump is a whole number of those steps.
    integrator = "rk4"
    dt = 1e-3
    default_scenario = "push_release"
    #: the textbook question each scenario answers, and its answer as a sentence (Scene.questions)
    questions = {
        "push_release": (
            "Passers-by push the car down with 250 kg and let go: how does it move?",
            "It bobs ±{static_sag_m:.3g ~m} about its rest height at {omega_rad_s:.4g} rad/s (period {period_s:.3g}"
            " s), undamped; MuJoCo's car rises at most to {max_height_m:.4g ~m} (exact: the rest height"
            " {equilibrium_height_m:.4g ~m} plus the sag)." + FOLLOWS_EXACT,
        ),
        "damped_release": (
            "The same release with shock absorbers at ζ = 0.3?",
            "The bobbing dies out with logarithmic decrement {logarithmic_decrement:.6g} (MuJoCo's peaks:"
            " {logarithmic_decrement_measured:.6g}), time constant {decay_time_constant_s:.3g} s; the car rises at"
            " most to {max_height_m:.4g ~m}." + FOLLOWS_EXACT,
        ),
        "pitch_heave": (
            "With front and rear springs, how does the car pitch and heave after a push over the front axle?",
            "Two modes at {frequency_1_hz:.4g} Hz and {frequency_2_hz:.4g} Hz (exactly ω = {omega_1_analytic_rad_s:.8g}"
            " and {omega_2_analytic_rad_s:.8g} rad/s; MuJoCo's linearization {omega_1_rad_s:.8g} and"
            " {omega_2_rad_s:.8g} rad/s), each a rotation about its own node ({mode_1_node_m:.3g} m and"
            " {mode_2_node_m:.3g} m from the centre of mass)." + FOLLOWS_EXACT,
        ),
        "road_bump": (
            "A quarter car drives over an 8 cm half-sine bump at 8 m/s: what do the passengers feel?",
            "A peak body acceleration of {peak_body_acceleration_m_s2:.3g} m/s² and {peak_suspension_travel_m:.3g ~m}"
            " of suspension travel; the tire keeps at least {min_tire_force_n:.4g} N of its static"
            " {static_tire_force_n:.4g} N on the road (measured on MuJoCo's run)." + FOLLOWS_EXACT,
        ),
    }
    parameters = {
        p.name: p
        for p in (
            Parameter(
                "mass",
                "kg",
                "sprung mass: car + passengers, everything the springs carry (road_bump: mass/4 per corner)",
                minimum=MIN_MASS,
                reason=MIN_MASS_REASON,
            ),
            Parameter("stiffness", "N/m", "the four springs together", minimum=0.0, minimum_inclusive=False),
            Parameter("damping", "N s/m", "the four dampers together", minimum=0.0),
            Parameter(
                "damping_ratio",
                "-",
                "damping as a fraction of critical, sets the dampers not given "
                "explicitly (Gillespie: 0.2-0.4 for passenger cars)",
                minimum=0.0,
                default=0.3,
            ),
            Parameter(
                "clearance",
                "m",
                "height of the car bottom above the ground at rest, passengers in",
                minimum=0.0,
                minimum_inclusive=False,
            ),
            Parameter(
                "push_mass", "kg", "mass of the passers-by pushing down with their weight", minimum=0.0, default=250.0
            ),
            Parameter(
                "pitch_inertia",
                "kg m^2",
                "moment of inertia about the lateral axis through the centre of mass",
                minimum=MIN_MASS,
                reason=MIN_MASS_REASON,
            ),
            Parameter(
                "front_axle_distance", "m", "a: centre of mass to front axle", minimum=0.0, minimum_inclusive=False
            ),
            Parameter(
                "rear_axle_distance", "m", "b: centre of mass to rear axle", minimum=0.0, minimum_inclusive=False
            ),
            Parameter(
                "front_stiffness",
                "N/m",
                f"front axle's two springs together (default: {FRONT_STIFFNESS_SHARE:g} x stiffness)",
                minimum=0.0,
                minimum_inclusive=False,
            ),
            Parameter(
                "rear_stiffness", "N/m", "rear axle's two springs together", minimum=0.0, minimum_inclusive=False
            ),
            Parameter("front_damping", "N s/m", "front axle's two dampers together", minimum=0.0),
            Parameter("rear_damping", "N s/m", "rear axle's two dampers together", minimum=0.0),
            Parameter(
                "push_position",
                "m",
                "where the passers-by push, ahead of the centre of mass (default: over the front axle)",
            ),
            Parameter(
                "unsprung_mass",
                "kg",
                "one wheel with its share of brake, hub and axle",
                minimum=MIN_MASS,
                reason=MIN_MASS_REASON,
            ),
            Parameter("tire_stiffness", "N/m", "vertical stiffness of one tire", minimum=0.0, minimum_inclusive=False),
            Parameter(
                "bump_height", "m", "height of the half-sine bump", minimum=0.0, minimum_inclusive=False, default=0.08
            ),
            Parameter(
                "bump_length",
                "m",
                "length of the bump along the road",
                minimum=0.0,
                minimum_inclusive=False,
                default=4.0,
            ),
            Parameter("speed", "m/s", "driving speed", minimum=0.0, minimum_inclusive=False, default=8.0),
        )
    }
    #: `springlab fit`: the car bottom's height rings about the clearance; a run starts at rest, pushed down
    #: `springlab frequency car [SCENARIO]` (frequency.py): the quarter car's road height to body heave (its
    #: transmissibility, the default); the chapter's single mass driven by the road through spring and damper
    #: (the isolation frequency sqrt(2) omega_n); both pitch-plane modes under the passers-by's push
    frequency = (
        FrequencySpec(
            "road_bump",
            "road",
            "heave",
            "road height to body heave: the quarter car's transmissibility",
            road_as_control,
            input_unit="m",
        ),
        FrequencySpec(
            "damped_release",
            "road_acceleration",
            "heave:acc",
            "road to body acceleration: the single mass's transmissibility (c s + k) / (m s^2 + c s + k)",
            road_under_the_car,
            isolation,
            input_unit="m/s^2",
        ),
        FrequencySpec(
            "pitch_heave",
            "push",
            "pitch",
            "a push over the front axle to body pitch: both pitch-plane modes",
            push_at_the_front,
            name_modes,
            input_unit="N",
        ),
    )
    fit = OscillatorFit(
        "heave",
        ("damped_release", "push_release"),
        default_free=("stiffness", "damping", "x0", "v0", "offset"),
        rest="clearance",
        release=_released_at,
    )
    #: `springlab interactive`: the 1-DOF releases in the browser, the values Release.edit sets written into the
    #: MJCF text; the clearance is fixed (it moves the body's pos), the mass slider stops short of where the
    #: undamped rebound would leave the springs (m = push_mass = 250 kg: check_consistency) and the stiffness
    #: well before the push reaches the ground (k = 24,525 N/m); pitch_heave and road_bump need a matrix exponential in the page (docs/interactive.md)
    interactive = InteractiveSpec(
        joint="heave",
        scenarios=("push_release", "damped_release"),
        edits=(
            MjcfEdit("mass", "body", "car", "mass", child="inertial"),
            MjcfEdit("stiffness", "joint", "heave", "stiffness"),
            MjcfEdit("damping", "joint", "heave", "damping"),
            MjcfEdit("clearance + mass * g / stiffness", "joint", "heave", "springref"),
        ),
        x0="clearance + mass * g / stiffness - (mass + push_mass) * g / stiffness",
        v0="0",
        rest="clearance + mass * g / stiffness - mass * g / stiffness",
        ranges={"mass": (260.0, 10000.0), "stiffness": (1e5, 1e7)},
    )
    scenarios = {
        s.name: s
        for s in (
            Scenario(
                "push_release",
                "the textbook problem: pushed down by 250 kg of passers-by, released, no damping",
                1.0,
                {"damping": 0.0},
                dt=1e-3,
                variant=Release(damped=False),
            ),
            Scenario(
                "damped_release",
                "the same release with dampers at damping_ratio (default 0.3)",
                1.0,
                derive=damping_from_ratio,
                dt=2e-3,
                variant=Release(damped=True),
            ),
            Scenario(
                "pitch_heave",
                "2 DOF: front/rear axle springs and dampers, pushed down over the front axle and released",
                2.0,
                derive=pitch_heave_defaults,
                dt=2e-3,
                variant=PitchHeave(),
            ),
            Scenario(
                "road_bump",
                "quarter car over a half-sine bump (0.08 m high, 4 m long) at 8 m/s",
                3.0,
                {"stiffness": COMFORT_STIFFNESS},
                derive=damping_from_ratio,
                dt=1e-3,
                variant=RoadBump(),
            ),
        )
    }

    # -- parameters ----------------------------------------------------------

    def model_defaults(self, model: mujoco.MjModel) -> dict[str, float]:
        heave = model.joint("heave")
        com = model.body("car").ipos
        return {
            "mass": float(model.body("car").mass[0]),
            "stiffness": float(heave.stiffness[0]),
            "damping": float(model.dof_damping[heave.dofadr[0]]),
            "clearance": float(model.qpos0[heave.qposadr[0]]),
            "pitch_inertia": float(model.body("car").inertia[1]),
            "front_axle_distance": float(model.site("front_axle").pos[0] - com[0]),
            "rear_axle_distance": float(com[0] - model.site("rear_axle").pos[0]),
            "unsprung_mass": float(model.body("wheels").mass[0]),
            "tire_stiffness": float(model.numeric("tire_stiffness").data[0]),
        }

    @functools.cache  # noqa: B019 - scenes are module-level singletons, never freed
    def gravity(self) -> float:
        """Gravitational acceleration g [m/s^2] of the MJCF (opt.gravity, read back)."""
        with quiet_mujoco():
            return gravity(self.model_spec().compile())

    def resolve(self, scenario: Scenario, overrides: Mapping[str, Any]) -> dict[str, float]:
        """Only the parameters the scenario uses; setting one it does not use is an error."""
        values = super().resolve(scenario, overrides)
        relevant = scenario.variant.relevant
        for name in overrides:
            if name not in relevant:
                raise ParameterError(
                    f"{name} does not apply to car {scenario.name}; its parameters: {', '.join(relevant)}"
                )
        return {name: values[name] for name in relevant}

    def check_consistency(self, params: dict[str, float], scenario: Scenario) -> None:
        # every moving body's mass and principal inertias at or above MuJoCo's MIN_MASS (else it cannot compile)
        scenario.variant.check_body_masses(params, self._mjcf_inertia())
        # the 2-DOF variants check the exact motion itself, in setup()
        scenario.variant.check_consistency(params, self.gravity())

    @functools.cache  # noqa: B019 - scenes are module-level singletons, never freed
    def _mjcf_inertia(self) -> tuple[float, float, float]:
        """The car body's principal inertias in the MJCF [kg m^2]: roll, pitch, yaw."""
        roll, pitch, yaw = (float(i) for i in self.model_spec().body("car").inertia)
        return roll, pitch, yaw

    # -- model ---------------------------------------------------------------

    def joint_columns(self, model: mujoco.MjModel, trajectory: Trajectory) -> dict[str, tuple[np.ndarray, np.ndarray]]:
        present = [j for j in self.joints if mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_JOINT, j) >= 0]
        columns = {}
        for joint in present:
            j = model.joint(joint)
            columns[joint] = (trajectory.qpos[:, j.qposadr[0]], trajectory.qvel[:, j.dofadr[0]])
        return columns

    def edit(self, spec: mujoco.MjSpec, params: dict[str, float], scenario: Scenario) -> None:
        g = -float(spec.option.gravity[2])
        car, heave = spec.body("car"), spec.joint("heave")
        clearance = params["clearance"]
        car.pos = [0.0, 0.0, clearance]
        heave.ref = clearance  # qpos(heave) stays the bottom's height; rest pose = clearance
        car.mass = params["mass"]
        scenario.variant.edit(spec, params, g)

    def setup(self, case: Case, steps: int, dt: float) -> Setup:
        return case.scenario.variant.setup(case, steps, dt)

    # -- exact references, modes, results (the scenario's variant) -------------

    def reference(self, case: Case, time: np.ndarray, *, dt: float) -> Reference:
        return case.scenario.variant.reference(case, time, dt)

    def modes(self, case: Case) -> list[tuple[float, float]]:
        return case.scenario.variant.modes(case)

    def phase_field(self, case: Case) -> PhaseField | None:
        return case.scenario.variant.phase_field(case)

    def equilibria(self, case: Case) -> list[dict]:
        return case.scenario.variant.equilibria(case)

    def quantities(self, case: Case, trajectory: Trajectory) -> dict:
        return case.scenario.variant.quantities(case, trajectory)

    def model_limits(self, case: Case, trajectory: Trajectory) -> list[str]:
        return case.scenario.variant.model_limits(case, trajectory)

    def drawing(self, case: Case) -> Drawing:
        return case.scenario.variant.drawing(case)


SCENE = Car()
