"""nonlinear: a mass on a non-linear spring (chapter section 5.5, Fig. 5.20 and 5.21).

    m x'' + d x' + k1 x + k3 x^3 = F(t),   x = stretch of the spring [m], + away from the wall

The spring is MuJoCo's polynomial joint stiffness "k1 0 k3" (force
-(k1 x + k3 x^3), no Python callback). Its potential energy is
V(x) = k1 x^2 / 2 + k3 x^4 / 4 [J], so an unforced, undamped block keeps
E = m v^2 / 2 + V(x).

Parameters (SI): mass [kg], k1 [N/m], k3 [N/m^3], damping d [N s/m]
(mass, k1, k3, damping default to models/nonlinear.xml and are read back from
the compiled model), force_amplitude [N], force_frequency [Hz]
(F(t) = force_amplitude sin(2 pi force_frequency t); a constant force when the
frequency is 0), x0 [m], v0 [m/s].

Scenarios (the chapter asks for none by number; these show what it describes):

* `softening` (default): k1 = 100 N/m, k3 = -1e4 N/m^3, a spring that weakens
  with stretch (Fig. 5.20). Equilibria: 0 (stable, omega = sqrt(k1/m) =
  10 rad/s) and the saddles +-sqrt(-k1/k3) = +-0.1 m where the spring force
  vanishes again. Released at x0 = 0.09 m, inside the separatrix (the orbits
  through the saddles, energy V(0.1 m) = 0.25 J): a bounded, strongly
  anharmonic oscillation whose period comes from the energy integral.
* `softening_escape`: the same spring, launched from 0 at 0.75 m/s, i.e. with
  more energy (0.281 J) than the separatrix: the block passes the saddle and
  escapes. Under x'' = +|k3| x^3 / m it would reach infinity in finite time, so
  the run stops at the escape criterion |x| >= 3 x_saddle (0.3 m, ESCAPE_FACTOR)
  and reports the escape time; this is a result, not a divergence.
* `double_well`: k1 = -100 N/m, k3 = 1e4 N/m^3 (Duffing's double well): stable
  equilibria +-sqrt(-k1/k3) = +-0.1 m with small-oscillation frequency
  omega = sqrt(-2 k1 / m) = 14.1 rad/s, a saddle at 0 (barrier 0.25 J).
  Released at 0.13 m it oscillates inside the right-hand well.
* `forced_duffing`: the double well with damping 2.5 N s/m, forced by
  3 N sin(10 t) (Holmes' chaotic Duffing oscillator x'' + 0.25 x' - x + x^3 =
  0.3 sin t in units of 0.1 m and 0.1 s). Two runs whose initial positions
  differ by 1e-9 m separate to the size of the wells (0.1 m); the scenario
  reports the separation time and the finite-time Lyapunov exponent over it,
  both from a pair converged for that question (dt halved until two successive
  separation times agree within SEPARATION_RTOL: the default run's own
  trajectory leaves the exact one before the twins separate), and an estimate
  of the long-time largest Lyapunov exponent (renormalized pair of runs).

How the force keeps the integrator's order: as in slider.py, a sinusoidal
force comes from an MJCF-native generator, a very heavy exciter body on its
own spring at the forcing frequency, coupled to the block by a fixed tendon
spring whose stiffness is taken out of the joint's k1. The exciter is
integrated by the same integrator (RK4 stays fourth order) and the model stays
batchable. A constant force is a constant control (exact).

How it is validated (no closed-form x(t)): each scenario is held to `checks`,
scalar claims against independent references, each with its tolerance basis:

* linearization: MuJoCo's own acceleration, finite-differenced at every
  equilibrium (centred differences at two steps, Richardson-combined, which is
  exact for a cubic force), gives the linearized frequency (or saddle rate),
  checked against sqrt(|V''(x_e)| / m); tolerance 2 x the differences'
  round-off.
* energy: undamped, unforced runs conserve E; its drift relative to the
  largest kinetic energy of the run (E has an arbitrary zero) must stay within
  ENERGY_DRIFT_LIMIT = 1e-6 (the accuracy springlab promises at the default
  setting).
* period (bounded runs) or escape time (escaping runs): measured from the
  trajectory (cubic Hermite interpolation of the turning points / the escape
  crossing, O(dt^4)) against the energy integral T = 2 int dx / sqrt(2 (E - V) / m)
  by tanh-sinh quadrature with the turning-point factors (x - a)(b - x) taken
  out exactly; tolerance 2 x the Richardson error estimate of
  the measured value (from a second run at dt / 2, order p) + the quadrature's
  own error estimate + 100 eps per step.
* forced runs: the observed order of convergence from runs at dt, dt/2 and
  dt/4 over the first CONVERGENCE_WINDOW seconds (before the chaos amplifies
  the error out of the asymptotic range) against the integrator's order.

Phase plane: `phase_field` (unforced), `equilibria` (with stability from the
Jacobian) and `separatrices` (the energy level of every saddle) for plots.

Code layout: the conservative part and its quadratures live in
orbits.py, the chaos measurements in chaos.py, and the
check builders (for any joint) in springlab.scenes.checks; this module is the scene.
"""

