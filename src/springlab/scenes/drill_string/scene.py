"""drill_string: Fig. 5.2's drill rod, a kilometre of pipe between the top drive and the bit (chapter 5.1, 5.6).

"How do frictional forces on a drill bit at the bottom of a kilometre-long drill rod influence the rotation
of this drill rod?" The rod is a torsional continuum (springlab.scenes.drill_string.continuum, exact); the
MuJoCo model lumps it into N elements (`n_elements`), each a torsional spring between two rotors
(models/drill_string.xml, generated for any N by springlab.scenes.drill_string.build). Three gaps are
measured apart:

* integration: the MuJoCo run against the N-element model solved exactly (M and K read back from the
  compiled model, springlab.scenes.drill_string.lumped): the trajectory's tolerance, the `_exact` quantities;
* discretization: the N-element model's exact answer against the continuum's (`_continuum` quantities),
  second order in 1/N for lumped masses;
* friction model: MuJoCo's frictionloss is Coulomb friction on a soft constraint (see the model file):
  a stuck bit creeps very slowly; the breakaway checks state its share.

Scenarios:

* `modes`: the string released in the N-element model's first mode (the bit one turn ahead), no friction;
  the first answers.REPORTED_MODES frequencies of the model against the continuum's, and f1 measured from the run.
* `spin_up` (linear): the top drive accelerates uniformly to `top_speed_rpm` in `spin_up_time` (a constant
  torque on a 1e12 kg m^2 flywheel, switched off on a step boundary: exact for every integrator), the bit
  free; the run against the exact N-element response, the bit's speed against the continuum's modal
  series (CONTINUUM_MODES modes, the truncation bound stated).
* `breakaway` (default): the same start-up with dry friction `bit_friction_torque` at the bit: the bit
  sticks while the string winds up, breaks free when the string's torque on it reaches the friction
  torque, overshoots the top drive's speed and sticks again. Held to its checks: the breakaway time, the
  bit's peak speed and the re-stick time against the N-element model's exact stick-slip solution
  (Richardson-estimated run error), each also against the continuum's (travelling waves, exact).

The top drive's ramp is realized on the run's step grid (round(spin_up_time / dt) steps, the acceleration
adjusted so the speed reaches top_speed_rpm exactly); every exact answer uses the realized ramp.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import Any

import mujoco
import numpy as np

from springlab.errors import ParameterError
from springlab.exact import analytic
from springlab.exact.linear import state_matrix
from springlab.scenes import checks as scene_checks
from springlab.scenes.base import Case, Check, Parameter, Reference, Scenario, Scene
from springlab.scenes.capabilities.refine import RefinableSpec, RefinedQuestion
from springlab.sim.simulate import ORDERS, Setup, Trajectory

from . import answers, build, continuum, figures
from .answers import Drive
from .lumped import BIT, TOP, LumpedString

#: the most elements a string may have (the tendon encoding steps in O(N); see benchmarks/bench_drill_string.py)
MAX_ELEMENTS = 4096
#: elements of the default model (the breakaway time to about 1e-4 of the continuum's: docs/scenes/drill_string.md)
DEFAULT_ELEMENTS = 32
#: the `modes` scenario starts with the bit this far [rad] from rest, in the first mode's shape (one turn)
MODE_AMPLITUDE = 2 * math.pi
#: the lightest bottom-hole assembly [kg m^2] (see the parameter's reason)
MIN_BIT_INERTIA = 1.0
#: reference errors of the exact event times [s] (brentq to 1e-15 s on functions exact to round-off)
EVENT_ROOT_ERROR = 1e-12


def _positive(name: str, unit: str, description: str) -> Parameter:
    """A parameter that must be > 0."""
    return Parameter(name, unit, description, minimum=0.0, minimum_inclusive=False)


def _breakaway_answer(values: Mapping[str, Any]) -> str:
    """The breakaway's answer, worded for a run that re-sticks within its duration or one that does not yet."""
    if not math.isfinite(values.get("breakaway_time_s", math.nan)):
        return (
            "The bit is still stuck when the run ends at {duration_s:.4g} s, the string wound up"
            " {windup_turns_static:.3g} turns by the time it can break free (the rod's bit does at"
            " {breakaway_time_s_continuum:.5g} s): a longer --duration shows the slip."
        )
    text = (
        "The bit sticks while the string winds up {windup_turns:.2f} turns (exact {windup_turns_exact:.5f}); it"
        " breaks free at {breakaway_time_s:.5g} s (exact {breakaway_time_s_exact:.7g} s, the rod:"
        " {breakaway_time_s_continuum:.5g} s), whips round at {peak_bit_speed_rad_s:.3g rpm}, {peak_speed_ratio:.2g}x"
        " the top drive (exact {peak_bit_speed_rad_s_exact:.5g rpm}),"
    )
    if math.isfinite(values.get("restick_time_s", math.nan)):
        text += (
            " and re-sticks (its speed below 1 % of the top drive's, {restick_speed_rad_s:.2g rpm}) at"
            " {restick_time_s:.6g} s (exact {restick_time_s_exact:.6g} s)"
        )
    else:
        text += (
            " and has not slowed below 1 % of the top drive's speed ({restick_speed_rad_s:.2g rpm}) by the run's end"
        )
    return text + (
        ": stick-slip, with a perfectly steady top drive (MuJoCo's dry friction is Coulomb; the velocity-weakening"
        " friction of real bits is not a MuJoCo model)."
    )


