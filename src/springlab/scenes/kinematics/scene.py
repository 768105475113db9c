"""kinematics: position, velocity and acceleration of a vehicle on a rail (chapter section 5.2).

    m x'' = F(t) = m a(t),   x = position along the road [m], v = x' [m/s], a = x'' [m/s^2]

No spring, no damper: the vehicle is driven by a prescribed force F(t) = m a(t),
so x(t), v(t) and a(t) are related only by differentiation and integration
(eq. 5.2-5.5), which is what the chapter's section 5.2 asks about.

Parameters (SI): mass [kg] (read back from models/kinematics.xml), x0 [m],
v0 [m/s], a0 [m/s^2] = a(0), jerk [m/s^3] = da/dt (constant). With them

    a(t) = a0 + jerk t
    v(t) = v0 + a0 t + jerk t^2 / 2
    x(t) = x0 + v0 t + a0 t^2 / 2 + jerk t^3 / 6

Scenarios:

* `polynomial_position`: the chapter's x(t) = 0.03 t^3 + 0.2 t^2 + 1.2 t + 3.0 m,
  i.e. x0 = 3 m, v0 = 1.2 m/s, a0 = 0.4 m/s^2, jerk = 0.18 m/s^3; it reports
  v(t) = 0.09 t^2 + 0.4 t + 1.2 m/s and a(t) = 0.18 t + 0.4 m/s^2.
* `linear_acceleration`: a(t) = 1.2 t + 3.0 m/s^2 with v(0) = 15 m/s and
  x(0) = 150 m; it reports v(t) = 0.6 t^2 + 3 t + 15 m/s and
  x(t) = 0.2 t^3 + 1.5 t^2 + 15 t + 150 m.
* `constant_acceleration`: eq. 5.5, a = 2 m/s^2 from v(0) = 10 m/s at x(0) = 0.
* `tachograph`: the v-t record of a touring bus over 12 s (like Fig. 5.6),
  TACHOGRAPH_TIMES / TACHOGRAPH_VELOCITIES: it pulls away from a stop at
  1.5 m/s^2 to 6 m/s in 4 s, cruises at 6 m/s for 4 s, and brakes at
  1.5 m/s^2 to a stop at 12 s. The displacement is the area under v(t)
  (12 + 24 + 12 = 48 m), the acceleration its slope. Only mass and x0 apply.

How the force keeps the comparison exact (see models/kinematics.xml): the
`force_ramp` actuator integrates its control, act' = ctrl, and its force is
the activation, so the initial activation m a0 and the constant control
m jerk make F(t) = m (a0 + jerk t) exactly linear in time at every RK4 stage;
the `force_step` motor adds a force that is constant over each step. The
tachograph's acceleration is piecewise constant and switches only at its knot
times, which must lie on the step grid (dt must divide 4 s and 8 s), so the
force is exact there too. The motion is then a polynomial of degree <= 3 on
every step, and RK4 (exact for polynomial solutions up to degree 4) reproduces
it to round-off. In the error model of springlab.runs.compare the reference is the
autonomous system z = (x, v, F, dF/dt), z' = A z, with A nilpotent
(A^4 = 0): RK4's predicted error is zero and its tolerance is the round-off
allowance; the first-order integrators get C h t |A^2 z|, i.e. O(dt).

Exact references: analytic.integrate_acceleration (polynomial scenarios) and
analytic.piecewise_linear_velocity (tachograph).

Code layout: each scenario carries its variant (`Scenario.variant`), as the car's
do: `Polynomial` here for the three polynomial scenarios, `Tachograph` in
tachograph.py (which draws the vehicle as a bus, bus.py).
"""

from __future__ import annotations

from collections.abc import Callable, Sequence

import mujoco
import numpy as np

from springlab.exact import analytic
from springlab.scenes.base import MIN_MASS, MIN_MASS_REASON, Case, Parameter, PhaseField, Reference, Scenario, Scene
from springlab.scenes.capabilities.fit import PolynomialFit
from springlab.sim.simulate import Setup, Trajectory

