"""friction: a block under dry (Coulomb) friction, exact answers against MuJoCo's regularised friction.

    m x'' + k x = f_c - F sgn(x'),   at rest the block sticks while |f_c - k x| <= F

x [m] along the surface (positive down the slope), k the spring [N/m], f_c = m g sin(theta) the
slope's pull [N] and F [N] the bound of the friction force: the joint's `frictionloss` F, or the
contact's mu m g cos(theta). models/friction.xml holds the model; springlab.scenes.friction.coulomb
the exact piecewise motion; springlab.scenes.friction.measure what a run is read for.

Scenarios (each a `Variant`: which of MuJoCo's friction models, with or without the spring):

* `coulomb_decay`: joint dry friction (frictionloss F = 1 N) on a 100 N/m spring, released from
  0.105 m. Exact: half periods pi/omega about +-F/k, the amplitude falls by 2 F/k = 0.02 m per half
  cycle (linearly; the viscous slider's falls by a constant factor), and the block stops for good
  after 5 half cycles at 5 pi/omega = 1.5708 s, at x = -0.005 m.
* `contact_decay`: the same spring with a box on a plane instead, contact friction mu = 0.1
  (F = mu m g = 0.981 N): 5 half cycles, stop at x = -0.0069 m.
* `incline_hold`: no spring, a 20 degree incline, mu = 0.5 (tan 20 deg = 0.36 < mu): exactly no
  motion at all. MuJoCo's block creeps; the run measures how fast and how far.
* `incline_slide`: 30 degrees, mu = 0.3 (tan 30 deg = 0.58 > mu): exact uniform acceleration
  a = g (sin theta - mu cos theta) = 2.356 m/s^2 down the slope.

MuJoCo's settings are parameters (`solref_timeconst`, `solimp_d0`, `impratio`, `elliptic_cone`,
`noslip_iterations`), read back from the model, where MuJoCo's defaults are written out; each
scenario's preset is its validated setting, the cheapest the friction-settings study found to meet
1e-2 (docs/scenes/friction.md). `--set` any of them back to MuJoCo's default to see what it does.

How a run is judged. The exact motion has kinks (every turning point, the stop), so the smooth
error estimate of springlab.runs.compare (order p over the asymptotic range) does not hold across
them. A friction run is held to its measured error against the exact piecewise solution
(compared columns: position and velocity), at the certified cap 1e-2 or --tol, and to a measured
convergence: a second run at dt/2 must agree with it within the same tolerance (check
`dt_halving_change_relative`, 2 max |x(dt) - x(dt/2)| over the scale of x, velocity likewise: the
stick-slip events are resolved at this dt), and a decay must turn as often as the exact block
(check `half_cycles`). A block held at rest has no motion to be relative to: its errors are in
block lengths (position) and block lengths per run (velocity), so 1e-2 means "crept less than
1 % of its own length over the run".
"""

from __future__ import annotations

import copy
import dataclasses
import math
from collections.abc import Mapping
from typing import Any

import mujoco
import numpy as np

from springlab.errors import ParameterError
from springlab.scenes.base import (
    MIN_MASS,
    MIN_MASS_REASON,
    Case,
    Check,
    Parameter,
    PhaseField,
    Reference,
    Scenario,
    Scene,
)
from springlab.scenes.capabilities.friction import (
    CONTACT_FRICTION,
    JOINT_FRICTION,
    DryFrictionSpec,
    FrictionCase,
    FrictionMeasure,
    SolverSetting,
)
from springlab.sim.simulate import Setup, Trajectory

from . import measure
from .coulomb import CoulombMotion

#: the most relative error a PASS certifies without --tol (springlab.runs.compare.CERTIFIED_CAP, a layer above)
CERTIFIED = 1e-2
#: safety factor on the measured change between dt and dt/2 (exact for a first-order method:
#: its error at dt is twice the change)
SAFETY = 2.0
#: MuJoCo's bounds on an impedance (mjMINIMP, mjMAXIMP): it clamps solimp values to them
MIN_IMPEDANCE, MAX_IMPEDANCE = 1e-4, 0.9999
#: the block's joints: along the surface (reported), across it, along its normal
ALONG, ACROSS, NORMAL = "block", "lateral", "normal"