def _round_divisor(total: float, dt: float) -> float:
    """The largest round timestep (1, 2, 2.5, 4 or 5 x 10^k s) not above `dt` that divides `total` [s]."""
    for exponent in range(math.floor(math.log10(dt)), math.floor(math.log10(dt)) - 12, -1):
        for mantissa in (5.0, 4.0, 2.5, 2.0, 1.0):
            step = mantissa * 10.0**exponent
            if step <= dt * (1 + 1e-12) and abs(total / step - round(total / step)) <= 1e-9 * total / step:
                return step
    return total / math.ceil(total / dt)


def _friction_free(params: dict[str, float], explicit: set[str]) -> dict[str, float]:
    """Scenario preset: no friction at the bit (the linear scenarios)."""
    return {"bit_friction_torque": 0.0}


class DrillString(Scene):
    name = "drill_string"
    title = "Fig. 5.2's drill rod: torsional modes, top-drive start-up and the bit's breakaway under dry friction"
    joints = (TOP, BIT)
    camera = "side"
    integrator = "rk4"
    # RK4 throughout; each scenario's dt is the largest of 1, 2, 2.5, 4, 5 ms that validates at the default
    # N = 32 with an error bound <= 1e-6 (docs/scenes/drill_string.md)
    dt = 2e-3
    default_scenario = "breakaway"
    parameters = {
        p.name: p
        for p in (
            Parameter(
                "n_elements",
                "-",
                "lumped elements the string is cut into (an integer)",
                minimum=1,
                maximum=MAX_ELEMENTS,
                default=DEFAULT_ELEMENTS,
                reason=f"a whole number of elements; at most {MAX_ELEMENTS} (about 4.5 ms of wall time per step)",
            ),
            _positive("length", "m", "length of the drill string L"),
            _positive("shear_modulus", "Pa", "shear modulus G of the pipe's steel"),
            _positive("density", "kg/m^3", "density rho of the pipe's steel"),
            _positive("outer_diameter", "m", "outer diameter D of the drill pipe"),
            Parameter("inner_diameter", "m", "inner diameter d of the drill pipe (< D)", minimum=0.0),
            Parameter(
                "bit_inertia",
                "kg m^2",
                "inertia J_b of the bottom-hole assembly and bit",
                minimum=MIN_BIT_INERTIA,
                reason="a BHA is tens to hundreds of kg m^2; below 1 kg m^2 the bit's time constant J_b / Z falls"
                " under 3 ms and the exact travelling-wave solution would take millions of steps",
            ),
            Parameter("bit_friction_torque", "N m", "dry friction torque T_f at the bit", minimum=0.0),
            _positive("top_speed_rpm", "rpm", "the top drive's speed after spin-up"),
            _positive("spin_up_time", "s", "time the top drive takes to reach its speed"),
        )
    }
    scenarios = {
        s.name: s
        for s in (
            Scenario(
                "modes",
                "released in the N-element model's first mode (bit one turn ahead): frequencies vs the continuum",
                7.5,
                derive=_friction_free,
                dt=2.5e-3,
            ),
            Scenario(
                "spin_up",
                "the top drive spins up to its speed, bit free: the response against the exact and the continuum",
                10.0,
                derive=_friction_free,
                dt=2e-3,
            ),
            Scenario(
                "breakaway",
                "the top drive spins up, dry friction at the bit: stick, wind-up, breakaway, overshoot, re-stick",
                10.0,
                dt=1e-3,
            ),
        )
    }
    questions = {
        "modes": (
            "What are the torsional natural frequencies of the drill string, and how many elements does f1 need?",
            "f1 = {mode_1_frequency_hz_continuum:.6g} Hz for the rod (period {mode_1_period_s_continuum:.6g} s); the"
            " {n_elements:.0f}-element model's is exactly {mode_1_frequency_hz_exact:.7g} Hz (period"
            " {mode_1_period_s:.6g} s, discretization error {mode_1_discretization_error:.2g}) and the run measures"
            " {mode_1_frequency_hz:.7g} Hz.",
        ),
        "spin_up": (
            "How does the bit follow when the top drive spins up, with nothing holding the bit?",
            "The bit lags the top drive by a travel time of {travel_time_s:.3g} s and overshoots to"
            " {bit_peak_speed_rad_s:.7g rpm} (exact {bit_peak_speed_rad_s_exact:.7g rpm}; the rod's"
            " {bit_peak_speed_rad_s_continuum:.5g rpm}) against {top_speed_rpm:.3g} rpm at the top: the string winds"
            " up {windup_turns:.7g} turns (exact {windup_turns_exact:.7g}) and rings at f1 ="
            " {mode_1_frequency_hz_exact:.4g} Hz.",
        ),
        "breakaway": (
            "How does friction at the bit influence the rotation of a kilometre-long rod (Fig. 5.2)?",
            _breakaway_answer,
        ),
    }
    #: `springlab refine`: how many elements each question needs, and with which integrator and timestep
    refinable = RefinableSpec(
        size="n_elements",
        description="lumped elements",
        sizes=(4, 8, 16, 32, 64, 128),
        questions=(
            RefinedQuestion(
                "mode_1_frequency_hz",
                "modes",
                "the first torsional frequency f1",
                "mode_1_frequency_hz_exact",
                "mode_1_frequency_hz_continuum",
            ),
            RefinedQuestion(
                "breakaway_time_s",
                "breakaway",
                "the time the bit breaks free",
                "breakaway_time_s_exact",
                "breakaway_time_s_continuum",
            ),
            RefinedQuestion(
                "peak_bit_speed_rad_s",
                "breakaway",
                "the bit's peak speed after breakaway",
                "peak_bit_speed_rad_s_exact",
                "peak_bit_speed_rad_s_continuum",
            ),
        ),
        order=2.0,
        switch_time="spin_up_time",
    )
    figure = staticmethod(figures.panels)

    # -- parameters and model ----------------------------------------------------

    def model_defaults(self, model: mujoco.MjModel) -> dict[str, float]:
        values = {
            name: float(model.numeric(name).data[0])
            for name in ("length", "shear_modulus", "density", "outer_diameter", "inner_diameter")
        }
        values["top_speed_rpm"] = float(model.numeric("top_speed_rpm").data[0])
        values["spin_up_time"] = float(model.numeric("spin_up_time").data[0])
        values["bit_friction_torque"] = float(model.dof_frictionloss[model.joint(BIT).dofadr[0]])
        values["bit_inertia"] = self.rod(model).bit_inertia
        return values

    def check_consistency(self, params: dict[str, float], scenario: Scenario) -> None:
        n = params["n_elements"]
        if n != round(n):
            raise ParameterError(f"n_elements must be a whole number of elements (1 to {MAX_ELEMENTS}), got {n:g}")
        if params["inner_diameter"] >= params["outer_diameter"]:
            raise ParameterError(
                f"inner_diameter must be smaller than outer_diameter ({params['outer_diameter']:g} m),"
                f" got {params['inner_diameter']:g} m"
            )

    def edit(self, spec: mujoco.MjSpec, params: dict[str, float], scenario: Scenario) -> None:
        build.generate(spec, params)

    # -- physics read back from the compiled model ---------------------------------

    @staticmethod
    def rod(model: mujoco.MjModel) -> continuum.Rod:
        """The continuum the model discretizes: L, G, rho, J_p from its numerics, J_b from the bit's inertia."""
        return answers.rod_of(model)

    @staticmethod
    def physical(model: mujoco.MjModel) -> tuple[float, ...]:
        """(L [m], G [Pa], rho [kg/m^3], J_p [m^4], J_b [kg m^2], T_f [N m], N [-]) read back from the model."""
        rod = DrillString.rod(model)
        lumped = LumpedString.of(model)
        return (
            rod.length,
            rod.shear_modulus,
            rod.density,
            rod.polar_moment,
            rod.bit_inertia,
            lumped.friction,
            float(lumped.size - 1),
        )

    @staticmethod
    def drive(model: mujoco.MjModel, dt: float) -> Drive:
        """The top drive's start-up on a step grid of dt [s]."""
        return answers.drive_of(model, dt)

    def modes(self, case: Case) -> list[tuple[float, float]]:
        return [(float(w), 0.0) for w in answers.frequencies(answers.lumped_of(case))]

    def grid_notes(self, case: Case, dt: float) -> list[str]:
        """The spin-up's ramp is whole steps: a dt that does not divide spin_up_time lengthens or shortens it."""
        if case.scenario.name == "modes":
            return []
        asked = float(case.params["spin_up_time"])
        drive = self.drive(case.model, dt)
        if abs(drive.ramp_time - asked) <= 1e-9 * asked:
            return []
        return [
            f"the top drive's {asked:g} s spin-up lasts {drive.ramp_time:.6g} s on this step grid ({drive.ramp_steps}"
            f" steps of {dt:g} s), and the exact reference follows it; a dt that divides {asked:g} s keeps it:"
            f" {_round_divisor(asked, dt):g} s, or the nearest, {asked / math.ceil(asked / dt):.6g} s and"
            f" {asked / max(1, math.floor(asked / dt)):.6g} s"
        ]

    # -- a run ------------------------------------------------------------------------

    def setup(self, case: Case, steps: int, dt: float) -> Setup:
        model, scenario = case.model, case.scenario
        lumped = answers.lumped_of(case)
        if scenario.name == "modes":
            _, shapes = answers.modes_of(case)
            return Setup(qpos=MODE_AMPLITUDE * shapes[:, 0], qvel=np.zeros(model.nv), control=np.zeros(model.nu))
        drive = self.drive(model, dt)
        control = np.zeros((steps, model.nu))
        control[: drive.ramp_steps, 0] = lumped.drive_control(drive.acceleration)
        return Setup(qpos=np.zeros(model.nq), qvel=np.zeros(model.nv), control=control)

    def reference(self, case: Case, time: np.ndarray, *, dt: float) -> Reference | None:
        model, scenario = case.model, case.scenario
        lumped = answers.lumped_of(case)
        n = lumped.size
        mass = np.diag(lumped.mass)
        rows = {TOP: (0, n), BIT: (n - 1, 2 * n - 1)}
        if scenario.name == "modes":
            omega, shapes = answers.modes_of(case)
            shape = MODE_AMPLITUDE * shapes[:, 0]
            q = np.outer(np.cos(omega[0] * time), shape)
            v = np.outer(-omega[0] * np.sin(omega[0] * time), shape)
            system = state_matrix(mass, np.zeros_like(mass), lumped.stiffness)
            return Reference(
                pos={TOP: q[:, 0], BIT: q[:, -1]},
                vel={TOP: v[:, 0], BIT: v[:, -1]},
                system=system,
                states=np.hstack([q, v]),
                rows=rows,
            )
        if scenario.name == "spin_up":
            drive = self.drive(model, dt)
            torque = lumped.drive_torque(lumped.drive_control(drive.acceleration))
            breaks = np.array([0.0, drive.ramp_time])
            values = np.vstack([torque, np.zeros(n)])
            q, v = analytic.linear_response(
                time, mass, np.zeros_like(mass), lumped.stiffness, np.zeros(n), np.zeros(n), force=(breaks, values)
            )
            # z = (q, v, u): the drive's torque u a generator state, constant within each step
            system = np.zeros((2 * n + 1, 2 * n + 1))
            system[:, : 2 * n] = np.pad(state_matrix(mass, np.zeros_like(mass), lumped.stiffness), ((0, 1), (0, 0)))
            system[n, 2 * n] = 1.0 / lumped.mass[0]
            on = time < drive.ramp_time - 0.5 * dt
            states = np.column_stack([q, v, np.where(on, torque[0], 0.0)])
            return Reference(
                pos={TOP: q[:, 0], BIT: q[:, -1]},
                vel={TOP: v[:, 0], BIT: v[:, -1]},
                system=system,
                states=states,
                rows=rows,
            )
        return None  # breakaway: held to its checks (events of a piecewise-linear motion)

    # -- results ----------------------------------------------------------------------

    def quantities(self, case: Case, trajectory: Trajectory) -> dict[str, Any]:
        model, scenario = case.model, case.scenario
        rod = answers.rod_of_case(case)
        lumped = answers.lumped_of(case)
        out: dict[str, Any] = {
            "n_elements": lumped.size - 1,
            "polar_moment_m4": rod.polar_moment,
            "wave_speed_m_s": rod.wave_speed,
            "travel_time_s": rod.travel_time,
            "torsional_stiffness_n_m_per_rad": rod.stiffness,
            "rod_inertia_kg_m2": rod.rod_inertia,
            "inertia_ratio": float(rod.mu),
        }
        omega, _ = answers.modes_of(case)
        count = min(answers.REPORTED_MODES, len(omega))
        exact_hz = omega[:count] / (2 * math.pi)
        continuum_hz = rod.frequencies(count) / (2 * math.pi)
        for k in range(count):
            out[f"mode_{k + 1}_frequency_hz_exact"] = float(exact_hz[k])
            out[f"mode_{k + 1}_frequency_hz_continuum"] = float(continuum_hz[k])
            out[f"mode_{k + 1}_discretization_error"] = float(abs(exact_hz[k] / continuum_hz[k] - 1))
        # the period of the model that runs (N elements) and, named as such, the rod's
        out["mode_1_period_s"] = float(1.0 / exact_hz[0])
        out["mode_1_period_s_continuum"] = float(1.0 / continuum_hz[0])
        top, bit = (case.joint_columns(trajectory)[j] for j in (TOP, BIT))
        if scenario.name == "modes":
            measured = answers.measured_frequency(trajectory.time, bit[0], bit[1])
            out["mode_1_frequency_hz"] = measured
            out["mode_1_integration_error"] = abs(measured / exact_hz[0] - 1) if math.isfinite(measured) else math.nan
            out["mode_1_error"] = abs(measured / continuum_hz[0] - 1) if math.isfinite(measured) else math.nan
            return out
        drive = self.drive(model, trajectory.dt)
        out["top_speed_rad_s"] = drive.speed
        out["spin_up_time_realized_s"] = drive.ramp_time
        twist = top[0] - bit[0]
        if scenario.name == "spin_up":
            out.update(answers.spin_up(rod, lumped, drive, trajectory, top, bit))
            return out
        out.update(answers.breakaway(rod, lumped, drive, trajectory, top, bit, twist))
        return out

    def checks(self, case: Case, trajectory: Trajectory) -> list[Check]:
        if case.scenario.name == "modes":
            omega, _ = answers.modes_of(case)
            bit = case.joint_columns(trajectory)[BIT]
            measured = answers.measured_frequency(trajectory.time, bit[0], bit[1])
            order = ORDERS[trajectory.integrator]
            constant = 1.0 / 120.0 if order == 4 else 0.5
            phase = omega[0] * trajectory.dt
            tolerance = 2 * constant * phase**order + 100 * np.finfo(float).eps * trajectory.steps
            return [
                Check(
                    "mode_1_frequency_hz",
                    measured,
                    float(omega[0] / (2 * math.pi)),
                    tolerance,
                    f"2 x the leading-order frequency error C (w1 dt)^p of {trajectory.integrator} (C = "
                    f"{'1/120' if order == 4 else '1/2'}, p = {order}) + 100 eps per step; the N-element model's f1"
                    " from its M and K",
                )
            ]
        if case.scenario.name != "breakaway":
            return []
        return _breakaway_checks(case, trajectory)


