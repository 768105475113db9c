"""slider: a mass on a spring-damper slide joint (chapter sections 5.3 and 5.4).

    m x'' + d x' + k x = F(t),   x = stretch of the spring [m], + away from the wall

Parameters (SI): mass [kg], stiffness [N/m], damping [N s/m], x0 [m], v0 [m/s],
force_amplitude [N], force_frequency [Hz]. mass, stiffness and damping default
to the values in models/slider.xml and are read back from the compiled model.

Forcing, and why it keeps the integrator's order:

* `step`: F(t) = force_amplitude for t >= 0 through the `force` motor; a
  constant control is exact for every integrator.
* `harmonic`: F(t) = force_amplitude sin(2 pi force_frequency t). A control
  held over each step would make RK4 first order, so the force comes from an
  MJCF-native generator instead: a very heavy exciter body on its own spring
  (natural frequency = the forcing frequency, amplitude E = 1 m), coupled to
  the block by a fixed tendon spring. The exciter is integrated by the same
  integrator, so the force is as accurate as the motion (RK4 stays fourth
  order, and the scene stays compatible with mujoco.rollout/batch). Its
  back-reaction on the block's force is below 1e-12 relative because the
  exciter's spring is 1e12 times stiffer than anything it drives. The tendon
  adds its stiffness to the block; the joint's own stiffness is lowered by the
  same amount, so the block still sees exactly k. The exciter is internal and
  not reported as a joint.

Exact references: analytic.free_response / step_response / harmonic_response.
"""

from __future__ import annotations

import math
from collections.abc import Callable

import mujoco
import numpy as np

from springlab.exact import analytic
from springlab.exact.linear import generator_system, state_matrix
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
from springlab.scenes.capabilities.fit import OscillatorFit
from springlab.scenes.capabilities.frequency import FrequencySpec
from springlab.scenes.capabilities.interactive import InteractiveSpec, MjcfEdit
from springlab.scenes.capabilities.oscillator import OscillatorSpec
from springlab.sim import exciter
from springlab.sim.simulate import Setup, Trajectory


def _damping_for_ratio(zeta: float) -> Callable[[dict[str, float], set[str]], dict[str, float]]:
    """Scenario preset: damping [N s/m] = 2 zeta sqrt(k m) from the other parameters."""

    def derive(params: dict[str, float], explicit: set[str]) -> dict[str, float]:
        return {"damping": 2.0 * zeta * math.sqrt(params["stiffness"] * params["mass"])}

    return derive


def _resonant(params: dict[str, float], explicit: set[str]) -> dict[str, float]:
    """Scenario preset: undamped, forced exactly at the natural frequency [Hz]."""
    return {
        "damping": 0.0,
        "force_frequency": math.sqrt(params["stiffness"] / params["mass"]) / (2 * math.pi),
    }


_FORCE_FREE = {"force_amplitude": 0.0}
#: the variant of a harmonically forced scenario (Scenario.variant): its force_amplitude drives a sine at
#: force_frequency through the exciter (a 0 Hz frequency is a step); any other scenario's force is a step
HARMONIC = "harmonic"