from __future__ import annotations

import math
from collections.abc import Callable

import mujoco
import numpy as np

from springlab.errors import ParameterError
from springlab.exact import events
from springlab.scenes.base import MIN_MASS, MIN_MASS_REASON, Case, Check, Parameter, PhaseField, Scenario, Scene
from springlab.scenes.checks import (
    energy_drift_check,
    joint_jacobian,
    linearization_check,
    observed_order_check,
    richardson_check,
)
from springlab.sim import exciter
from springlab.sim.simulate import ORDERS, Setup, Trajectory

from . import chaos
from .chaos import (
    ACCURACY_FRACTION,
    LYAPUNOV_INTERVAL,
    LYAPUNOV_TIME,
    LYAPUNOV_TRANSIENT,
    PERTURBATION,
    SEPARATION_MAX_HALVINGS,
    SEPARATION_RTOL,
)
from .orbits import (
    crossings_through,
    curvature,
    energy,
    equilibria,
    equilibrium_kind,
    equilibrium_positions,
    gap_below,
    level_crossings,
    linear_eigenvalues,
    orbit,
    oscillation_period,
    potential,
    separatrices,
    spring_force,
    tanh_sinh,
    transit_time,
    turning_points,
)

__all__ = [
    "SCENE",
    "Nonlinear",
    "ACCURACY_FRACTION",
    "LYAPUNOV_INTERVAL",
    "LYAPUNOV_TIME",
    "LYAPUNOV_TRANSIENT",
    "PERTURBATION",
    "SEPARATION_MAX_HALVINGS",
    "SEPARATION_RTOL",
    "crossing_time",
    "crossings_through",
    "curvature",
    "energy",
    "equilibrium_kind",
    "equilibrium_positions",
    "gap_below",
    "level_crossings",
    "linear_eigenvalues",
    "measured_period",
    "oscillation_period",
    "potential",
    "spring_force",
    "tanh_sinh",
    "transit_time",
    "turning_points",
    "turning_times",
]

#: escape criterion: |x| >= ESCAPE_FACTOR x the saddle distance (or x the start, whichever is larger)
ESCAPE_FACTOR = 3.0
#: promised energy conservation of undamped runs at the default setting [-]
ENERGY_DRIFT_LIMIT = 1e-6
#: forced runs: self-convergence is measured over the first this many seconds [s]
CONVERGENCE_WINDOW = 5.0
#: finite-difference step of the linearization, relative to the model's length scale [-]
LINEARIZATION_STEP = 1e-4


# -- measuring the trajectory ---------------------------------------------------------


def _label(x: float) -> str:
    """A position [m] for a quantity name: '+0.1', '-0.1', '0'."""
    return "0" if x == 0 else f"{x:+.4g}"