@dataclasses.dataclass(frozen=True)
class Variant:
    """What a scenario's model is (`Scenario.variant`).

    Attributes
    ----------
    friction
        JOINT_FRICTION (the joint's frictionloss, no contact) or CONTACT_FRICTION (a box on a plane).
    spring
        whether the spring acts (a decay) or the block is on the incline by itself.
    holds
        for a block by itself: whether the incline must be within the friction angle (a hold) or
        beyond it (a slide); None with the spring.
    """

    friction: str
    spring: bool
    holds: bool | None = None


JOINT_DECAY = Variant(JOINT_FRICTION, spring=True)
CONTACT_DECAY = Variant(CONTACT_FRICTION, spring=True)
HOLD = Variant(CONTACT_FRICTION, spring=False, holds=True)
SLIDE = Variant(CONTACT_FRICTION, spring=False, holds=False)

#: the settings that act only on contacts (MuJoCo's docs; tests/scenes/friction/test_friction_mujoco.py checks them)
CONTACT_ONLY = ("impratio", "elliptic_cone")
#: the friction-settings study's grid (docs/scenes/friction.md explains the choice of values)
SETTINGS = (
    SolverSetting(
        "solref_timeconst",
        (0.02, 0.01, 0.005, 0.002),
        0.02,
        (JOINT_FRICTION, CONTACT_FRICTION),
        "solref time constant [s]",
        floor_in_dt=2.0,
    ),
    SolverSetting("solimp_d0", (0.9, 0.99), 0.9, (JOINT_FRICTION, CONTACT_FRICTION), "solimp d0 [-]"),
    SolverSetting("impratio", (1.0, 10.0, 100.0), 1.0, (CONTACT_FRICTION,), "impratio [-]"),
    SolverSetting(
        "elliptic_cone",
        (0.0, 1.0),
        0.0,
        (CONTACT_FRICTION,),
        "friction cone",
        names={0.0: "pyramidal", 1.0: "elliptic"},
    ),
    SolverSetting("noslip_iterations", (0.0, 3.0), 0.0, (JOINT_FRICTION, CONTACT_FRICTION), "NoSlip iterations [-]"),
)
_DECAY_MEASURES = (
    FrictionMeasure("stop_position_m", "stop position (relative to the initial amplitude)", "amplitude_m"),
    FrictionMeasure("stop_time_s", "stop time (relative)"),
    FrictionMeasure(
        "final_position_m", "position at the end of the run (relative to the initial amplitude)", "amplitude_m"
    ),
    FrictionMeasure("creep_velocity_m_s", "creep velocity after the stop [m/s]", ""),
)
DRY_FRICTION = DryFrictionSpec(
    cases=(
        FrictionCase(
            "coulomb_decay",
            JOINT_FRICTION,
            "a spring-block with joint dry friction released from rest: when and where does it stop?",
            _DECAY_MEASURES,
        ),
        FrictionCase(
            "contact_decay",
            CONTACT_FRICTION,
            "the same with a box sliding on a plane (contact friction): when and where does it stop?",
            _DECAY_MEASURES,
        ),
        FrictionCase(
            "incline_hold",
            CONTACT_FRICTION,
            "a box on an incline below its friction angle: does it stay put?",
            (
                FrictionMeasure("creep_velocity_m_s", "creep velocity [m/s]", ""),
                FrictionMeasure("crept_distance_m", "distance crept over the run (in block lengths)", "block_length_m"),
            ),
        ),
        FrictionCase(
            "incline_slide",
            CONTACT_FRICTION,
            "a box on an incline above its friction angle: how fast does it accelerate?",
            (
                FrictionMeasure("acceleration_m_s2", "acceleration (relative)"),
                FrictionMeasure("distance_m", "distance slid (relative)"),
            ),
        ),
    ),
    settings=SETTINGS,
    dts=(2e-3, 1e-3, 5e-4, 2.5e-4),
    # implicit is implicitfast plus Coriolis terms, which slide joints do not have: its runs are implicitfast's
    # bit for bit (measured over the whole grid), so the study does not pay for them twice
    integrators=("euler", "implicitfast", "rk4", "discrete"),
)