class Slider(Scene):
    name = "slider"
    title = "mass on a spring-damper slide joint: free, step and harmonic response"
    joints = ("slider",)
    camera = "side"
    # RK4 throughout. Each scenario's dt is the largest of 1, 2, 2.5, 4, 5, 10 ms
    # whose predicted error bound (springlab.runs.compare) is <= 1e-6 relative: the
    # cheapest setting that still validates at 1e-6. Scenes' fallback: 2 ms.
    integrator = "rk4"
    dt = 2e-3
    default_scenario = "free"
    #: the textbook's unit oscillator (springlab.studies.stability, springlab.studies.extremes)
    frequency = FrequencySpec(
        "free", "force", "slider", "applied force to block position: 1 / (m s^2 + d s + k)", input_unit="N"
    )
    oscillator = OscillatorSpec(
        mass="mass", stiffness="stiffness", damping="damping", x0="x0", v0="v0", free="free", joint="slider"
    )
    #: `springlab interactive`: the free and step scenarios in the browser, the same three values `edit` sets
    #: written into the MJCF text (the harmonic ones add the exciter through MjSpec: not in the page)
    interactive = InteractiveSpec(
        joint="slider",
        scenarios=("free", "underdamped", "undamped", "critical", "overdamped", "exercise", "step"),
        edits=(
            MjcfEdit("mass", "body", "block", "mass", child="inertial"),
            MjcfEdit("stiffness", "joint", "slider", "stiffness"),
            MjcfEdit("damping", "joint", "slider", "damping"),
        ),
        force="force_amplitude",
        actuator="force",
    )
    #: the textbook question each scenario answers, and its answer as a sentence (Scene.questions)
    questions = {
        "free": (
            "How does a lightly damped mass-spring system move after it is released?",
            "It oscillates at {natural_frequency_hz:.3g} Hz (damped period {damped_period_s:.3g} s) with an amplitude"
            " decaying as e^(-ζωt), ζ = {damping_ratio:.3g}, from {max_displacement_m:.3g ~m}." + FOLLOWS_EXACT,
        ),
        "undamped": (
            "What is the motion of an undamped mass on a spring released from x0?",
            "x(t) = x0 cos(ωt): ω = {omega_n_rad_s:.4g} rad/s, period {period_s:.4g} s, amplitude"
            " {max_displacement_m:.3g ~m} for ever." + FOLLOWS_EXACT,
        ),
        "underdamped": (
            "What does damping ratio 0.1 do to the free vibration?",
            "It still oscillates, at ω_d = {omega_d_rad_s:.4g} rad/s (period {damped_period_s:.4g} s), each swing"
            " smaller than the last (ζ = {damping_ratio:.3g})." + FOLLOWS_EXACT,
        ),
        "critical": (
            "How does a critically damped system return to rest?",
            "Without overshoot, as (A + Bt) e^(-ωt) with the double root λ = {lambda_1_per_s:.3g} 1/s: the fastest"
            " return that does not oscillate." + FOLLOWS_EXACT,
        ),
        "overdamped": (
            "How does an overdamped system (ζ = 2) return to rest?",
            "Without oscillating, as A e^(λ1 t) + B e^(λ2 t) with λ1 = {lambda_1_per_s:.4g} 1/s and λ2 ="
            " {lambda_2_per_s:.4g} 1/s, slower than critical damping." + FOLLOWS_EXACT,
        ),
        "step": (
            "What happens when a constant force is applied suddenly?",
            "The mass overshoots its new static position {static_deflection_m:.3g ~m}, reaching"
            " {max_displacement_m:.3g ~m} (almost twice it), and rings about it." + FOLLOWS_EXACT,
        ),
        "harmonic": (
            "What is the steady response to a harmonic force?",
            "At frequency ratio {frequency_ratio:.3g} the mass settles to amplitude {steady_state_amplitude_m:.3g ~m},"
            " lagging the force by {phase_lag_rad:.3g} rad ({phase_lag_rad:.3g °})." + FOLLOWS_EXACT,
        ),
        "resonance": (
            "What happens when an undamped system is forced at its natural frequency?",
            "Resonance: the amplitude grows linearly in time without bound (here to {max_displacement_m:.3g ~m} in"
            " {duration_s:.3g} s)." + FOLLOWS_EXACT,
        ),
        "exercise": (
            "The chapter's exercise: m = 1 kg, k = 2 N/m, c = 3 N s/m, released from 5 m; what is x(t)?",
            "x(t) = {coefficient_A_m:.3g} e^({lambda_1_per_s:.3g} t) + ({coefficient_B_m:.3g}) e^({lambda_2_per_s:.3g}"
            " t) m: overdamped (ζ = {damping_ratio:.3g}), no oscillation." + FOLLOWS_EXACT,
        ),
    }
    parameters = {
        p.name: p
        for p in (
            Parameter("mass", "kg", "mass of the block", minimum=MIN_MASS, reason=MIN_MASS_REASON),
            Parameter("stiffness", "N/m", "spring stiffness k", minimum=0.0),
            Parameter("damping", "N s/m", "damper coefficient d", minimum=0.0),
            Parameter("x0", "m", "initial stretch of the spring", default=0.1),
            Parameter("v0", "m/s", "initial velocity", default=0.0),
            Parameter("force_amplitude", "N", "amplitude of the applied force", default=0.0),
            Parameter("force_frequency", "Hz", "frequency of the harmonic force", minimum=0.0, default=2.0),
        )
    }
    #: `springlab fit`: the block rings as the mode itself; x0, v0 are parameters; `step` adds a known force
    fit = OscillatorFit(
        "slider",
        ("free", "underdamped", "undamped", "critical", "overdamped", "exercise", "step"),
        step_forces={"step": "force_amplitude"},
    )
    scenarios = {
        s.name: s
        for s in (
            Scenario("free", "release from x0, v0 with the model's damping", 5.0, _FORCE_FREE, dt=5e-3),
            Scenario(
                "undamped",
                "free response without damping (eq. 5.9)",
                5.0,
                _FORCE_FREE,
                derive=_damping_for_ratio(0.0),
                dt=2.5e-3,
            ),
            Scenario(
                "underdamped",
                "free response at damping ratio 0.1 (eq. 5.14)",
                5.0,
                _FORCE_FREE,
                derive=_damping_for_ratio(0.1),
                dt=5e-3,
            ),
            Scenario(
                "critical",
                "free response at damping ratio exactly 1",
                3.0,
                _FORCE_FREE,
                derive=_damping_for_ratio(1.0),
                dt=5e-3,
            ),
            Scenario(
                "overdamped",
                "free response at damping ratio 2 (eq. 5.15)",
                5.0,
                _FORCE_FREE,
                derive=_damping_for_ratio(2.0),
                dt=2.5e-3,
            ),
            Scenario(
                "step",
                "constant force from rest at the relaxed length",
                5.0,
                {"force_amplitude": 10.0, "x0": 0.0, "v0": 0.0},
                dt=5e-3,
            ),
            Scenario(
                "harmonic",
                "sinusoidal force from rest, transient included",
                10.0,
                {"force_amplitude": 1.0, "x0": 0.0, "v0": 0.0},
                dt=2e-3,
                variant=HARMONIC,
            ),
            Scenario(
                "resonance",
                "undamped, forced at its natural frequency: t sin growth",
                5.0,
                {"force_amplitude": 1.0, "x0": 0.0, "v0": 0.0},
                derive=_resonant,
                dt=2.5e-3,
                variant=HARMONIC,
            ),
            Scenario(
                "exercise",
                "the chapter's 'Under or overdamped?' problem: d/m = 3, k/m = 2",
                6.0,
                {"mass": 1.0, "stiffness": 2.0, "damping": 3.0, "x0": 5.0, "v0": 0.0, "force_amplitude": 0.0},
                dt=1e-2,
            ),
        )
    }

    # -- model ---------------------------------------------------------------

    def model_defaults(self, model: mujoco.MjModel) -> dict[str, float]:
        joint = model.joint("slider")
        return {
            "mass": float(model.body("block").mass[0]),
            "stiffness": float(joint.stiffness[0]),
            "damping": float(model.dof_damping[joint.dofadr[0]]),
        }

    @staticmethod
    def _forcing(params: dict[str, float], scenario: Scenario) -> str:
        """'harmonic', 'step' or 'none' for these parameters."""
        if params["force_amplitude"] == 0.0:
            return "none"
        if scenario.variant == HARMONIC and params["force_frequency"] > 0:
            return "harmonic"
        return "step"

    def edit(self, spec: mujoco.MjSpec, params: dict[str, float], scenario: Scenario) -> None:
        spec.body("block").mass = params["mass"]
        joint = spec.joint("slider")
        joint.stiffness = [params["stiffness"], 0.0, 0.0]
        joint.damping = [params["damping"], 0.0, 0.0]
        if self._forcing(params, scenario) == "harmonic":
            self._add_exciter(spec, params)

    def _add_exciter(self, spec: mujoco.MjSpec, params: dict[str, float]) -> None:
        """The harmonic force generator (springlab.sim.exciter)."""
        omega = 2 * math.pi * params["force_frequency"]
        exciter.add(
            spec,
            "slider",
            force_amplitude=params["force_amplitude"],
            force_frequency=params["force_frequency"],
            driven_stiffness=params["stiffness"] + params["mass"] * omega**2 + params["damping"] * omega,
        )

    def setup(self, case: Case, steps: int, dt: float) -> Setup:
        model, params = case.model, case.params
        qpos = np.zeros(model.nq)
        qvel = np.zeros(model.nv)
        qpos[model.joint("slider").qposadr[0]] = params["x0"]
        qvel[model.joint("slider").dofadr[0]] = params["v0"]
        forcing = self._forcing(params, case.scenario)
        if forcing == "harmonic":
            exciter.start(model, qvel, params["force_frequency"])
        control = np.array([params["force_amplitude"] if forcing == "step" else 0.0])
        return Setup(qpos=qpos, qvel=qvel, control=control)

    # -- physics read back from the compiled model --------------------------

    @staticmethod
    def physical(model: mujoco.MjModel) -> tuple[float, float, float]:
        """(mass [kg], stiffness [N/m], damping [N s/m]) the block sees in `model`.

        The stiffness includes a coupling tendon's share when the exciter is present.
        """
        joint = model.joint("slider")
        dof = joint.dofadr[0]
        # the coupling tendon's coefficient on the block is 1
        stiffness = float(joint.stiffness[0]) + exciter.coupling_stiffness(model)
        return float(model.body("block").mass[0]), stiffness, float(model.dof_damping[dof])

    def reference(self, case: Case, time: np.ndarray, *, dt: float) -> Reference:
        m, k, d = case.physical()
        params = case.params
        x0, v0, f0 = params["x0"], params["v0"], params["force_amplitude"]
        forcing = self._forcing(params, case.scenario)
        omega = 2 * math.pi * params["force_frequency"]
        # the autonomous system z' = A z behind the reference, forcing as generator states
        if forcing == "harmonic":
            x, v = analytic.harmonic_response(time, m, k, d, f0, params["force_frequency"], x0, v0)
            # g = (F sin, F cos): F(t) is the first, a rotation at omega
            system = generator_system([[m]], [[d]], [[k]], forcing=[[1.0, 0.0]], generator=[[0, omega], [-omega, 0]])
            states = np.column_stack([x, v, f0 * np.sin(omega * time), f0 * np.cos(omega * time)])
        elif forcing == "step":
            x, v = analytic.step_response(time, m, k, d, f0, x0, v0)
            system = generator_system([[m]], [[d]], [[k]], forcing=[[1.0]], generator=[[0.0]])  # g = F, constant
            states = np.column_stack([x, v, np.full_like(time, f0)])
        else:
            x, v = analytic.free_response(time, m, k, d, x0, v0)
            system = state_matrix([[m]], [[d]], [[k]])
            states = np.column_stack([x, v])
        return Reference(pos={"slider": x}, vel={"slider": v}, system=system, states=states, rows={"slider": (0, 1)})

    def modes(self, case: Case) -> list[tuple[float, float]]:
        m, k, d = case.physical()
        modes = []
        if k > 0:
            modes.append((math.sqrt(k / m), analytic.damping_ratio(m, k, d)))
        if self._forcing(case.params, case.scenario) == "harmonic":
            modes.append((2 * math.pi * case.params["force_frequency"], 0.0))  # the exciter
        return modes

    def phase_field(self, case: Case) -> PhaseField | None:
        m, k, d = case.physical()
        return lambda x, v: (v, -(k * x + d * v) / m)

    def equilibria(self, case: Case) -> list[dict]:
        m, k, d = case.physical()
        return [{"x": 0.0, "stable": k > 0}]

    # -- results -------------------------------------------------------------

    def quantities(self, case: Case, trajectory: Trajectory) -> dict:
        m, k, d = case.physical()
        params = case.params
        out: dict = {"regime": analytic.regime(m, k, d), "damping_ratio": analytic.damping_ratio(m, k, d)}
        if k > 0:
            omega_n = analytic.natural_frequency(m, k)
            out["omega_n_rad_s"] = omega_n
            out["natural_frequency_hz"] = omega_n / (2 * math.pi)
        if out["regime"] in ("underdamped", "undamped") and k > 0:
            out["period_s"] = 2 * math.pi / analytic.natural_frequency(m, k)
            omega_d = analytic.damped_frequency(m, k, d)
            out["omega_d_rad_s"] = omega_d
            out["damped_period_s"] = 2 * math.pi / omega_d
        else:
            # x(t) = A e^{lambda_1 t} + B e^{lambda_2 t} (eq. 5.15), the exercise's answer
            lam1, lam2 = sorted((r.real for r in analytic.characteristic_roots(m, k, d)), reverse=True)
            out["lambda_1_per_s"], out["lambda_2_per_s"] = lam1, lam2
            if out["regime"] == "overdamped":
                x0, v0 = params["x0"], params["v0"]
                out["coefficient_A_m"] = (v0 - lam2 * x0) / (lam1 - lam2)
                out["coefficient_B_m"] = (lam1 * x0 - v0) / (lam1 - lam2)
        forcing = self._forcing(params, case.scenario)
        if forcing == "step" and k > 0:
            out["static_deflection_m"] = params["force_amplitude"] / k
        if forcing == "harmonic":
            amplitude, phase = analytic.steady_state_amplitude(
                m, k, d, params["force_amplitude"], params["force_frequency"]
            )
            out["frequency_ratio"] = 2 * math.pi * params["force_frequency"] / math.sqrt(k / m) if k else math.inf
            # undamped at resonance the response grows without bound: no steady state (inf, null in JSON)
            out["steady_state_exists"] = bool(math.isfinite(amplitude))
            out["steady_state_amplitude_m"] = amplitude
            out["phase_lag_rad"] = phase
        x = trajectory.qpos[:, case.model.joint("slider").qposadr[0]]
        out["max_displacement_m"] = float(np.max(np.abs(x)))
        return out


SCENE = Slider()
