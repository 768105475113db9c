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

Sources for the realistic defaults: Gillespie, Fundamentals of Vehicle
Dynamics (SAE, 1992), ch. 5 "Ride": passenger cars have suspension damping
ratios of about 0.2-0.4 (default 0.3) and body bounce frequencies of about
1-1.5 Hz (road_bump's comfort suspension: 1.2 Hz). The textbook's
k = 1e6 N/m puts its car at 5 Hz, stiffer than a tire, which is why road_bump
presets the softer springs.
"""

from __future__ import annotations

import functools
import math

import mujoco
import numpy as np

from .. import analytic
from ..errors import ParameterError
from ..scene import Parameter, Reference, Scenario, Scene, Setup
from ..simulate import Trajectory, quiet_mujoco

#: pitch_heave: share of the springs' stiffness at the front axle [-]. Below the
#: front's share of the load (b / (a + b) = 0.56), so the front rides softer
#: than the rear, as most cars do (Olley's flat-ride rule); this couples heave
#: and pitch (kf a != kr b).
FRONT_STIFFNESS_SHARE = 0.45
#: road_bump: the four springs of a comfort-tuned 1000 kg car [N/m]: body bounce
#: sqrt(k / m) / 2 pi = 1.23 Hz (Gillespie: 1-1.5 Hz for passenger cars)
COMFORT_STIFFNESS = 6.0e4
#: exciter spring stiffness relative to the largest force it carries per metre of bump
EXCITER_STIFFNESS_RATIO = 1e12

_ONE_DOF = ("push_release", "damped_release")


def _damping_from_ratio(params: dict[str, float], explicit: set[str]) -> dict[str, float]:
    """damping [N s/m] = 2 zeta sqrt(k m), unless damping itself was given (then zeta follows)."""
    if "damping" in explicit and "damping_ratio" in explicit:
        raise ParameterError("set either damping [N s/m] or damping_ratio [-], not both")
    k, m = params["stiffness"], params["mass"]
    if "damping" in explicit:
        return {"damping_ratio": params["damping"] / (2.0 * math.sqrt(k * m))}
    return {"damping": 2.0 * params["damping_ratio"] * math.sqrt(k * m)}


def _pitch_heave_defaults(params: dict[str, float], explicit: set[str]) -> dict[str, float]:
    """Axle springs split from the textbook's four springs; axle dampers at damping_ratio
    of each axle's static load; the push over the front axle."""
    for axle in ("front", "rear"):
        if f"{axle}_damping" in explicit and "damping_ratio" in explicit:
            raise ParameterError(f"set either {axle}_damping [N s/m] or damping_ratio [-], not both")
    a, b, m = params["front_axle_distance"], params["rear_axle_distance"], params["mass"]
    out = {
        "front_stiffness": FRONT_STIFFNESS_SHARE * params["stiffness"],
        "rear_stiffness": (1.0 - FRONT_STIFFNESS_SHARE) * params["stiffness"],
        "push_position": a,
    }
    out.update({k: params[k] for k in ("front_stiffness", "rear_stiffness") if k in explicit})
    zeta = params["damping_ratio"]
    out["front_damping"] = 2.0 * zeta * math.sqrt(out["front_stiffness"] * m * b / (a + b))
    out["rear_damping"] = 2.0 * zeta * math.sqrt(out["rear_stiffness"] * m * a / (a + b))
    return out


#: the parameters each scenario uses, in the order summaries list them
RELEVANT = {
    "push_release": ("mass", "stiffness", "damping", "clearance", "push_mass"),
    "damped_release": ("mass", "stiffness", "damping", "damping_ratio", "clearance", "push_mass"),
    "pitch_heave": (
        "mass",
        "pitch_inertia",
        "front_axle_distance",
        "rear_axle_distance",
        "front_stiffness",
        "rear_stiffness",
        "front_damping",
        "rear_damping",
        "damping_ratio",
        "clearance",
        "push_mass",
        "push_position",
    ),
    "road_bump": (
        "mass",
        "stiffness",
        "damping",
        "damping_ratio",
        "clearance",
        "unsprung_mass",
        "tire_stiffness",
        "bump_height",
        "bump_length",
        "speed",
    ),
}


class Car(Scene):
    name = "car"
    title = "car body on its suspension: sag, push-and-release, damping, pitch/heave, road bump"
    joints = ("heave", "pitch", "wheel")
    camera = "side"
    # RK4 throughout. Each scenario's dt is the largest of 1, 2, 2.5, 4, 5, 10 ms
    # whose predicted error bound (springlab.compare) is <= 1e-6 relative, as for
    # the slider; road_bump's 0.5 s bump is a whole number of those steps.
    integrator = "rk4"
    dt = 1e-3
    default_scenario = "push_release"
    parameters = {
        p.name: p
        for p in (
            Parameter(
                "mass",
                "kg",
                "sprung mass: car + passengers, everything the springs carry (road_bump: mass/4 per corner)",
                minimum=0.0,
                minimum_inclusive=False,
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
                minimum=0.0,
                minimum_inclusive=False,
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
                minimum=0.0,
                minimum_inclusive=False,
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
    scenarios = {
        s.name: s
        for s in (
            Scenario(
                "push_release",
                "the textbook problem: pushed down by 250 kg of passers-by, released, no damping",
                1.0,
                {"damping": 0.0},
                dt=1e-3,
            ),
            Scenario(
                "damped_release",
                "the same release with dampers at damping_ratio (default 0.3)",
                1.0,
                derive=_damping_from_ratio,
                dt=2e-3,
            ),
            Scenario(
                "pitch_heave",
                "2 DOF: front/rear axle springs and dampers, pushed down over the front axle and released",
                2.0,
                derive=_pitch_heave_defaults,
                dt=2e-3,
            ),
            Scenario(
                "road_bump",
                "quarter car over a half-sine bump (0.08 m high, 4 m long) at 8 m/s",
                3.0,
                {"stiffness": COMFORT_STIFFNESS},
                derive=_damping_from_ratio,
                dt=1e-3,
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
            return _gravity(self.model_spec().compile())

    def resolve(self, scenario: Scenario, overrides) -> dict[str, float]:
        """Only the parameters the scenario uses; setting one it does not use is an error."""
        values = super().resolve(scenario, overrides)
        relevant = RELEVANT[scenario.name]
        for name in overrides:
            if name not in relevant:
                raise ParameterError(
                    f"{name} does not apply to car {scenario.name}; its parameters: {', '.join(relevant)}"
                )
        return {name: values[name] for name in relevant}

    def check_consistency(self, params: dict[str, float], scenario: Scenario) -> None:
        if scenario.name not in _ONE_DOF:
            return  # 2-DOF checks need the exact motion: see setup()
        g = self.gravity()
        m, k, d, clearance, push = (params[n] for n in ("mass", "stiffness", "damping", "clearance", "push_mass"))
        sag = push * g / k
        if sag >= clearance:
            raise ParameterError(
                f"push_mass = {push:g} kg pushes the car bottom {sag:.4g} m down, through the ground"
                f" (clearance {clearance:g} m); valid: push_mass < {k * clearance / g:.6g} kg"
            )
        # highest point after release: x_s + sag (undamped), less the first overshoot's decay (damped)
        zeta = d / (2.0 * math.sqrt(k * m))
        overshoot = math.exp(-math.pi * zeta / math.sqrt(1.0 - zeta * zeta)) if zeta < 1.0 else 0.0
        if sag * overshoot > m * g / k:
            raise ParameterError(
                f"push_mass = {push:g} kg makes the car rebound {sag * overshoot:.4g} m above its rest height,"
                f" off its springs (they are compressed only {m * g / k:.4g} m by its weight);"
                f" valid: push_mass <= {m / overshoot:.6g} kg"
            )

    # -- model ---------------------------------------------------------------

    def joint_columns(self, model, trajectory):
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
        if scenario.name in _ONE_DOF:
            m, k = params["mass"], params["stiffness"]
            heave.stiffness = [k, 0.0, 0.0]
            heave.damping = [params["damping"], 0.0, 0.0]
            heave.springref = clearance + m * g / k  # static equilibrium at the clearance
        elif scenario.name == "pitch_heave":
            self._edit_pitch_heave(spec, params, g)
        else:
            self._edit_quarter_car(spec, params, g)

    @staticmethod
    def _edit_pitch_heave(spec: mujoco.MjSpec, params: dict[str, float], g: float) -> None:
        """The pitch hinge through the CoM and the axle springs as fixed tendons (module docstring)."""
        car, heave = spec.body("car"), spec.joint("heave")
        m, a, b = params["mass"], params["front_axle_distance"], params["rear_axle_distance"]
        heave.stiffness = [0.0, 0.0, 0.0]  # the springs are the axle tendons now
        heave.damping = [0.0, 0.0, 0.0]
        inertia = list(car.inertia)
        car.inertia = [inertia[0], params["pitch_inertia"], inertia[2]]
        com = list(car.ipos)
        car.add_joint(name="pitch", type=mujoco.mjtJoint.mjJNT_HINGE, axis=[0.0, 1.0, 0.0], pos=com)
        # the picture follows the parameters: axle sites, hubs and wheels at a and b
        for site, wheel_site, x in (("front_axle", "hub_front", com[0] + a), ("rear_axle", "hub_rear", com[0] - b)):
            spec.site(site).pos = [x, *list(spec.site(site).pos)[1:]]
            spec.site(wheel_site).pos = [x, *list(spec.site(wheel_site).pos)[1:]]
        for side in ("left", "right"):
            for axle, x in (("front", com[0] + a), ("rear", com[0] - b)):
                geom = spec.geom(f"wheel_{axle}_{side}")
                geom.pos = [x, *list(geom.pos)[1:]]
        clearance, length = params["clearance"], a + b
        for axle, k, c, coef, load in (
            ("front", params["front_stiffness"], params["front_damping"], -a, m * g * b / length),
            ("rear", params["rear_stiffness"], params["rear_damping"], b, m * g * a / length),
        ):
            # length = heave + coef * pitch = clearance at rest; preload = the axle's static load
            rest = clearance + load / k
            tendon = spec.add_tendon(
                name=f"{axle}_suspension", stiffness=[k, 0.0, 0.0], damping=[c, 0.0, 0.0], springlength=[rest, rest]
            )
            tendon.wrap_joint("heave", 1.0)
            tendon.wrap_joint("pitch", coef)

    @staticmethod
    def _edit_quarter_car(spec: mujoco.MjSpec, params: dict[str, float], g: float) -> None:
        """One corner: sprung mass, suspension tendon, wheel, tire springs gated onto the bump exciter."""
        car, heave = spec.body("car"), spec.joint("heave")
        ms, ks, cs = params["mass"] / 4.0, params["stiffness"] / 4.0, params["damping"] / 4.0
        mu, kt = params["unsprung_mass"], params["tire_stiffness"]
        car.mass = ms
        car.inertia = [i / 4.0 for i in car.inertia]  # no rotation here; kept in proportion
        heave.stiffness = [0.0, 0.0, 0.0]
        heave.damping = [0.0, 0.0, 0.0]
        radius = float(spec.geom("wheel_front_left").size[0])  # unloaded tire radius [m]
        wheel_rest = radius - (ms + mu) * g / kt  # wheel-centre height under the static load
        wheels = spec.body("wheels")
        wheels.pos = [0.0, 0.0, wheel_rest]
        wheels.mass = mu
        wheels.add_joint(name="wheel", type=mujoco.mjtJoint.mjJNT_SLIDE, axis=[0.0, 0.0, 1.0], ref=wheel_rest)
        rest = params["clearance"] - wheel_rest + ms * g / ks  # spring carries the sprung weight at rest
        suspension = spec.add_tendon(
            name="suspension", stiffness=[ks, 0.0, 0.0], damping=[cs, 0.0, 0.0], springlength=[rest, rest]
        )
        suspension.wrap_joint("heave", 1.0)
        suspension.wrap_joint("wheel", -1.0)
        # the bump generator: road height under the tire = exciter coordinate (horizontal axis: no gravity)
        height, omega = params["bump_height"], math.pi * params["speed"] / params["bump_length"]
        exciter_stiffness = EXCITER_STIFFNESS_RATIO * kt * (radius + height) / height
        exciter = spec.worldbody.add_body(name="road", pos=[0.0, 0.0, -1.0])
        exciter.mass = exciter_stiffness / omega**2
        exciter.inertia = [1.0, 1.0, 1.0]
        exciter.explicitinertial = True
        exciter.add_joint(
            name="road", type=mujoco.mjtJoint.mjJNT_SLIDE, axis=[1.0, 0.0, 0.0], stiffness=[exciter_stiffness, 0.0, 0.0]
        )
        contact = spec.add_tendon(name="bump_contact")
        contact.wrap_joint("road", 1.0)
        contact.wrap_joint("wheel", -1.0)
        affine = mujoco.mjtGain.mjGAIN_AFFINE
        # force = (gain0 + gain1 * length) * ctrl: a tire spring of rest length `radius`, switched by ctrl
        spec.add_actuator(
            name="tire_on_bump",
            trntype=mujoco.mjtTrn.mjTRN_TENDON,
            target="bump_contact",
            gaintype=affine,
            gainprm=[-kt * radius, -kt, 0.0] + [0.0] * 7,
            ctrllimited=0,
        )
        spec.add_actuator(
            name="tire_on_road",
            trntype=mujoco.mjtTrn.mjTRN_JOINT,
            target="wheel",
            gaintype=affine,
            gainprm=[kt * radius, -kt, 0.0] + [0.0] * 7,
            ctrllimited=0,
        )

    def setup(self, model, params, scenario, steps, dt) -> Setup:
        qpos = model.qpos0.copy()  # the static equilibrium (clearance; wheel at its loaded height)
        qvel = np.zeros(model.nv)
        heave = model.joint("heave").qposadr[0]
        control = None
        if scenario.name in _ONE_DOF:
            m, k, d, springref, g = _one_dof(model)
            qpos[heave] = springref - (m + params["push_mass"]) * g / k  # pushed down by the passers-by
        elif scenario.name == "pitch_heave":
            linear = _Linear2Dof(model)
            q0 = linear.equilibrium + np.linalg.solve(linear.stiffness, _push_force(model, params))
            qpos[heave], qpos[model.joint("pitch").qposadr[0]] = q0
        else:
            quarter = _QuarterCar(model, params)
            qvel[model.joint("road").dofadr[0]] = quarter.height * quarter.omega
            switch_step = quarter.switch_step(dt)
            control = np.zeros((steps, 2))
            control[:switch_step, 0] = 1.0  # tire on the bump exciter
            control[switch_step:, 1] = 1.0  # tire on the flat road
        if scenario.name in ("pitch_heave", "road_bump"):
            self._check_motion(model, params, scenario, np.arange(steps + 1) * dt, dt)
        return Setup(qpos=qpos, qvel=qvel, control=control)

    def _check_motion(self, model, params, scenario, time: np.ndarray, dt: float) -> None:
        """ParameterError if the exact motion lifts the car off its springs or puts its bottom below ground."""
        reference = self.reference(model, params, scenario, time, dt=dt)
        if scenario.name == "pitch_heave":
            linear = _Linear2Dof(model)
            x, theta = reference.pos["heave"], reference.pos["pitch"]
            what = f"push_mass = {params['push_mass']:g} kg at push_position = {params['push_position']:g} m"
            stations = {"front axle": linear.a, "rear axle": -linear.b, "push position": params["push_position"]}
            springs = {
                "front": _axle_force(linear, 0, x, theta, reference.vel),
                "rear": _axle_force(linear, 1, x, theta, reference.vel),
            }
            fix = "use a smaller push_mass"
        else:
            quarter = _QuarterCar(model, params)
            what = f"bump_height = {params['bump_height']:g} m at speed = {params['speed']:g} m/s"
            stations = {"body": None}
            x = reference.pos["heave"]
            springs = {
                "suspension": quarter.suspension_force(
                    x, reference.pos["wheel"], reference.vel["heave"], reference.vel["wheel"]
                )
            }
            fix = "use a lower bump or another speed"
        for where, station in stations.items():
            bottom = x if station is None else x - station * theta
            if bottom.min() < 0.0:
                i = int(np.argmin(bottom))
                raise ParameterError(
                    f"{what} drives the car bottom ({where}) through the ground (height"
                    f" {bottom[i]:.4g} m at t = {time[i]:.4g} s); {fix}"
                )
        for axle, force in springs.items():
            if force.min() < 0.0:
                i = int(np.argmin(force))
                raise ParameterError(
                    f"{what} lifts the car off its {axle} springs (springs and dampers would"
                    f" have to pull {-force[i]:.4g} N at t = {time[i]:.4g} s); {fix}"
                )

    # -- exact references -----------------------------------------------------

    def reference(self, model, params, scenario, time, *, dt) -> Reference:
        if scenario.name in _ONE_DOF:
            return self._one_dof_reference(model, params, time)
        if scenario.name == "pitch_heave":
            return self._pitch_heave_reference(model, params, time)
        return self._road_bump_reference(model, params, time, dt)

    @staticmethod
    def _one_dof_reference(model, params, time) -> Reference:
        m, k, d, springref, g = _one_dof(model)
        rest = springref - m * g / k
        x0 = springref - (m + params["push_mass"]) * g / k
        x, v = analytic.free_response(time, m, k, d, x0 - rest, 0.0)
        # z = (x, v, 1): the spring's preload and gravity as a constant generator state
        system = np.array([[0.0, 1.0, 0.0], [-k / m, -d / m, k * rest / m], [0.0, 0.0, 0.0]])
        states = np.column_stack([x + rest, v, np.ones_like(time)])
        return Reference(
            pos={"heave": x + rest}, vel={"heave": v}, system=system, states=states, rows={"heave": (0, 1)}
        )

    @staticmethod
    def _pitch_heave_reference(model, params, time) -> Reference:
        linear = _Linear2Dof(model)
        q0 = linear.equilibrium + np.linalg.solve(linear.stiffness, _push_force(model, params))
        q, v = analytic.linear_response(
            time, linear.mass, linear.damping, linear.stiffness, q0, np.zeros(2), force=linear.preload
        )
        a = analytic.state_matrix(linear.mass, linear.damping, linear.stiffness)
        system = np.zeros((5, 5))
        system[:4, :4] = a
        system[2:4, 4] = np.linalg.solve(linear.mass, linear.preload)
        states = np.column_stack([q, v, np.ones_like(time)])
        return Reference(
            pos={"heave": q[:, 0], "pitch": q[:, 1]},
            vel={"heave": v[:, 0], "pitch": v[:, 1]},
            system=system,
            states=states,
            rows={"heave": (0, 2), "pitch": (1, 3)},
        )

    @staticmethod
    def _road_bump_reference(model, params, time, dt: float) -> Reference:
        quarter = _QuarterCar(model, params)
        z0 = quarter.initial_state()
        true = _piecewise_lti(time, z0, [(0.0, quarter.on_bump), (quarter.bump_time, quarter.on_road)])
        switch = quarter.switch_step(dt) * dt
        realized = _piecewise_lti(time, z0, [(0.0, quarter.on_bump), (switch, quarter.on_road)])
        rows = {"heave": (0, 2), "wheel": (1, 3)}
        input_error = {}
        for joint, (ip, iv) in rows.items():
            input_error[f"{joint}_pos"] = float(np.max(np.abs(realized[:, ip] - true[:, ip])))
            input_error[f"{joint}_vel"] = float(np.max(np.abs(realized[:, iv] - true[:, iv])))
        basis = (
            f"+ the exact effect of ending the bump on the step grid at {switch:.6g} s instead of"
            f" {quarter.bump_time:.6g} s"
            if switch != quarter.bump_time
            else ""
        )
        return Reference(
            pos={"heave": true[:, 0], "wheel": true[:, 1]},
            vel={"heave": true[:, 2], "wheel": true[:, 3]},
            system=quarter.on_bump,
            states=true,
            rows=rows,
            switches=[(switch, quarter.on_road)],
            input_error=input_error,
            tolerance_basis=basis,
        )

    # -- modes and phase plane -------------------------------------------------

    def modes(self, model, params, scenario) -> list[tuple[float, float]]:
        if scenario.name in _ONE_DOF:
            m, k, d, _, _ = _one_dof(model)
            return [(math.sqrt(k / m), analytic.damping_ratio(m, k, d))]
        if scenario.name == "pitch_heave":
            linear = _Linear2Dof(model)
            return _damped_modes(analytic.state_matrix(linear.mass, linear.damping, linear.stiffness))
        quarter = _QuarterCar(model, params)
        return _damped_modes(quarter.on_road[:4, :4]) + [(quarter.omega, 0.0)]

    def phase_field(self, model, params, scenario):
        if scenario.name not in _ONE_DOF:
            return None
        m, k, d, springref, g = _one_dof(model)
        rest = springref - m * g / k
        return lambda x, v: (v, -(k * (x - rest) + d * v) / m)

    def equilibria(self, model, params, scenario) -> list[dict]:
        if scenario.name not in _ONE_DOF:
            return []
        m, k, d, springref, g = _one_dof(model)
        return [{"x": springref - m * g / k, "stable": True}]

    # -- results -------------------------------------------------------------

    def quantities(self, model, params, scenario, trajectory: Trajectory) -> dict:
        if scenario.name in _ONE_DOF:
            return self._release_quantities(model, params, scenario, trajectory)
        if scenario.name == "pitch_heave":
            return self._pitch_heave_quantities(model, params, trajectory)
        return self._road_bump_quantities(model, params, trajectory)

    @staticmethod
    def _release_quantities(model, params, scenario, trajectory) -> dict:
        m, k, d, springref, g = _one_dof(model)
        rest = springref - m * g / k
        sag = params["push_mass"] * g / k
        omega = math.sqrt(k / m)
        heave = model.joint("heave")
        x = trajectory.qpos[:, heave.qposadr[0]]
        v = trajectory.qvel[:, heave.dofadr[0]]
        out: dict = {
            "static_sag_m": sag,
            "height_before_release_m": rest - sag,
            "equilibrium_height_m": rest,
            "amplitude_m": -sag,
            "omega_rad_s": omega,
            "period_s": 2 * math.pi / omega,
            "sag_under_own_weight_m": m * g / k,
        }
        if d == 0.0:
            # the phase plane (x, v): an ellipse centred at (x_s, 0), semi-axes |A| and omega |A|
            out["phase_ellipse_height_semi_axis_m"] = sag
            out["phase_ellipse_velocity_semi_axis_m_s"] = omega * sag
        out["max_height_m"] = float(np.max(x))
        out["max_speed_m_s"] = float(np.max(np.abs(v)))
        if scenario.name == "damped_release" or d > 0.0:
            zeta = analytic.damping_ratio(m, k, d)
            out["damping_ratio"] = zeta
            out["regime"] = analytic.regime(m, k, d)
            if 0.0 < zeta < 1.0:
                omega_d = analytic.damped_frequency(m, k, d)
                out["omega_d_rad_s"] = omega_d
                out["damped_period_s"] = 2 * math.pi / omega_d
                out["logarithmic_decrement"] = 2 * math.pi * zeta / math.sqrt(1 - zeta * zeta)
                peaks = _peaks(trajectory.time, x - rest, v, trajectory.dt)
                # well above the integration error; successive same-sign extrema are one damped period apart
                peaks = peaks[np.abs(peaks[:, 1]) > 1e-3 * np.max(np.abs(peaks[:, 1]), initial=0.0)]
                if len(peaks) >= 3:
                    out["logarithmic_decrement_measured"] = float(np.mean(np.log(peaks[:-2, 1] / peaks[2:, 1])))
                    out["measured_extrema"] = int(len(peaks))
            if zeta > 0:
                out["decay_time_constant_s"] = 1.0 / (zeta * omega)
        return out

    @staticmethod
    def _pitch_heave_quantities(model, params, trajectory) -> dict:
        linear = _Linear2Dof(model)
        measured = linearize(model, linear.equilibrium)
        analytic_modes = _undamped_modes(linear.mass, linear.stiffness)
        mujoco_modes = _undamped_modes(measured["M"], measured["K"])
        q0 = linear.equilibrium + np.linalg.solve(linear.stiffness, _push_force(model, params))
        out: dict = {
            "initial_heave_offset_m": float(q0[0] - linear.equilibrium[0]),
            "initial_pitch_rad": float(q0[1]),
        }
        for i, (omega, shape) in enumerate(mujoco_modes, start=1):
            out[f"omega_{i}_rad_s"] = omega
            out[f"frequency_{i}_hz"] = omega / (2 * math.pi)
            if abs(shape[0]) > 1e-12:
                out[f"mode_{i}_pitch_per_heave_rad_m"] = shape[1] / shape[0]
            if abs(shape[1]) > 1e-12:
                # the station (ahead of the centre of mass) that stays still in this mode: x - s theta = 0
                out[f"mode_{i}_node_m"] = shape[0] / shape[1]
        for i, (omega, _) in enumerate(analytic_modes, start=1):
            out[f"omega_{i}_analytic_rad_s"] = omega
        damped = _damped_modes(analytic.state_matrix(measured["M"], measured["C"], measured["K"]))
        for i, (omega, zeta) in enumerate(damped, start=1):
            out[f"mode_{i}_damping_ratio"] = zeta
            out[f"omega_d_{i}_rad_s"] = omega * math.sqrt(max(1 - zeta * zeta, 0.0))
        exact = {"M": linear.mass, "C": linear.damping, "K": linear.stiffness}
        out["linearization_max_rel_diff"] = max(
            float(np.max(np.abs(measured[n] - exact[n])) / np.max(np.abs(exact[n])))
            for n in exact
            if np.max(np.abs(exact[n])) > 0
        )
        heave, pitch = model.joint("heave"), model.joint("pitch")
        out["max_heave_deviation_m"] = float(
            np.max(np.abs(trajectory.qpos[:, heave.qposadr[0]] - linear.equilibrium[0]))
        )
        out["max_pitch_rad"] = float(np.max(np.abs(trajectory.qpos[:, pitch.qposadr[0]])))
        return out

    @staticmethod
    def _road_bump_quantities(model, params, trajectory) -> dict:
        quarter = _QuarterCar(model, params)
        heave, wheel, road = (model.joint(n) for n in ("heave", "wheel", "road"))
        xs = trajectory.qpos[:, heave.qposadr[0]]
        xw = trajectory.qpos[:, wheel.qposadr[0]]
        vs = trajectory.qvel[:, heave.dofadr[0]]
        vw = trajectory.qvel[:, wheel.dofadr[0]]
        switch = quarter.switch_step(trajectory.dt)
        on_bump = np.arange(len(trajectory.time)) < switch
        road_height = np.where(on_bump, trajectory.qpos[:, road.qposadr[0]], 0.0)  # the realized input
        suspension = quarter.suspension_force(xs, xw, vs, vw)
        tire = quarter.tire_force(xw, road_height)
        static_tire = (quarter.ms + quarter.mu) * quarter.g
        body_modes = _damped_modes(quarter.on_road[:4, :4])
        out: dict = {
            "sprung_mass_kg": quarter.ms,
            "body_frequency_hz": body_modes[0][0] / (2 * math.pi),
            "body_damping_ratio": body_modes[0][1],
            "wheel_hop_frequency_hz": body_modes[1][0] / (2 * math.pi),
            "wheel_hop_damping_ratio": body_modes[1][1],
            "bump_duration_s": quarter.bump_time,
            "peak_body_acceleration_m_s2": float(np.max(np.abs(suspension / quarter.ms - quarter.g))),
            "peak_suspension_travel_m": float(np.max(np.abs((xs - xw) - (xs[0] - xw[0])))),
            "peak_tire_deflection_m": float(np.max(np.abs(tire - static_tire))) / quarter.kt,
            "min_body_height_m": float(np.min(xs)),
            "static_tire_force_n": static_tire,
            "min_tire_force_n": float(np.min(tire)),
            "tire_leaves_road": bool(np.min(tire) < 0.0),
        }
        if out["tire_leaves_road"]:
            # a real tire cannot pull: after this instant the linear model's answers are an upper estimate
            out["tire_lift_off_time_s"] = float(trajectory.time[int(np.argmax(tire < 0.0))])
        return out


SCENE = Car()


# -- helpers ---------------------------------------------------------------------------------------


def _gravity(model: mujoco.MjModel) -> float:
    """g [m/s^2] from opt.gravity (the car's z axis is vertical)."""
    return -float(model.opt.gravity[2])


def _tendon(model: mujoco.MjModel, name: str) -> dict:
    """A fixed tendon read back: stiffness [N/m], damping [N s/m], rest length [m], joint -> coefficient."""
    i = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_TENDON, name)
    start, count = model.tendon_adr[i], model.tendon_num[i]
    coefficients = {
        mujoco.mj_id2name(model, mujoco.mjtObj.mjOBJ_JOINT, int(model.wrap_objid[w])): float(model.wrap_prm[w])
        for w in range(start, start + count)
    }
    return {
        "stiffness": float(model.tendon_stiffness[i]),
        "damping": float(model.tendon_damping[i]),
        "rest": float(model.tendon_lengthspring[i, 0]),
        "coefficients": coefficients,
    }


def _one_dof(model: mujoco.MjModel) -> tuple[float, float, float, float, float]:
    """(m [kg], k [N/m], d [N s/m], springref [m], g [m/s^2]) of the 1-DOF car, read back."""
    heave = model.joint("heave")
    return (
        float(model.body("car").mass[0]),
        float(heave.stiffness[0]),
        float(model.dof_damping[heave.dofadr[0]]),
        float(model.qpos_spring[heave.qposadr[0]]),
        _gravity(model),
    )


class _Linear2Dof:
    """pitch_heave's linear equations M q'' + C q' + K q = f0, q = (heave [m], pitch [rad]), read back."""

    def __init__(self, model: mujoco.MjModel):
        m = float(model.body("car").mass[0])
        inertia = float(model.body("car").inertia[1])
        g = _gravity(model)
        stiff, damp, rest, arm = [], [], [], []
        for axle in ("front", "rear"):
            t = _tendon(model, f"{axle}_suspension")
            stiff.append(t["stiffness"])
            damp.append(t["damping"])
            rest.append(t["rest"])
            arm.append(t["coefficients"]["pitch"])  # d(length)/d(pitch): -a front, +b rear
            if t["coefficients"]["heave"] != 1.0:
                raise ValueError(f"{axle}_suspension must have coefficient 1 on heave")
        self.a, self.b = -arm[0], arm[1]
        jac = np.array([[1.0, arm[0]], [1.0, arm[1]]])  # axle lengths = jac @ q
        self.jacobian = jac
        self.axle_stiffness, self.axle_damping, self.axle_rest = np.array(stiff), np.array(damp), np.array(rest)
        self.mass = np.diag([m, inertia])
        self.stiffness = jac.T @ np.diag(stiff) @ jac
        self.damping = jac.T @ np.diag(damp) @ jac
        # constant generalized force: spring preloads and gravity
        self.preload = jac.T @ (np.array(stiff) * np.array(rest)) + np.array([-m * g, 0.0])
        self.equilibrium = np.linalg.solve(self.stiffness, self.preload)


def _push_force(model: mujoco.MjModel, params: dict[str, float]) -> np.ndarray:
    """Generalized force (heave [N], pitch [N m]) of the passers-by's weight pushing down at push_position."""
    force = params["push_mass"] * _gravity(model)
    station = params["push_position"]
    return np.array([-force, force * station])  # height there = heave - station * pitch


def _axle_force(linear: _Linear2Dof, axle: int, x, theta, vel) -> np.ndarray:
    """Compressive force [N] of one axle's springs and dampers along a motion."""
    jac = linear.jacobian[axle]
    length = jac[0] * x + jac[1] * theta
    rate = jac[0] * vel["heave"] + jac[1] * vel["pitch"]
    return linear.axle_stiffness[axle] * (linear.axle_rest[axle] - length) - linear.axle_damping[axle] * rate


class _QuarterCar:
    """road_bump's quarter car read back from the model, with the true bump input from the parameters.

    State z = (x_s, x_w, v_s, v_w, e, e', 1): body and wheel heights [m] and
    velocities [m/s], the bump generator e(t) = H sin(omega t) and its rate, and
    a constant for the preloads and gravity.
    """

    def __init__(self, model: mujoco.MjModel, params: dict[str, float]):
        self.g = _gravity(model)
        self.ms = float(model.body("car").mass[0])
        self.mu = float(model.body("wheels").mass[0])
        spring = _tendon(model, "suspension")
        self.ks, self.cs, self.rest = spring["stiffness"], spring["damping"], spring["rest"]
        gain = model.actuator("tire_on_road").gainprm
        self.kt = -float(gain[1])
        self.radius = float(gain[0]) / self.kt
        self.height = params["bump_height"]
        self.omega = math.pi * params["speed"] / params["bump_length"]
        self.bump_time = params["bump_length"] / params["speed"]
        ms, mu, ks, cs, kt, g = self.ms, self.mu, self.ks, self.cs, self.kt, self.g
        a = np.zeros((7, 7))
        a[0, 2] = a[1, 3] = a[4, 5] = 1.0
        a[2, :4] = [-ks / ms, ks / ms, -cs / ms, cs / ms]
        a[2, 6] = ks * self.rest / ms - g
        a[3, :4] = [ks / mu, -(ks + kt) / mu, cs / mu, -cs / mu]
        a[3, 6] = (kt * self.radius - ks * self.rest) / mu - g
        a[5, 4] = -(self.omega**2)
        self.on_road = a
        self.on_bump = a.copy()
        self.on_bump[3, 4] = kt / mu  # the tire follows the bump

    def initial_state(self) -> np.ndarray:
        """Static equilibrium, with the generator started at e = 0, e' = H omega."""
        a = self.on_road[:4, :4]
        rest = np.linalg.solve(a[2:4, :2], -self.on_road[2:4, 6])
        return np.array([rest[0], rest[1], 0.0, 0.0, 0.0, self.height * self.omega, 1.0])

    def switch_step(self, dt: float) -> int:
        """Step at whose start the tire leaves the bump: the step boundary nearest the bump's end."""
        return int(round(self.bump_time / dt))

    def suspension_force(self, xs, xw, vs, vw) -> np.ndarray:
        """Compressive force [N] of the suspension spring and damper."""
        return self.ks * (self.rest - (xs - xw)) - self.cs * (vs - vw)

    def tire_force(self, xw, road_height) -> np.ndarray:
        """Compressive tire force [N] (negative: the tire would have to pull on the road)."""
        return self.kt * (self.radius + road_height - xw)


def _piecewise_lti(time: np.ndarray, z0: np.ndarray, segments: list[tuple[float, np.ndarray]]) -> np.ndarray:
    """Exact z(t) of z' = A_j z on [s_j, s_j+1) (segments [(s_j, A_j)], s_0 = 0), at `time` [s].

    analytic.lti_response on each segment, restarted from the exact state at
    the switch, which may fall anywhere between output times.
    """
    time = np.asarray(time, float)
    z = np.empty((len(time), len(z0)))
    state = np.asarray(z0, float)
    for j, (start, a) in enumerate(segments):
        end = segments[j + 1][0] if j + 1 < len(segments) else np.inf
        inside = (time >= start) & (time < end)
        if inside.any():
            z[inside] = analytic.lti_response(time[inside] - start, a, state)
        if np.isfinite(end):
            state = analytic.lti_response(np.array([end - start]), a, state)[0]
    return z


def _undamped_modes(mass: np.ndarray, stiffness: np.ndarray) -> list[tuple[float, np.ndarray]]:
    """[(omega [rad/s], unit mode shape (heave, pitch), heave >= 0)] of K phi = omega^2 M phi, ascending."""
    values, vectors = np.linalg.eig(np.linalg.solve(mass, stiffness))
    out = []
    for i in np.argsort(values.real):
        shape = vectors[:, i].real / np.linalg.norm(vectors[:, i].real)
        out.append((math.sqrt(values[i].real), shape if shape[0] >= 0 else -shape))
    return out


def _damped_modes(a: np.ndarray) -> list[tuple[float, float]]:
    """[(omega_n [rad/s], zeta [-])] of a state matrix's eigenvalues, ascending.

    An oscillatory pair gives one entry, omega_n = |lambda|, zeta = -Re(lambda) / |lambda|;
    a real root gives (|lambda|, 1), the critically damped bound, for stability advice.
    """
    out = []
    for lam in np.linalg.eigvals(a):
        if lam.imag > 0:
            out.append((abs(lam), -lam.real / abs(lam)))
        elif lam.imag == 0 and lam.real != 0:
            out.append((abs(lam), 1.0))
    return sorted(out)


def _peaks(time, offset, velocity, dt) -> np.ndarray:
    """Extrema (t [s], value [m]) of `offset`, from the sign changes of `velocity`.

    The time is the velocity's zero by linear interpolation, the value a cubic
    Hermite interpolant of (offset, velocity) there: O(dt^4), so the measured
    logarithmic decrement is not limited by the sampling.
    """
    out = [(time[0], offset[0])] if velocity[0] == 0.0 else []  # released from rest: an extremum
    crossings = np.flatnonzero(np.sign(velocity[:-1]) * np.sign(velocity[1:]) < 0)
    for i in crossings:
        v0, v1 = velocity[i], velocity[i + 1]
        s = v0 / (v0 - v1)  # fraction of the step
        x0, x1 = offset[i], offset[i + 1]
        h00, h10, h01, h11 = 2 * s**3 - 3 * s**2 + 1, s**3 - 2 * s**2 + s, -2 * s**3 + 3 * s**2, s**3 - s**2
        out.append((time[i] + s * dt, h00 * x0 + h10 * dt * v0 + h01 * x1 + h11 * dt * v1))
    return np.array(out).reshape(-1, 2)


def linearize(model: mujoco.MjModel, qpos: np.ndarray) -> dict[str, np.ndarray]:
    """MuJoCo's continuous-time linearization at rest at `qpos` [m, rad]: M, C, K (nv x nv).

    mujoco.mjd_inverseFD finite-differences the inverse dynamics f(q, v, a):
    M = df/da, C = df/dv, K = df/dq (it returns them transposed; RK4 is not
    supported, so the integrator is set to implicit for the call and restored).
    """
    data = mujoco.MjData(model)
    data.qpos[:] = model.qpos0
    for name, value in zip(("heave", "pitch"), qpos):
        data.qpos[model.joint(name).qposadr[0]] = value
    integrator = model.opt.integrator
    model.opt.integrator = mujoco.mjtIntegrator.mjINT_IMPLICIT
    nv = model.nv
    dfdq, dfdv, dfda = np.zeros((nv, nv)), np.zeros((nv, nv)), np.zeros((nv, nv))
    try:
        with quiet_mujoco():
            mujoco.mj_forward(model, data)
            mujoco.mjd_inverseFD(model, data, 1e-6, False, dfdq, dfdv, dfda, None, None, None, None)
    finally:
        model.opt.integrator = integrator
    return {"M": dfda.T.copy(), "C": dfdv.T.copy(), "K": dfdq.T.copy()}