from .tachograph import TACHOGRAPH_TIMES, TACHOGRAPH_VELOCITIES, Tachograph, reject_profile_parameters

__all__ = ["SCENE", "Kinematics", "Polynomial", "TACHOGRAPH_TIMES", "TACHOGRAPH_VELOCITIES", "polynomial_expression"]


def polynomial_expression(symbol: str, coefficients: Sequence[float], unit: str) -> str:
    """'x(t) = 0.03 t^3 + 0.2 t^2 + 1.2 t + 3 m' from ascending coefficients [c0, c1, ...]."""
    terms = []
    for power in range(len(coefficients) - 1, -1, -1):
        c = float(coefficients[power])
        if c == 0.0:
            continue
        magnitude = abs(c)
        number = f"{magnitude:.6g}"
        if power == 0:
            body = number
        else:
            t_part = "t" if power == 1 else f"t^{power}"
            body = t_part if number == "1" else f"{number} {t_part}"
        sign = "-" if c < 0 else "+"
        terms.append((sign, body))
    if not terms:
        return f"{symbol}(t) = 0 {unit}"
    first_sign, first_body = terms[0]
    text = ("-" if first_sign == "-" else "") + first_body
    for sign, body in terms[1:]:
        text += f" {sign} {body}"
    return f"{symbol}(t) = {text} {unit}"