def _no_spring(params: dict[str, float], explicit: set[str]) -> dict[str, float]:
    """Preset of the scenarios held by friction alone: the spring is off (set explicitly: bad input)."""
    if "stiffness" in explicit and params["stiffness"] != 0:
        raise ParameterError(
            "stiffness: this scenario holds or slides the block by friction alone; a spring on an"
            " incline is contact_decay with --set incline_deg=..."
        )
    return {"stiffness": 0.0}


#: the validated settings of the scenarios, with RK4 at the scenario's dt: the cheapest the friction-settings
#: study (springlab friction-settings friction --tol 1e-2, docs/scenes/friction.md) verified with both the
#: error and its dt-halving change within half the certified 1e-2 (a margin: the verdict must not hang on
#: the last digit). The slide needs a dt below the study's grid: 0.125 ms (its velocity chatters on the
#: contact, an integration error that falls only as dt)
_JOINT_VALIDATED = {"solref_timeconst": 0.002, "solimp_d0": 0.9, "noslip_iterations": 0.0}
_DECAY_VALIDATED = {
    "solref_timeconst": 0.002,
    "solimp_d0": 0.99,
    "impratio": 10.0,
    "elliptic_cone": 0.0,
    "noslip_iterations": 0.0,
}
_HOLD_VALIDATED = {
    "solref_timeconst": 0.01,
    "solimp_d0": 0.95,
    "impratio": 100.0,
    "elliptic_cone": 1.0,
    "noslip_iterations": 0.0,
}
_SLIDE_VALIDATED = {
    "solref_timeconst": 0.02,
    "solimp_d0": 0.9,
    "impratio": 100.0,
    "elliptic_cone": 0.0,
    "noslip_iterations": 0.0,
}