# -- checks ---------------------------------------------------------------------------------


def _breakaway_checks(case: Case, trajectory: Trajectory) -> list[Check]:
    """The breakaway time, the bit's peak speed and the re-stick time against the N-element model's exact ones.

    The run's own error is estimated by Richardson from a second run at dt/2 with order 1: MuJoCo's
    friction constraint is regularized over a time constant of 2 dt, a first-order effect whatever the
    integrator (taking order 1 over-estimates an error that falls faster).
    """
    lumped = answers.lumped_of(case)
    drive = answers.drive_of(case.model, trajectory.dt)
    half_dt = trajectory.dt / 2
    duration = float(trajectory.time[-1])
    finer = case.simulate(trajectory.integrator, half_dt, duration, keep=True)
    columns = [case.joint_columns(run) for run in (trajectory, finer)]
    coarse, fine = (
        answers.simulated_events(lumped, answers.drive_of(case.model, run.dt), run, cols[TOP], cols[BIT])
        for run, cols in zip((trajectory, finer), columns)
    )
    exact = answers.stick_slip(lumped, duration, drive)
    restick_exact = answers.restick_exact(lumped, exact, drive)
    basis = (
        "2 x the Richardson estimate from a run at dt/2 with order 1 (MuJoCo's friction constraint is"
        " regularized over 2 dt) + 100 eps per step; the exact value from the N-element model's stick-slip solution"
    )
    out = []
    for name, key, reference in (
        ("breakaway_time_s", "breakaway", exact.first("slip")),
        ("peak_bit_speed_rad_s", "peak", exact.peak_speed),
        ("restick_time_s", "restick", restick_exact),
    ):
        if not (math.isfinite(reference) and math.isfinite(coarse[key]) and math.isfinite(fine[key])):
            continue
        # the exact values are roots and maxima found to about 1e-13 s: their own error is round-off
        error = EVENT_ROOT_ERROR * (1.0 if name.endswith("time_s") else abs(reference))
        out.append(
            scene_checks.richardson_check(name, coarse[key], fine[key], 1, reference, error, trajectory.steps, basis)
        )
    return out


SCENE = DrillString()