class Polynomial:
    """The variant of the polynomial scenarios: a(t) = a0 + jerk t from the parameters, x(t) a cubic.

    The `force_ramp` actuator's activation is the force m a0 and its control the constant m jerk,
    so F(t) = m (a0 + jerk t) is exactly linear in time at every RK4 stage (module docstring).
    """

    @staticmethod
    def acceleration_coefficients(params: dict[str, float]) -> tuple[float, float]:
        """(a0 [m/s^2], jerk [m/s^3]) of a(t) = a0 + jerk t."""
        return params["a0"], params["jerk"]

    def edit(self, spec: mujoco.MjSpec) -> None:
        """Nothing: the chapter's polynomial examples are a car's, as the MJCF draws it."""

    def setup(self, m: float, params: dict[str, float], steps: int, dt: float) -> Setup:
        """Released from x0 at v0; the activation starts at m a0 [N] and grows at m jerk [N/s]."""
        qpos = np.array([params["x0"]])
        a0, jerk = self.acceleration_coefficients(params)
        return Setup(
            qpos=qpos, qvel=np.array([params["v0"]]), act=np.array([m * a0]), control=np.array([m * jerk, 0.0])
        )

    def exact(
        self, m: float, params: dict[str, float], time: np.ndarray
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """(x [m], v [m/s], state matrix, states) at `time` [s]: z = (x, v, F, dF/dt)."""
        a0, jerk = self.acceleration_coefficients(params)
        x, v, a = analytic.integrate_acceleration(time, [a0, jerk], params["x0"], params["v0"])
        # z = (x, v, F, dF/dt): a force ramp, generated exactly
        system = np.zeros((4, 4))
        system[0, 1], system[1, 2], system[2, 3] = 1.0, 1.0 / m, 1.0
        states = np.column_stack([x, v, m * np.asarray(a, float) * np.ones_like(time), np.full_like(time, m * jerk)])
        return x, v, system, states

    def phase_field(self, params: dict[str, float]) -> Callable | None:
        """(x, v) -> (v, a) under a constant a (orbits: the parabolas v^2 = v0^2 + 2 a (x - x0)), else None."""
        if params["jerk"] != 0.0:
            return None
        a0 = params["a0"]
        return lambda x, v: (np.asarray(v, float), np.full(np.shape(v), a0, dtype=float))

    def quantities(
        self, m: float, params: dict[str, float], trajectory: Trajectory, t_end: float, x_sim: float, v_sim: float
    ) -> dict:
        """x(t), v(t), a(t), F(t) as expressions and their values at `t_end` [s], beside MuJoCo's."""
        a0, jerk = self.acceleration_coefficients(params)
        x0, v0 = params["x0"], params["v0"]
        position = [x0, v0, a0 / 2.0, jerk / 6.0]
        velocity = [v0, a0, jerk / 2.0]
        acceleration = [a0, jerk]
        x_end, v_end, a_end = (
            float(np.polynomial.polynomial.polyval(t_end, c)) for c in (position, velocity, acceleration)
        )
        return {
            "position_expression": polynomial_expression("x", position, "m"),
            "velocity_expression": polynomial_expression("v", velocity, "m/s"),
            "acceleration_expression": polynomial_expression("a", acceleration, "m/s^2"),
            "force_expression": polynomial_expression("F", [m * a0, m * jerk], "N"),
            "end_time_s": t_end,
            "x_end_m": x_end,
            "v_end_m_s": v_end,
            "a_end_m_s2": a_end,
            "displacement_m": x_end - x0,
            "x_end_simulated_m": x_sim,
            "v_end_simulated_m_s": v_sim,
            # the force is the activation: a = act / m
            "a_end_simulated_m_s2": float(trajectory.act[-1, 0]) / m,
        }


class Kinematics(Scene):
    name = "kinematics"
    title = "vehicle on a rail driven by F = m a(t): position, velocity, acceleration (section 5.2)"
    joints = ("vehicle",)
    camera = "chase"
    # RK4 is exact here (the motion is a cubic on every step), so dt only sets the
    # sampling; 10 ms puts the tachograph's switch times on the grid.
    integrator = "rk4"
    dt = 1e-2
    default_scenario = "polynomial_position"
    #: the textbook question each scenario answers, and its answer as a sentence (Scene.questions)
    questions = {
        "polynomial_position": (
            "Given x(t) = 0.03 t³ + 0.2 t² + 1.2 t + 3 m, find v(t) and a(t).",
            "{velocity_expression} and {acceleration_expression}; at t = {end_time_s:.3g} s, v = {v_end_m_s:.4g} m/s"
            " and a = {a_end_m_s2:.4g} m/s² (MuJoCo's run: {v_end_simulated_m_s:.10g} m/s and"
            " {a_end_simulated_m_s2:.10g} m/s²).",
        ),
        "linear_acceleration": (
            "Given a(t) = 1.2 t + 3 m/s², v(0) = 15 m/s, x(0) = 150 m, find v(t) and x(t).",
            "{velocity_expression} and {position_expression}: x = {x_end_m:.5g} m at t = {end_time_s:.3g} s"
            " (MuJoCo's run: {x_end_simulated_m:.10g} m).",
        ),
        "constant_acceleration": (
            "Uniform acceleration (eq. 5.5): a = 2 m/s² from 10 m/s; where is the car after 5 s?",
            "{position_expression}: {x_end_m:.4g} m, at {v_end_m_s:.4g} m/s (MuJoCo's run: {x_end_simulated_m:.10g} m"
            " at {v_end_simulated_m_s:.10g} m/s).",
        ),
        "tachograph": (
            "A bus's tachograph records v(t) over 12 s: how far did it go, and what were its accelerations?",
            "The area under v(t) is {displacement_m:.4g} m (MuJoCo's bus: {x_end_simulated_m:.10g} m); the slopes are"
            " {segment_accelerations_m_s2} m/s².",
        ),
    }
    parameters = {
        p.name: p
        for p in (
            Parameter("mass", "kg", "mass of the vehicle", minimum=MIN_MASS, reason=MIN_MASS_REASON),
            Parameter("x0", "m", "initial position x(0)", default=0.0),
            Parameter("v0", "m/s", "initial velocity v(0)", default=0.0),
            Parameter("a0", "m/s^2", "initial acceleration a(0)", default=0.0),
            Parameter("jerk", "m/s^3", "rate of change of the acceleration da/dt (constant)", default=0.0),
        )
    }
    #: `springlab fit`: the chapter's polynomial x0 + v0 t + a0 t^2 / 2 + jerk t^3 / 6 (section 5.2)
    fit = PolynomialFit("vehicle", ("polynomial_position",), ("x0", "v0", "a0", "jerk"))
    scenarios = {
        s.name: s
        for s in (
            Scenario(
                "polynomial_position",
                "x(t) = 0.03 t^3 + 0.2 t^2 + 1.2 t + 3.0 m: find v(t) and a(t)",
                10.0,
                {"x0": 3.0, "v0": 1.2, "a0": 0.4, "jerk": 0.18},
                variant=Polynomial(),
            ),
            Scenario(
                "linear_acceleration",
                "a(t) = 1.2 t + 3.0 m/s^2, v(0) = 15 m/s, x(0) = 150 m: find v(t), x(t)",
                5.0,
                {"x0": 150.0, "v0": 15.0, "a0": 3.0, "jerk": 1.2},
                variant=Polynomial(),
            ),
            Scenario(
                "constant_acceleration",
                "uniformly accelerated motion, eq. 5.5: a = 2 m/s^2 from 10 m/s",
                5.0,
                {"x0": 0.0, "v0": 10.0, "a0": 2.0, "jerk": 0.0},
                variant=Polynomial(),
            ),
            Scenario(
                "tachograph",
                "a bus's 12 s v-t record: displacement = area under v(t), a = its slope",
                TACHOGRAPH_TIMES[-1],
                {"x0": 0.0},
                derive=reject_profile_parameters,
                variant=Tachograph(),
            ),
        )
    }

    # -- model ---------------------------------------------------------------

    def model_defaults(self, model: mujoco.MjModel) -> dict[str, float]:
        return {"mass": float(model.body("vehicle").mass[0])}

    def edit(self, spec: mujoco.MjSpec, params: dict[str, float], scenario: Scenario) -> None:
        spec.body("vehicle").mass = params["mass"]
        scenario.variant.edit(spec)

    @staticmethod
    def mass(model: mujoco.MjModel) -> float:
        """Mass of the vehicle in `model` [kg]."""
        return float(model.body("vehicle").mass[0])

    def setup(self, case: Case, steps: int, dt: float) -> Setup:
        return case.scenario.variant.setup(self.mass(case.model), case.params, steps, dt)

    # -- exact reference (the scenario's variant) ----------------------------------

    def reference(self, case: Case, time: np.ndarray, *, dt: float) -> Reference:
        x, v, system, states = case.scenario.variant.exact(self.mass(case.model), case.params, time)
        return Reference(
            pos={"vehicle": np.asarray(x, float)},
            vel={"vehicle": np.asarray(v, float)},
            system=system,
            states=states,
            rows={"vehicle": (0, 1)},
        )

    # -- phase plane -------------------------------------------------------------

    def phase_field(self, case: Case) -> PhaseField | None:
        """(x, v) -> (v, a): autonomous only for a constant acceleration (None otherwise).

        With a(t) varying in time the phase plane has no fixed vector field; under a
        constant a the orbits are the parabolas v^2 = v0^2 + 2 a (x - x0).
        """
        return case.scenario.variant.phase_field(case.params)

    # -- results -------------------------------------------------------------

    def quantities(self, case: Case, trajectory: Trajectory) -> dict:
        # the nominal end time; MuJoCo's accumulated time differs from it by round-off only
        t_end = trajectory.steps * trajectory.dt
        x_sim = float(trajectory.qpos[-1, 0])
        v_sim = float(trajectory.qvel[-1, 0])
        return case.scenario.variant.quantities(self.mass(case.model), case.params, trajectory, t_end, x_sim, v_sim)


SCENE = Kinematics()
