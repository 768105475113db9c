"""car's road_bump: the quarter car over a half-sine bump, with its MJCF-native road input (module car's docstring).

ms xs'' = -ks (xs - xw - rest) - cs (xs' - xw') - ms g
mu xw'' =  ks (xs - xw - rest) + cs (xs' - xw') + kt (radius + r(t) - xw) - mu g
"""

from __future__ import annotations

import math
from collections.abc import Mapping

import mujoco
import numpy as np

from springlab.errors import ParameterError
from springlab.exact import analytic, events
from springlab.scenes.base import MIN_MASS, MIN_MASS_REASON, Case, Reference
from springlab.scenes.capabilities.drawing import Drawing
from springlab.scenes.capabilities.drawing import RoadBump as BumpDrawing
from springlab.sim.simulate import Setup, Trajectory

from .parts import Variant, damped_modes, gravity, refuse_motion, tendon

#: road_bump: the four springs of a comfort-tuned 1000 kg car [N/m]: body bounce
#: sqrt(k / m) / 2 pi = 1.23 Hz (Gillespie: 1-1.5 Hz for passenger cars)
COMFORT_STIFFNESS = 6.0e4
#: exciter spring stiffness relative to the largest force it carries per metre of bump
EXCITER_STIFFNESS_RATIO = 1e12


class QuarterCar:
    """road_bump's quarter car read back from the model, with the true bump input from the parameters.

    State z = (x_s, x_w, v_s, v_w, e, e', 1): body and wheel heights [m] and
    velocities [m/s], the bump generator e(t) = H sin(omega t) and its rate, and
    a constant for the preloads and gravity.
    """

    def __init__(self, model: mujoco.MjModel, params: dict[str, float]):
        self.g = gravity(model)
        self.ms = float(model.body("car").mass[0])
        self.mu = float(model.body("wheels").mass[0])
        spring = tendon(model, "suspension")
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

    @classmethod
    def of(cls, case: Case) -> QuarterCar:
        """The case's quarter car, read back once per case (its setup, reference, modes and quantities share it)."""
        return case.memo("quarter_car", lambda: cls(case.model, case.params))

    def initial_state(self) -> np.ndarray:
        """Static equilibrium, with the generator started at e = 0, e' = H omega."""
        a = self.on_road[:4, :4]
        rest = np.linalg.solve(a[2:4, :2], -self.on_road[2:4, 6])
        return np.array([rest[0], rest[1], 0.0, 0.0, 0.0, self.height * self.omega, 1.0])

    def switch_step(self, dt: float) -> int:
        """Step at whose start the tire leaves the bump: the step boundary nearest the bump's end."""
        return int(round(self.bump_time / dt))

    def suspension_force(
        self, xs: float | np.ndarray, xw: float | np.ndarray, vs: float | np.ndarray, vw: float | np.ndarray
    ) -> np.ndarray:
        """Compressive force [N] of the suspension spring and damper."""
        return self.ks * (self.rest - (xs - xw)) - self.cs * (vs - vw)

    def tire_force(self, xw: np.ndarray, road_height: float | np.ndarray) -> np.ndarray:
        """Compressive tire force [N] (negative: the tire would have to pull on the road)."""
        return self.kt * (self.radius + road_height - xw)

    def static_tire_force(self) -> float:
        """Tire force [N] at rest: the weight of the sprung and unsprung masses."""
        return (self.ms + self.mu) * self.g

    def states(self, model: mujoco.MjModel, trajectory: Trajectory) -> np.ndarray:
        """(n, 7) state z of a run, read from its joints (the exciter's coordinate is e)."""
        heave, wheel, road = (model.joint(n) for n in ("heave", "wheel", "road"))
        q, v = trajectory.qpos, trajectory.qvel
        return np.column_stack(
            [
                q[:, heave.qposadr[0]],
                q[:, wheel.qposadr[0]],
                v[:, heave.dofadr[0]],
                v[:, wheel.dofadr[0]],
                q[:, road.qposadr[0]],
                v[:, road.dofadr[0]],
                np.ones(len(trajectory.time)),
            ]
        )

    def measured(self, model: mujoco.MjModel, trajectory: Trajectory) -> dict[str, float]:
        """Peaks, minima and the lift-off time of a run, between its samples to the run's order.

        On each input segment (on the bump up to the switch step, on the flat road from it) the
        state obeys z' = A z exactly, so any output y = c z has y' = c A z and y'' = c A^2 z: cubic
        Hermite interpolation of (y, y') (extrema located on (y', y'')) is O(dt^4), as RK4
        (springlab.exact.events). Reading them at the samples would be O(dt^2) in a peak and O(dt) in a time.

        Returns: body_acceleration [m/s^2] (largest |x_s''|), suspension_travel [m] (largest change of
        x_s - x_w), tire_deflection [m] (largest change from the static deflection), min_body_height [m],
        min_tire_force [N] and lift_off_time [s] (first time the tire force is negative, nan: never).
        """
        z = self.states(model, trajectory)
        time = trajectory.time
        switch = min(self.switch_step(trajectory.dt), len(time) - 1)
        unit = np.eye(7)
        static_travel = z[0, 0] - z[0, 1]
        peaks = {"body_acceleration": 0.0, "suspension_travel": 0.0, "tire_deflection": 0.0}
        lows = {"min_body_height": math.inf, "min_tire_force": math.inf}
        lift_off = math.nan
        # segment samples: the switch sample belongs to both (its left and right limits)
        segments = [(self.on_bump, slice(0, switch + 1)), (self.on_road, slice(switch, len(time)))]
        for a, part in segments:
            t, zs = time[part], z[part]
            if len(t) < 2:
                continue
            on_bump = a is self.on_bump
            road = unit[4] if on_bump else np.zeros(7)
            tire = self.kt * (self.radius * unit[6] + road - unit[1])
            outputs = {
                "body_acceleration": a[2],
                "suspension_travel": unit[0] - unit[1] - static_travel * unit[6],
                "tire_deflection": tire / self.kt - self.static_tire_force() / self.kt * unit[6],
            }
            for name, c in outputs.items():
                y, dy, ddy = zs @ c, zs @ (c @ a), zs @ (c @ a @ a)
                peaks[name] = max(peaks[name], events.peak_magnitude(t, y, dy, ddy))
            for name, c in (("min_body_height", unit[0]), ("min_tire_force", tire)):
                y, dy, ddy = zs @ c, zs @ (c @ a), zs @ (c @ a @ a)
                found = events.extrema(t, y, dy, ddy)
                lows[name] = min(lows[name], float(np.min(y)), *(found[:, 1] if len(found) else []))
                if name == "min_tire_force" and math.isnan(lift_off):
                    lift_off = events.first_below(t, y, dy, 0.0)
        return {**peaks, **lows, "lift_off_time": lift_off}