class Friction(Scene):
    name = "friction"
    title = "dry (Coulomb) friction with exact answers: decay to a stop, hold and slide on an incline"
    joints = (ALONG,)
    camera = "side"
    integrator = "rk4"
    dt = 1e-3
    default_scenario = "coulomb_decay"
    dry_friction = DRY_FRICTION
    questions = {
        "coulomb_decay": (
            "A block on a spring with dry friction F is released from rest: how does it come to a stop?",
            "Each half cycle lasts π/ω = {half_period_s:.4g} s and ends {amplitude_drop_per_half_cycle_m:.3g ~m} (2F/k)"
            " closer to the spring's rest: the amplitude falls linearly, not by a constant factor as under viscous"
            " damping. It stops for good after {half_cycles_exact} half cycles, at t = {stop_time_s_exact:.4g} s and"
            " x = {stop_position_m_exact:.4g ~m}, inside the stick zone ±F/k = ±{stick_zone_m:.3g ~m}."
            " MuJoCo: {half_cycles} half cycles, stop at {stop_time_s:.4g} s and x = {stop_position_m:.4g ~m}, then"
            " a creep of {creep_velocity_m_s:.3g ~m/s} (exact: {creep_velocity_m_s_exact:.3g ~m/s}).",
        ),
        "contact_decay": (
            "The same block slides on a plane with contact friction μ: how does it come to a stop?",
            "Friction is μ m g = {friction_force_N:.4g} N, so the amplitude falls by 2F/k ="
            " {amplitude_drop_per_half_cycle_m:.3g ~m} per half cycle; the block stops after {half_cycles_exact} half"
            " cycles at t = {stop_time_s_exact:.4g} s, x = {stop_position_m_exact:.4g ~m}. MuJoCo: {half_cycles}"
            " half cycles, stop at {stop_time_s:.4g} s and x = {stop_position_m:.4g ~m}, then a creep of"
            " {creep_velocity_m_s:.3g ~m/s} (exact: {creep_velocity_m_s_exact:.3g ~m/s}).",
        ),
        "incline_hold": (
            "Does friction hold a block on an incline below its friction angle?",
            "Yes: the incline ({incline_deg:.3g}°) is below the friction angle atan μ = {friction_angle_deg:.3g}°,"
            " so exactly nothing moves (exact creep {creep_velocity_m_s_exact:.3g ~m/s}). MuJoCo's block creeps at"
            " {creep_velocity_m_s:.3g ~m/s}: {crept_distance_m:.3g ~m} over the run (exact"
            " {crept_distance_m_exact:.3g ~m}).",
        ),
        "incline_slide": (
            "How fast does a block slide down an incline steeper than its friction angle?",
            "a = g (sin θ − μ cos θ) = {acceleration_m_s2_exact:.8g} m/s² from the start, {distance_m_exact:.7g ~m}"
            " down the slope by the run's end; MuJoCo's block accelerates at {acceleration_m_s2:.8g} m/s² and slides"
            " {distance_m:.7g ~m}.",
        ),
    }
    parameters = {
        p.name: p
        for p in (
            Parameter("mass", "kg", "mass of the block", minimum=MIN_MASS, reason=MIN_MASS_REASON),
            Parameter("stiffness", "N/m", "spring stiffness k (0: no spring)", minimum=0.0),
            Parameter(
                "friction_force",
                "N",
                "joint dry friction F: the bound of the friction force (frictionloss)",
                minimum=0.0,
            ),
            Parameter("mu", "-", "contact friction coefficient μ (F = μ m g cos θ)", minimum=0.0),
            Parameter("x0", "m", "initial position along the surface (the spring's stretch)", default=0.105),
            Parameter("v0", "m/s", "initial velocity along the surface", default=0.0),
            Parameter(
                "incline_deg",
                "deg",
                "incline of the surface; x runs down the slope",
                minimum=-90.0,
                maximum=90.0,
                reason="an incline beyond 90 degrees would put the block under the surface",
            ),
            Parameter(
                "solref_timeconst",
                "s",
                "time constant of MuJoCo's friction constraints: solreffriction[0] of the joint, solref[0] of the"
                " contacts (MuJoCo's default 0.02)",
                minimum=0.0,
                minimum_inclusive=False,
            ),
            Parameter(
                "solimp_d0",
                "-",
                "impedance d0 = solimp[0] of the friction constraints (MuJoCo's default 0.9)",
                minimum=MIN_IMPEDANCE,
                maximum=MAX_IMPEDANCE,
                reason="MuJoCo clamps an impedance to [mjMINIMP, mjMAXIMP] = [1e-4, 0.9999]",
            ),
            Parameter(
                "impratio",
                "-",
                "frictional-to-normal impedance ratio of contacts (option impratio; MuJoCo's default 1)",
                minimum=0.0,
                minimum_inclusive=False,
            ),
            Parameter(
                "elliptic_cone",
                "-",
                "contact friction cones: 1 elliptic, 0 pyramidal (MuJoCo's default)",
                minimum=0.0,
                maximum=1.0,
            ),
            Parameter(
                "noslip_iterations",
                "-",
                "iterations of MuJoCo's NoSlip pass after the solver (0: off, MuJoCo's default)",
                minimum=0.0,
                maximum=1000.0,
            ),
        )
    }
    scenarios = {
        s.name: s
        for s in (
            Scenario(
                "coulomb_decay",
                "joint dry friction (frictionloss) on a spring, released from rest: stops after 5 half cycles",
                3.0,
                {"incline_deg": 0.0, "x0": 0.105, "v0": 0.0, **_JOINT_VALIDATED},
                dt=1e-3,
                variant=JOINT_DECAY,
            ),
            Scenario(
                "contact_decay",
                "a box on a plane (contact friction mu = 0.1) on a spring, released from rest: stops after 5 half cycles",
                3.0,
                {"incline_deg": 0.0, "mu": 0.1, "x0": 0.105, "v0": 0.0, **_DECAY_VALIDATED},
                dt=2.5e-4,
                variant=CONTACT_DECAY,
            ),
            Scenario(
                "incline_hold",
                "a box on a 20 deg incline, mu = 0.5 (below the friction angle 26.6 deg): exactly no motion",
                2.0,
                {"incline_deg": 20.0, "mu": 0.5, "x0": 0.0, "v0": 0.0, **_HOLD_VALIDATED},
                derive=_no_spring,
                dt=2e-3,
                variant=HOLD,
            ),
            Scenario(
                "incline_slide",
                "a box on a 30 deg incline, mu = 0.3 (above the friction angle 16.7 deg): a = g (sin - mu cos)",
                0.5,
                {"incline_deg": 30.0, "mu": 0.3, "x0": 0.0, "v0": 0.0, **_SLIDE_VALIDATED},
                derive=_no_spring,
                dt=1.25e-4,
                variant=SLIDE,
            ),
        )
    }

    # -- parameters ------------------------------------------------------------------

    def model_defaults(self, model: mujoco.MjModel) -> dict[str, float]:
        joint = model.joint(ALONG)
        dof = int(joint.dofadr[0])
        surface = model.geom("surface")
        return {
            "mass": float(model.body("block").mass[0]),
            "stiffness": float(joint.stiffness[0]),
            "friction_force": float(model.dof_frictionloss[dof]),
            "mu": float(surface.friction[0]),
            "incline_deg": math.degrees(_incline(model)),
            "solref_timeconst": float(model.dof_solref[dof][0]),
            "solimp_d0": float(model.dof_solimp[dof][0]),
            "impratio": float(model.opt.impratio),
            "elliptic_cone": float(model.opt.cone == mujoco.mjtCone.mjCONE_ELLIPTIC),
            "noslip_iterations": float(model.opt.noslip_iterations),
        }

    def resolve(self, scenario: Scenario, overrides: Mapping[str, Any]) -> dict[str, float]:
        variant: Variant = scenario.variant
        # a setting that does not exist for this scenario's friction is a contradiction, not a no-op
        foreign = ("mu", *CONTACT_ONLY) if variant.friction == JOINT_FRICTION else ("friction_force",)
        given = [name for name in overrides if name in foreign]
        if given:
            raise ParameterError(_foreign_message(scenario, given[0]))
        return super().resolve(scenario, overrides)

    def check_consistency(self, params: dict[str, float], scenario: Scenario) -> None:
        for name in ("elliptic_cone", "noslip_iterations"):
            if params[name] != round(params[name]):
                raise ParameterError(
                    f"{name} must be a whole number ({self.parameters[name].valid_range()}), got {params[name]:g}"
                )
        variant: Variant = scenario.variant
        if variant.holds is None:
            return
        slope = abs(math.tan(math.radians(params["incline_deg"]))) if abs(params["incline_deg"]) < 90 else math.inf
        angle = math.degrees(math.atan(params["mu"]))
        other = next((s.name for s in self.scenarios.values() if s.variant.holds is (not variant.holds)), "")
        if variant.holds and slope > params["mu"]:
            raise ParameterError(
                f"{scenario.name} needs an incline within the friction angle, tan θ <= μ: |θ| <= atan {params['mu']:g}"
                f" = {angle:.3g}°, got {params['incline_deg']:g}° (use {other})"
            )
        if not variant.holds and slope <= params["mu"]:
            raise ParameterError(
                f"{scenario.name} needs an incline steeper than the friction angle, tan θ > μ: |θ| > {angle:.3g}°,"
                f" got {params['incline_deg']:g}° (use {other})"
            )

    # -- model -----------------------------------------------------------------------

    def edit(self, spec: mujoco.MjSpec, params: dict[str, float], scenario: Scenario) -> None:
        variant: Variant = scenario.variant
        theta = math.radians(params["incline_deg"])
        spec.frame("incline").quat = [math.cos(theta / 2), 0.0, math.sin(theta / 2), 0.0]
        spec.body("block").mass = params["mass"]
        joint = spec.joint(ALONG)
        joint.stiffness = [params["stiffness"], 0.0, 0.0]
        timeconst, d0 = params["solref_timeconst"], params["solimp_d0"]
        spec.option.noslip_iterations = int(params["noslip_iterations"])
        if params["stiffness"] == 0:
            spec.delete(spec.text("spring:spring"))  # no spring, none drawn
        if variant.friction == JOINT_FRICTION:
            joint.frictionloss = params["friction_force"]
            joint.solref_friction = [timeconst, 1.0]
            joint.solimp_friction = [d0, *list(joint.solimp_friction)[1:]]
            # frictionloss needs no normal force and no contact: the block keeps one degree of freedom
            spec.delete(spec.joint(ACROSS))
            spec.delete(spec.joint(NORMAL))
            spec.option.disableflags |= int(mujoco.mjtDisableBit.mjDSBL_CONTACT)
            return
        joint.frictionloss = 0.0
        for geom in (spec.geom("surface"), spec.geom("block")):
            geom.friction = [params["mu"], *list(geom.friction)[1:]]
            geom.solref = [timeconst, 1.0]
            geom.solimp = [d0, *list(geom.solimp)[1:]]
        spec.option.impratio = params["impratio"]
        spec.option.cone = (
            mujoco.mjtCone.mjCONE_ELLIPTIC if params["elliptic_cone"] else mujoco.mjtCone.mjCONE_PYRAMIDAL
        )

    def setup(self, case: Case, steps: int, dt: float) -> Setup:
        model, params = case.model, case.params
        qpos, qvel = np.zeros(model.nq), np.zeros(model.nv)
        along = model.joint(ALONG)
        qpos[along.qposadr[0]], qvel[along.dofadr[0]] = params["x0"], params["v0"]
        if model.njnt > 1:
            # kept per dt: a sweep runs every integrator at each dt of a case from the same rest
            qpos[model.joint(NORMAL).qposadr[0]] = case.memo(
                ("resting_height", float(dt)), lambda: _resting_height_at(model, qpos, qvel, dt)
            )
        return Setup(qpos=qpos, qvel=qvel)

    # -- physics read back from the compiled model --------------------------------------

    def physical(self, model: mujoco.MjModel) -> tuple[float, float, float, float]:
        """(mass m [kg], stiffness k [N/m], friction bound F [N], slope force f_c [N]) the block sees.

        F is the joint's frictionloss plus, where contacts act, mu m g cos(theta) (MuJoCo's mixing:
        the larger friction of the two geoms); f_c = m g sin(theta), g = |opt.gravity|.
        """
        joint = model.joint(ALONG)
        mass = float(model.body("block").mass[0])
        gravity = float(np.linalg.norm(model.opt.gravity))
        theta = _incline(model)
        friction = float(model.dof_frictionloss[joint.dofadr[0]])
        if contacts(model):
            mu = max(float(model.geom("surface").friction[0]), float(model.geom("block").friction[0]))
            friction += mu * mass * gravity * math.cos(theta)
        return mass, float(model.jnt_stiffness[joint.id]), friction, mass * gravity * math.sin(theta)

    def motion(self, case: Case, horizon: float) -> CoulombMotion:
        """The exact motion of this case's block (springlab.scenes.friction.coulomb), followed to `horizon` [s]."""
        m, k, friction, slope = case.physical()
        return CoulombMotion(m, k, friction, slope, case.params["x0"], case.params["v0"], horizon)

    def block_length(self, model: mujoco.MjModel) -> float:
        """The block's length along the surface [m] (the scale of a hold's creep)."""
        return 2.0 * float(model.geom("block").size[0])

    def modes(self, case: Case) -> list[tuple[float, float]]:
        m, k, _, _ = case.physical()
        return [(math.sqrt(k / m), 0.0)] if k > 0 else []

    # -- exact reference -------------------------------------------------------------

    def reference(self, case: Case, time: np.ndarray, *, dt: float) -> Reference:
        model = case.model
        x, v = self.motion(case, float(time[-1])).state(time)
        length = self.block_length(model)
        span = max(float(time[-1] - time[0]), dt)
        return Reference(
            pos={ALONG: x},
            vel={ALONG: v},
            tolerance=math.inf,
            tolerance_basis=(
                "dry friction: measured against the exact piecewise Coulomb solution, held to 1e-2 (the most a"
                " PASS certifies) or --tol; no smooth error estimate (its order p does not hold across stick-slip"
                " events), the convergence is measured instead by a run at dt/2 (check dt_halving_change_relative)"
            ),
            scales={f"{ALONG}_pos": length, f"{ALONG}_vel": length / span},
        )

    def checks(self, case: Case, trajectory: Trajectory) -> list[Check]:
        model, scenario = case.model, case.scenario
        x, v = case.joint_columns(trajectory)[ALONG]
        exact = self.motion(case, float(trajectory.time[-1]))
        half = case.simulate(trajectory.integrator, trajectory.dt / 2, float(trajectory.time[-1]), keep=True)
        xh, vh = case.joint_columns(half)[ALONG]
        n = min(len(x), (len(xh) + 1) // 2)
        ref_x, ref_v = exact.state(trajectory.time)
        length = self.block_length(model)
        span = max(float(trajectory.time[-1]), trajectory.dt)
        scale_x = float(np.max(np.abs(ref_x))) or length
        scale_v = float(np.max(np.abs(ref_v))) or length / span
        change = max(
            float(np.max(np.abs(x[:n] - xh[: 2 * n : 2]))) / scale_x,
            float(np.max(np.abs(v[:n] - vh[: 2 * n : 2]))) / scale_v,
        )
        out = [
            Check(
                "dt_halving_change_relative",
                SAFETY * change,
                0.0,
                CERTIFIED,
                "measured convergence: 2 max |x(dt) - x(dt/2)| (velocity likewise) over the scale of the compared"
                " columns must be within the run's tolerance: the stick-slip events are resolved at this dt",
                follows_tol=True,
            )
        ]
        if scenario.variant.spring:
            measured = len(measure.turning_points(trajectory.time, x, v))
            out.append(
                Check(
                    "half_cycles",
                    float(measured),
                    float(exact.half_cycles),
                    0.0,
                    "the block turns as often as the exact one (turning points: the velocity changes sign or stops)",
                    certifies_error=False,
                )
            )
        return out

    # -- results ---------------------------------------------------------------------

    def quantities(self, case: Case, trajectory: Trajectory) -> dict:
        model, params, scenario = case.model, case.params, case.scenario
        m, k, friction, slope = case.physical()
        time = trajectory.time
        x, v = case.joint_columns(trajectory)[ALONG]
        exact = self.motion(case, float(time[-1]))
        variant: Variant = scenario.variant
        out: dict = {"friction_force_N": friction, "slope_force_N": slope}
        if variant.friction == CONTACT_FRICTION:
            gravity = float(np.linalg.norm(model.opt.gravity))
            out["normal_force_N"] = m * gravity * math.cos(_incline(model))
            out["friction_angle_deg"] = math.degrees(math.atan(params["mu"]))
        if k > 0:
            omega = math.sqrt(k / m)
            out["omega_rad_s"] = omega
            out["half_period_s"] = math.pi / omega
            out["equilibrium_m"] = slope / k
            out["stick_zone_m"] = friction / k
            out["amplitude_drop_per_half_cycle_m"] = 2 * friction / k
            out["amplitude_m"] = abs(params["x0"] - slope / k) or abs(params["v0"]) / omega
        turning = measure.turning_points(time, x, v)
        if variant.spring:
            stop_t, stop_x = turning[-1] if turning else (math.nan, math.nan)
            out["half_cycles"] = len(turning)
            out["half_cycles_exact"] = exact.half_cycles
            out["turning_points_m"] = [p[1] for p in turning]
            out["turning_points_m_exact"] = exact.turning_points
            out["stop_time_s"] = stop_t
            out["stop_time_s_exact"] = exact.stop_time
            out["stop_position_m"] = stop_x
            out["stop_position_m_exact"] = exact.stop_position
            out["final_position_m"] = float(x[-1])
            out["final_position_m_exact"] = (
                exact.stop_position if exact.stop_time <= time[-1] else float(exact.state(time[-1:])[0][0])
            )
            out["creep_velocity_m_s"] = measure.creep_velocity(time, x, stop_t) if turning else math.nan
            out["creep_velocity_m_s_exact"] = 0.0
            return out
        out["block_length_m"] = self.block_length(model)
        exact_x, _ = exact.state(time)
        end = float(time[-1])
        if variant.holds:
            # once the exact block rests (at once, from rest), MuJoCo's creeps: measured over the second half
            settled = max(exact.stop_time, end / 2) if exact.stops else math.inf
            out["holding_margin"] = friction / abs(slope) if slope else math.inf
            out["creep_velocity_m_s"] = measure.creep_velocity(time, x, settled) if settled < end else math.nan
            out["creep_velocity_m_s_exact"] = 0.0
            out["crept_distance_m"] = float(x[-1] - exact_x[-1])
            out["crept_distance_m_exact"] = 0.0
            return out
        # the slide's acceleration over its last piece (the whole run from rest)
        last = exact.segments[-1]
        window = time >= last.start
        out["acceleration_m_s2"] = measure.acceleration(time[window], v[window])
        out["acceleration_m_s2_exact"] = float(last.force / m)
        out["distance_m"] = float(x[-1] - x[0])
        out["distance_m_exact"] = float(exact_x[-1] - exact_x[0])
        return out

    # -- phase plane ------------------------------------------------------------------

    def phase_field(self, case: Case) -> PhaseField | None:
        m, k, friction, slope = case.physical()

        def field(x: np.ndarray, v: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
            x, v = np.asarray(x, float), np.asarray(v, float)
            net = slope - k * x
            # at rest friction takes up to F of the net force; moving, it is F against the motion
            at_rest = np.where(np.abs(net) <= friction, 0.0, net - friction * np.sign(net))
            return v + 0.0 * x, np.where(v == 0, at_rest, net - friction * np.sign(v)) / m

        return field

    def equilibria(self, case: Case) -> list[dict]:
        """The stick zone |x - f_c/k| <= F/k: every point of it an equilibrium, given as its two ends with
        "to" naming the other (k = 0: none, or everywhere)."""
        m, k, friction, slope = case.physical()
        if k <= 0:
            return []
        low, high = (slope - friction) / k, (slope + friction) / k
        return [{"x": low, "stable": True, "to": high}, {"x": high, "stable": True, "to": low}]


def _incline(model: mujoco.MjModel) -> float:
    """The surface's incline theta [rad]: the turn of the frame holding the block about y."""
    w, _, y, _ = (float(c) for c in model.body("block").quat)
    return 2.0 * math.atan2(y, w)


def contacts(model: mujoco.MjModel) -> bool:
    """Whether the model's contacts act (the joint-friction variant disables them)."""
    return not model.opt.disableflags & int(mujoco.mjtDisableBit.mjDSBL_CONTACT)


def _resting_height_at(model: mujoco.MjModel, qpos: np.ndarray, qvel: np.ndarray, dt: float) -> float:
    """`resting_height` of a copy of `model` at timestep `dt` [s]: MuJoCo raises a solref time constant below
    2 dt to 2 dt (refsafe), so the rest depends on the run's own dt."""
    at_dt = copy.copy(model)
    at_dt.opt.timestep = dt
    return resting_height(at_dt, qpos, qvel)


def resting_height(model: mujoco.MjModel, qpos: np.ndarray, qvel: np.ndarray) -> float:
    """The normal coordinate [m] at which MuJoCo's soft contact carries the block at rest: the root of its
    normal acceleration (brentq on mj_forward, the other coordinates at `qpos`, the velocity `qvel`),
    or 0 (touching) where there is none below it.

    Starting there, the run has no settling transient of the normal contact that the exact motion
    (a rigid surface) does not have.
    """
    from scipy import optimize  # here: the command line starts without scipy (tests/cli/test_cli_usage.py)

    data = mujoco.MjData(model)
    adr, dof = model.joint(NORMAL).qposadr[0], model.joint(NORMAL).dofadr[0]

    def normal_acceleration(z: float) -> float:
        data.qpos[:], data.qvel[:] = qpos, qvel
        data.qpos[adr] = z
        mujoco.mj_forward(model, data)
        return float(data.qacc[dof])

    high = 0.0  # touching
    if normal_acceleration(high) >= 0:
        # at rest the soft friction cone already pushes the block off the surface (an elliptic cone whose
        # friction must carry more than mu times the weight): start touching it, no root below
        return high
    low = -1e-4
    while normal_acceleration(low) < 0:
        low *= 2.0
        if low < -1.0:
            raise ParameterError(
                "the contact cannot carry the block within 1 m of penetration: a softer solref than any block can rest on"
            )
    return float(optimize.brentq(normal_acceleration, low, high, xtol=1e-15, rtol=4 * np.finfo(float).eps))


def _foreign_message(scenario: Scenario, name: str) -> str:
    """Why `name` cannot be set in `scenario`: it belongs to the other friction model."""
    if name == "friction_force":
        return (
            f"friction_force: {scenario.name}'s friction is contact friction, F = mu m g cos(theta); set mu"
            " (friction_force is the joint dry friction of coulomb_decay)"
        )
    if name == "mu":
        return f"mu: {scenario.name}'s friction is the joint's dry friction (frictionloss); set friction_force"
    return (
        f"{name}: acts on contacts only (MuJoCo's impratio and friction cones), and {scenario.name}'s friction"
        " is the joint's frictionloss; use contact_decay, incline_hold or incline_slide"
    )


SCENE = Friction()