def turning_times(time: np.ndarray, velocity: np.ndarray, acceleration: np.ndarray) -> np.ndarray:
    """Times [s] of the position maxima (v crossing zero downwards), to O(dt^4) by cubic Hermite
    interpolation of v with its derivative a [m/s^2] (springlab.exact.events)."""
    return events.down_crossings(time, velocity, acceleration)


def measured_period(time: np.ndarray, position: np.ndarray, velocity: np.ndarray, acceleration: np.ndarray) -> float:
    """Mean spacing of successive position maxima [s] (nan with fewer than two)."""
    peaks = turning_times(time, velocity, acceleration)
    if len(peaks) < 2:
        return math.nan
    return float((peaks[-1] - peaks[0]) / (len(peaks) - 1))


def crossing_time(time: np.ndarray, position: np.ndarray, velocity: np.ndarray, radius: float) -> float:
    """First time [s] |x| reaches `radius` [m], to O(dt^4) by cubic Hermite interpolation (nan: never)."""
    return events.first_crossing(time, position, velocity, radius)


# -- the scene -------------------------------------------------------------------------------


_UNFORCED = {"force_amplitude": 0.0, "damping": 0.0}
_DOUBLE_WELL = {"k1": -100.0, "k3": 1e4}


class Nonlinear(Scene):
    name = "nonlinear"
    title = "mass on a non-linear spring: equilibria, separatrices, escape, chaos (section 5.5)"
    joints = ("block",)
    camera = "side"
    # RK4 at 1 ms: omega dt <= 0.05 everywhere the scenarios go (the stiffest point is the
    # escape radius, |V''|/m = 2600 1/s^2); energy drift stays below 1e-6 of the exchanged energy.
    integrator = "rk4"
    dt = 1e-3
    default_scenario = "softening"
    #: the textbook question each scenario answers, and its answer as a sentence (Scene.questions)
    questions = {
        "softening": (
            "A softening spring: where are the equilibria and is a release from 0.09 m bounded?",
            "Equilibria at {equilibria_m} m (saddle, centre, saddle); the motion is {motion}, with period"
            " {period_quadrature_s:.7g} s by exact quadrature (MuJoCo's run: {period_simulated_s:.7g} s), longer"
            " than the linear 2π/ω.",
        ),
        "softening_escape": (
            "Released beyond the separatrix, does the softening spring hold the block?",
            "No: its energy {energy_J:.3g} J exceeds the barrier {barrier_height_J:.3g} J and the block escapes"
            " (motion {motion}), reaching {escape_radius_m:.3g} m after {escape_time_quadrature_s:.6g} s by exact"
            " quadrature (MuJoCo's run: {escape_time_s:.6g} s).",
        ),
        "double_well": (
            "A double-well spring: how does a block released in one well move?",
            "It stays in that well (energy {energy_J:.3g} J below the barrier), oscillating between"
            " {turning_points_m[0]:.3g ~m} and {turning_points_m[1]:.3g ~m} with period {period_quadrature_s:.7g} s"
            " by exact quadrature (MuJoCo's run: {period_simulated_s:.7g} s).",
        ),
        "forced_duffing": (
            "A damped, forced double well: is the motion predictable?",
            "No, it is chaotic: nearby starts separate at about {lyapunov_exponent_per_s:.3g} 1/s (± "
            "{lyapunov_standard_error_per_s:.2g} 1/s), so a start known to {perturbation_m:.3g ~m} is lost after"
            " {separation_time_s:.3g} s and the computed path is accurate only up to {accurate_until_s:.3g} s.",
        ),
    }
    parameters = {
        p.name: p
        for p in (
            Parameter("mass", "kg", "mass of the block", minimum=MIN_MASS, reason=MIN_MASS_REASON),
            Parameter("k1", "N/m", "linear spring coefficient (spring force k1 x + k3 x^3)"),
            Parameter("k3", "N/m^3", "cubic spring coefficient (< 0 softening, > 0 hardening)"),
            Parameter("damping", "N s/m", "damper coefficient d", minimum=0.0),
            Parameter("force_amplitude", "N", "amplitude of the applied force", default=0.0),
            Parameter(
                "force_frequency",
                "Hz",
                "frequency of the sinusoidal force (0: constant force)",
                minimum=0.0,
                default=5.0 / math.pi,
            ),
            Parameter("x0", "m", "initial stretch of the spring", default=0.09),
            Parameter("v0", "m/s", "initial velocity", default=0.0),
        )
    }
    scenarios = {
        s.name: s
        for s in (
            Scenario(
                "softening",
                "softening spring released inside the separatrix: bounded, anharmonic",
                5.0,
                {**_UNFORCED, "x0": 0.09, "v0": 0.0},
            ),
            Scenario(
                "softening_escape",
                "softening spring launched above the saddle energy: escapes",
                5.0,
                {**_UNFORCED, "x0": 0.0, "v0": 0.75},
            ),
            Scenario(
                "double_well",
                "Duffing double well (k1 < 0 < k3): oscillation inside one well",
                5.0,
                {**_UNFORCED, **_DOUBLE_WELL, "x0": 0.13, "v0": 0.0},
            ),
            Scenario(
                "forced_duffing",
                "damped, sinusoidally forced double well: chaos, 1e-9 m grows to the wells",
                40.0,
                {
                    **_DOUBLE_WELL,
                    "damping": 2.5,
                    "force_amplitude": 3.0,
                    "force_frequency": 5.0 / math.pi,
                    "x0": 0.1,
                    "v0": 0.0,
                },
            ),
        )
    }

    # -- model ---------------------------------------------------------------

    def model_defaults(self, model: mujoco.MjModel) -> dict[str, float]:
        joint = model.joint(self.joints[0])
        return {
            "mass": float(model.body("block").mass[0]),
            "k1": float(joint.stiffness[0]),
            "k3": float(model.jnt_stiffnesspoly[joint.id][1]),
            "damping": float(model.dof_damping[joint.dofadr[0]]),
        }

    @staticmethod
    def _forcing(params: dict[str, float]) -> str:
        """'harmonic', 'constant' or 'none' for these parameters."""
        if params["force_amplitude"] == 0.0:
            return "none"
        return "harmonic" if params["force_frequency"] > 0 else "constant"

    def edit(self, spec: mujoco.MjSpec, params: dict[str, float], scenario: Scenario) -> None:
        spec.body("block").mass = params["mass"]
        joint = spec.joint("block")
        joint.stiffness = [params["k1"], 0.0, params["k3"]]
        joint.damping = [params["damping"], 0.0, 0.0]
        if self._forcing(params) == "harmonic":
            self._add_exciter(spec, params)

    def _add_exciter(self, spec: mujoco.MjSpec, params: dict[str, float]) -> None:
        """The sinusoidal force generator (springlab.sim.exciter)."""
        omega = 2 * math.pi * params["force_frequency"]
        # everything the exciter drives, as a stiffness scale: the spring at the escape radius too
        reach = ESCAPE_FACTOR * max(abs(params["x0"]), self._length_scale(params))
        driven = (
            abs(params["k1"]) + 3 * abs(params["k3"]) * reach**2 + params["mass"] * omega**2 + params["damping"] * omega
        )
        exciter.add(
            spec,
            "block",
            force_amplitude=params["force_amplitude"],
            force_frequency=params["force_frequency"],
            driven_stiffness=driven,
        )

    @staticmethod
    def _length_scale(params: dict[str, float]) -> float:
        """sqrt(|k1/k3|) [m], the distance of the non-trivial equilibria (0 when k1 or k3 is 0)."""
        return math.sqrt(abs(params["k1"] / params["k3"])) if params["k3"] and params["k1"] else 0.0

    def setup(self, case: Case, steps: int, dt: float) -> Setup:
        params = case.params
        return self._setup(case, params["x0"], params["v0"])

    def _setup(self, case: Case, x0: float, v0: float) -> Setup:
        model, params = case.model, case.params
        qpos = np.zeros(model.nq)
        qvel = np.zeros(model.nv)
        qpos[model.joint(self.joints[0]).qposadr[0]] = x0
        qvel[model.joint(self.joints[0]).dofadr[0]] = v0
        forcing = self._forcing(params)
        if forcing == "harmonic":
            exciter.start(model, qvel, params["force_frequency"])
        control = np.array([params["force_amplitude"] if forcing == "constant" else 0.0])
        return Setup(qpos=qpos, qvel=qvel, control=control)

    # -- physics read back from the compiled model --------------------------

    def physical(self, model: mujoco.MjModel) -> tuple[float, float, float, float]:
        """(mass [kg], k1 [N/m], k3 [N/m^3], damping [N s/m]) the block sees in `model`.

        k1 includes a coupling tendon's share when the exciter is present.
        """
        joint = model.joint(self.joints[0])
        # the coupling tendon's coefficient on the block is 1
        k1 = float(joint.stiffness[0]) + exciter.coupling_stiffness(model)
        k2, k3 = (float(c) for c in model.jnt_stiffnesspoly[joint.id])
        if k2 != 0:
            raise ParameterError("the nonlinear scene's spring has no x^2 term (jnt_stiffnesspoly[0] must be 0)")
        return float(model.body("block").mass[0]), k1, k3, float(model.dof_damping[joint.dofadr[0]])

    def escape_radius(self, case: Case) -> float:
        """|x| [m] at which a softening spring's block counts as escaped (inf: it cannot escape)."""
        params = case.params
        m, k1, k3, d = case.physical()
        if k3 >= 0:
            return math.inf
        reach = max(self._length_scale({"k1": k1, "k3": k3}), abs(params["x0"]))
        return ESCAPE_FACTOR * reach if reach > 0 else math.inf

    def can_escape(self, case: Case) -> bool:
        """Whether the block can physically reach the escape radius: not if the run is unforced
        and the undamped orbit through (x0, v0) is bounded (damping only lowers the energy)."""
        params = case.params
        if not math.isfinite(self.escape_radius(case)):
            return False
        if self._forcing(params) != "none":
            return True
        m, k1, k3, d = case.physical()
        a, b = turning_points(params["x0"], params["v0"], m, k1, k3)
        return not (math.isfinite(a) and math.isfinite(b))

    def stop_condition(self, case: Case) -> Callable[[np.ndarray, np.ndarray], np.ndarray] | None:
        # a bounded orbit that reaches the radius is a numerical blow-up, left to divergence detection
        model = case.model
        if not self.can_escape(case):
            return None
        radius = self.escape_radius(case)
        column = model.joint(self.joints[0]).qposadr[0]
        return lambda qpos, qvel: np.abs(qpos[:, column]) >= radius

    def modes(self, case: Case) -> list[tuple[float, float]]:
        params = case.params
        m, k1, k3, d = case.physical()
        modes = []
        for x_e in equilibrium_positions(k1, k3):
            stiffness = abs(float(curvature(x_e, k1, k3)))
            if stiffness > 0:
                modes.append((math.sqrt(stiffness / m), d / (2 * math.sqrt(stiffness * m))))
        # the stiffest point the block can reach: the escape radius, or the bounded orbit's turning points
        if self.can_escape(case):
            reach = self.escape_radius(case)
        else:
            a, b = turning_points(params["x0"], params["v0"], m, k1, k3)
            bounded = math.isfinite(a) and math.isfinite(b)
            reach = max(abs(a), abs(b)) if bounded else 1.5 * max(abs(params["x0"]), self._length_scale(params))
        stiffness = abs(float(curvature(reach, k1, k3)))
        if stiffness > 0:
            modes.append((math.sqrt(stiffness / m), d / (2 * math.sqrt(stiffness * m))))
        if self._forcing(params) == "harmonic":
            modes.append((2 * math.pi * params["force_frequency"], 0.0))  # the exciter
        return modes

    # -- phase plane -----------------------------------------------------------

    def phase_field(self, case: Case) -> PhaseField | None:
        m, k1, k3, d = case.physical()

        def field(x, v):
            x, v = np.asarray(x, float), np.asarray(v, float)
            return v + 0.0 * x, (spring_force(x, k1, k3) - d * v) / m

        return field

    def equilibria(self, case: Case) -> list[dict]:
        """Every equilibrium with its linearization (springlab.scenes.nonlinear.orbits.equilibria)."""
        m, k1, k3, d = case.physical()
        return equilibria(m, k1, k3, d)

    def separatrices(self, case: Case, points: int = 401) -> list[tuple[np.ndarray, np.ndarray]]:
        """The saddles' energy levels as (x [m], v [m/s]) curves (springlab.scenes.nonlinear.orbits.separatrices)."""
        m, k1, k3, d = case.physical()
        return separatrices(m, k1, k3, points)

    # -- linearization through MuJoCo ---------------------------------------------

    def mujoco_jacobian(self, model: mujoco.MjModel, x_e: float, step: float) -> np.ndarray:
        """[[0, 1], [da/dx, da/dv]] [1/s^2, 1/s] of the block at (x_e [m], v = 0): springlab.scenes.checks.joint_jacobian."""
        return joint_jacobian(model, self.joints[0], x_e, step)

    def _linearization_checks(self, case: Case) -> list[Check]:
        model, params = case.model, case.params
        m, k1, k3, d = case.physical()
        scale = max(self._length_scale({"k1": k1, "k3": k3}), abs(params["x0"]), 1e-3)
        step = LINEARIZATION_STEP * scale
        checks = []
        for x_e in equilibrium_positions(k1, k3):
            stiffness = float(curvature(x_e, k1, k3))
            if stiffness == 0:
                continue
            probe = abs(x_e) + step  # the largest acceleration at the probes, for the round-off
            largest = (abs(k1) * probe + abs(k3) * probe**3) / m
            name = f"omega_at_{_label(x_e)}_m_rad_s" if stiffness > 0 else f"saddle_rate_at_{_label(x_e)}_m_per_s"
            checks.append(
                linearization_check(
                    name,
                    model,
                    self.joints[0],
                    x_e,
                    step,
                    stiffness / m,
                    largest,
                    "MuJoCo's qacc linearized by Richardson-combined centred differences (exact for a cubic"
                    " force): 2 x its round-off, against sqrt(|k1 + 3 k3 x^2| / m)",
                )
            )
        return checks

    # -- re-running for error estimates -------------------------------------------

    def rerun(
        self,
        case: Case,
        integrator: str,
        dt: float,
        duration: float,
        x0: float | None = None,
        v0: float | None = None,
        state: tuple | None = None,
    ) -> Trajectory:
        """Another run of the case at another setting, optionally from another block state or from a full
        (qpos, qvel) state (the case's model is not changed: simulate steps a copy)."""
        params = case.params
        if state is None and x0 is None and v0 is None:
            # the scenario's own start: a verification run (dt/2, dt/4), kept on the case for the next verdict
            return case.simulate(integrator, dt, duration, keep=True)
        if state is not None:
            qpos, qvel = state
            setup = Setup(qpos=qpos, qvel=qvel, control=self._setup(case, 0.0, 0.0).control)
        else:
            setup = self._setup(case, params["x0"] if x0 is None else x0, params["v0"] if v0 is None else v0)
        return case.simulate(integrator, dt, duration, setup=setup)

    def block(self, model: mujoco.MjModel, trajectory: Trajectory) -> tuple[np.ndarray, np.ndarray]:
        j = model.joint(self.joints[0])
        return trajectory.qpos[:, j.qposadr[0]], trajectory.qvel[:, j.dofadr[0]]

    # -- results -------------------------------------------------------------

    def _orbit(self, case: Case) -> dict:
        """The unforced, undamped motion through (x0, v0) (springlab.scenes.nonlinear.orbits.orbit)."""
        m, k1, k3, d = case.physical()
        return dict(case.memo("orbit", lambda: orbit(m, k1, k3, case.params["x0"], case.params["v0"])))

    def quantities(self, case: Case, trajectory: Trajectory) -> dict:
        model, params = case.model, case.params
        m, k1, k3, d = case.physical()
        x, v = self.block(model, trajectory)
        equilibria = self.equilibria(case)
        out: dict = {
            "equilibria_m": [e["x"] for e in equilibria],
            "equilibrium_kinds": [e["kind"] for e in equilibria],
            "stable_equilibria_m": [e["x"] for e in equilibria if e["stable"]],
        }
        for e in equilibria:
            if "omega_rad_s" in e:
                out[f"omega_at_{_label(e['x'])}_m_rad_s"] = e["omega_rad_s"]
            if "saddle_rate_per_s" in e:
                out[f"saddle_rate_at_{_label(e['x'])}_m_per_s"] = e["saddle_rate_per_s"]
        if k3 != 0 and k1 != 0:
            out["saddle_or_well_distance_m"] = self._length_scale({"k1": k1, "k3": k3})
        if k3 < 0 < k1:
            # the softening spring's force peaks where V'' = 0 (Fig. 5.20)
            x_peak = math.sqrt(k1 / (-3 * k3))
            out["peak_spring_force_N"] = float(-spring_force(x_peak, k1, k3))
            out["peak_force_stretch_m"] = x_peak
        unforced = d == 0 and self._forcing(params) == "none"
        if unforced:
            out.update(self._orbit(case))
            if out["motion"] == "bounded":
                out["period_simulated_s"] = measured_period(trajectory.time, x, v, self._acceleration(case, x, v))
            energy_j = energy(x, v, m, k1, k3)
            out["energy_drift_relative"] = float(
                np.max(np.abs(energy_j - energy_j[0])) / max(np.max(0.5 * m * v**2), 1e-300)
            )
        out["max_displacement_m"] = float(np.max(np.abs(x)))
        radius = self.escape_radius(case)
        if math.isfinite(radius):
            out["escape_radius_m"] = radius
            out["escaped"] = bool(trajectory.stopped)
            if trajectory.stopped:
                out["escape_time_s"] = crossing_time(trajectory.time, x, v, radius)
                if unforced:
                    try:
                        out["escape_time_quadrature_s"] = transit_time(
                            m, k1, k3, params["x0"], params["v0"], math.copysign(radius, x[-1])
                        )[0]
                    except ValueError:
                        pass
        if self._forcing(params) == "harmonic" and d > 0:
            out.update(self._chaos(case, trajectory))
        return out

    def _acceleration(self, case: Case, x: np.ndarray, v: np.ndarray) -> np.ndarray:
        m, k1, k3, d = case.physical()
        return (spring_force(x, k1, k3) - d * v) / m

    def well_size(self, case: Case) -> float:
        """The distance from the saddle to a well [m] (or the largest displacement without wells)."""
        m, k1, k3, d = case.physical()
        return self._length_scale({"k1": k1, "k3": k3}) or max(abs(case.params["x0"]), 1e-3)

    def _chaos(self, case: Case, trajectory: Trajectory) -> dict:
        """Sensitivity to initial conditions (springlab.scenes.nonlinear.chaos.chaos)."""
        return chaos.chaos(self, case, trajectory)

    def lyapunov_exponent(
        self,
        case: Case,
        integrator: str,
        dt: float,
        transient: float = LYAPUNOV_TRANSIENT,
        total: float = LYAPUNOV_TIME,
        interval: float = LYAPUNOV_INTERVAL,
    ) -> tuple[float, float]:
        """Largest Lyapunov exponent [1/s] and its standard error [1/s], an estimate by Benettin's
        renormalization (springlab.scenes.nonlinear.chaos.lyapunov_exponent)."""
        return chaos.lyapunov_exponent(self, case, integrator, dt, transient, total, interval)

    # -- validation ------------------------------------------------------------------

    def checks(self, case: Case, trajectory: Trajectory) -> list[Check]:
        model, params = case.model, case.params
        m, k1, k3, d = case.physical()
        # the case's own (MuJoCo's qacc at its equilibria): computed once per case
        out = list(case.memo("linearization_checks", lambda: tuple(self._linearization_checks(case))))
        integrator, dt = trajectory.integrator, trajectory.dt
        order = ORDERS[integrator]
        unforced = d == 0 and self._forcing(params) == "none"
        x, v = self.block(model, trajectory)
        if unforced:
            e = energy(x, v, m, k1, k3)
            drift = float(np.max(np.abs(e - e[0])) / max(np.max(0.5 * m * v**2), 1e-300))
            out.append(
                energy_drift_check(
                    drift,
                    ENERGY_DRIFT_LIMIT,
                    "springlab's promise for undamped runs at the default setting: |E - E0| <="
                    " 1e-6 x the largest kinetic energy",
                )
            )
            orbit = self._orbit(case)
            duration = float(trajectory.time[-1])
            if orbit["motion"] == "bounded":
                period = measured_period(trajectory.time, x, v, self._acceleration(case, x, v))
                half = self.rerun(case, integrator, dt / 2, duration)
                xh, vh = self.block(model, half)
                period_half = measured_period(half.time, xh, vh, self._acceleration(case, xh, vh))
                if not math.isfinite(period):  # fewer than two maxima in the run: nothing to measure
                    return out
                out.append(
                    richardson_check(
                        "period_s",
                        period,
                        period_half,
                        order,
                        orbit["period_quadrature_s"],
                        orbit["period_quadrature_error_s"],
                        trajectory.steps,
                        f"2 x the Richardson error estimate of the measured period (runs at dt and dt/2, order {order})"
                        " + quadrature error + 100 eps per step, against the energy integral by quadrature",
                    )
                )
            if trajectory.stopped:
                radius = self.escape_radius(case)
                escape = crossing_time(trajectory.time, x, v, radius)
                half = self.rerun(case, integrator, dt / 2, duration)
                xh, vh = self.block(model, half)
                escape_half = crossing_time(half.time, xh, vh, radius)
                try:
                    reference, quad_error = transit_time(
                        m, k1, k3, params["x0"], params["v0"], math.copysign(radius, x[-1])
                    )
                except ValueError:
                    reference, quad_error = math.nan, 0.0
                out.append(
                    richardson_check(
                        "escape_time_s",
                        escape,
                        escape_half,
                        order,
                        reference,
                        quad_error,
                        trajectory.steps,
                        f"2 x the Richardson error estimate of the measured escape time (dt and dt/2, order {order})"
                        " + quadrature error + 100 eps per step, against int dx / v(x) by quadrature",
                    )
                )
        elif self._forcing(params) != "none":
            out.append(self._convergence_check(case, integrator, dt, float(trajectory.time[-1])))
        return out

    def _convergence_check(self, case: Case, integrator: str, dt: float, duration: float) -> Check:
        """Observed order of convergence from runs at dt, dt/2 and dt/4 over CONVERGENCE_WINDOW."""
        window = min(CONVERGENCE_WINDOW, duration)
        runs = [self.rerun(case, integrator, dt / 2**i, window) for i in range(3)]
        positions = [self.block(case.model, run)[0][:: 2**i] for i, run in enumerate(runs)]
        return observed_order_check(positions, ORDERS[integrator], window)


SCENE = Nonlinear()