def piecewise_lti(time: np.ndarray, z0: np.ndarray, segments: list[tuple[float, np.ndarray]]) -> np.ndarray:
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


class RoadBump(Variant):
    """One corner of the car driven over the bump at `speed`."""

    relevant = (
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
    )

    def check_body_masses(self, params: dict[str, float], mjcf_inertia: tuple[float, float, float]) -> None:
        """A quarter of the mass per corner, at or above MIN_MASS."""
        if params["mass"] / 4.0 < MIN_MASS:
            raise ParameterError(
                f"mass must be a finite number >= {4 * MIN_MASS:g} kg for road_bump (a quarter of it per corner;"
                f" {MIN_MASS_REASON}), got {params['mass']!r}"
            )

    def edit(self, spec: mujoco.MjSpec, params: dict[str, float], g: float) -> None:
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

    def setup(self, case: Case, steps: int, dt: float) -> Setup:
        model = case.model
        qvel = np.zeros(model.nv)
        quarter = QuarterCar.of(case)
        qvel[model.joint("road").dofadr[0]] = quarter.height * quarter.omega
        switch_step = quarter.switch_step(dt)
        control = np.zeros((steps, 2))
        control[:switch_step, 0] = 1.0  # tire on the bump exciter
        control[switch_step:, 1] = 1.0  # tire on the flat road
        self._check_motion(case, np.arange(steps + 1) * dt, dt)
        # qpos0: the static equilibrium (clearance; wheel at its loaded height)
        return Setup(qpos=model.qpos0.copy(), qvel=qvel, control=control)

    def _check_motion(self, case: Case, time: np.ndarray, dt: float) -> None:
        """ParameterError if the exact motion puts the bottom below ground or makes the suspension pull."""
        reference = self.reference(case, time, dt)
        params = case.params
        quarter = QuarterCar.of(case)
        x = reference.pos["heave"]
        refuse_motion(
            f"bump_height = {params['bump_height']:g} m at speed = {params['speed']:g} m/s",
            "use a lower bump or another speed",
            time,
            {"body": x},
            {
                "suspension": quarter.suspension_force(
                    x, reference.pos["wheel"], reference.vel["heave"], reference.vel["wheel"]
                )
            },
        )

    def reference(self, case: Case, time: np.ndarray, dt: float) -> Reference:
        quarter = QuarterCar.of(case)
        z0 = quarter.initial_state()
        true = piecewise_lti(time, z0, [(0.0, quarter.on_bump), (quarter.bump_time, quarter.on_road)])
        switch = quarter.switch_step(dt) * dt
        realized = piecewise_lti(time, z0, [(0.0, quarter.on_bump), (switch, quarter.on_road)])
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

    def modes(self, case: Case) -> list[tuple[float, float]]:
        quarter = QuarterCar.of(case)
        return damped_modes(quarter.on_road[:4, :4]) + [(quarter.omega, 0.0)]

    def quantities(self, case: Case, trajectory: Trajectory) -> dict:
        model = case.model
        quarter = QuarterCar.of(case)
        peaks = quarter.measured(model, trajectory)
        body_modes = damped_modes(quarter.on_road[:4, :4])
        static_tire = quarter.static_tire_force()
        out: dict = {
            "sprung_mass_kg": quarter.ms,
            "body_frequency_hz": body_modes[0][0] / (2 * math.pi),
            "body_damping_ratio": body_modes[0][1],
            "wheel_hop_frequency_hz": body_modes[1][0] / (2 * math.pi),
            "wheel_hop_damping_ratio": body_modes[1][1],
            "bump_duration_s": quarter.bump_time,
            "peak_body_acceleration_m_s2": peaks["body_acceleration"],
            "peak_suspension_travel_m": peaks["suspension_travel"],
            "peak_tire_deflection_m": peaks["tire_deflection"],
            "min_body_height_m": peaks["min_body_height"],
            "static_tire_force_n": static_tire,
            "min_tire_force_n": peaks["min_tire_force"],
            "tire_leaves_road": bool(peaks["min_tire_force"] < 0.0),
        }
        if out["tire_leaves_road"]:
            # a real tire cannot pull: from this instant on the linear model no longer describes the car
            out["tire_lift_off_time_s"] = peaks["lift_off_time"]
        return out

    def drawing(self, case: Case) -> Drawing:
        """The bump drawn under the front right wheel, travelling at the driving speed; a quarter car models one
        corner, so it is not drawn past the middle between the axles (the rear wheel does not feel it)."""
        p = case.params
        bump = BumpDrawing(p["bump_height"], p["bump_length"], p["speed"], "wheel_front_right", "wheel_rear_right")
        return Drawing(road=bump)

    def model_limits(self, case: Case, trajectory: Trajectory) -> list[str]:
        model, params = case.model, case.params
        quarter = QuarterCar.of(case)
        peaks = quarter.measured(model, trajectory)
        if peaks["min_tire_force"] >= 0.0:
            return []
        return [
            f"the tire leaves the road at t = {peaks['lift_off_time']:.6g} s (bump_height = {params['bump_height']:g} m"
            f" at speed = {params['speed']:g} m/s): the linear tire would have to pull"
            f" {-peaks['min_tire_force']:.4g} N on the road, which a real tire cannot, so the answers after that"
            " instant are not the car's; use a lower bump or another speed"
        ]


def road_as_control(spec: mujoco.MjSpec, params: Mapping[str, float]) -> None:
    """road_bump's quarter car with the road height under the tire as a control [m] (`springlab frequency`).

    The tire on the flat road becomes force = kt (radius + ctrl - x_w): a gain kt on the control and an affine
    bias kt radius - kt x_w, the same spring (ctrl = 0 is the flat road, the static equilibrium of qpos0), now
    with the road height as an input MuJoCo holds over each step. The bump exciter, its tendon and the tire
    on the bump are removed: the quarter car is left with its two degrees of freedom, heave and wheel.

    Parameters
    ----------
    spec
        road_bump's spec after the scene's edits.
    params
        the scene's parameters (SI).
    """
    spec.delete(spec.actuator("tire_on_bump"))
    spec.delete(spec.tendon("bump_contact"))
    spec.delete(spec.body("road"))
    tire = spec.actuator("tire_on_road")
    kt = -float(tire.gainprm[1])
    radius = float(tire.gainprm[0]) / kt
    tire.name = "road"
    tire.gaintype = mujoco.mjtGain.mjGAIN_FIXED
    tire.gainprm = [kt] + [0.0] * 9
    tire.biastype = mujoco.mjtBias.mjBIAS_AFFINE
    tire.biasprm = [kt * radius, -kt, 0.0] + [0.0] * 7
