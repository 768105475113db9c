"""printer_head's closed loop: a sampled PD/PID position loop on an encoder, run in MuJoCo and exactly.

The variant `Feedback` of the scenarios `feedback_motor` (the encoder on the motor shaft: collocated) and
`feedback_carriage` (a linear encoder on the carriage: across the belt from the force). The firmware's loop at
`control_rate_hz` (period T, a whole number of MuJoCo steps) reads the encoder at each sample, computes

    u_k = clip(F_k + kp e_k + kd (v_k - (y_k - y_(k-1)) / T) + ki I_k, +-drive_force),   e_k = r_k - y_k,

(springlab.exact.sampled_loop's law; the clip is the motor's force limit, as MuJoCo's ctrlrange clips) and
holds it until the next sample. The set point r_k follows a planner's path to move_distance D: a bang-bang
path lasting `planned_move_time` (each half rounded up to whole controller periods, its acceleration a lowered
to D / (n T)^2 so it ends at D), whose rigid-body force F_ff = M a is fed forward, as a printer's motion
planner feeds its acceleration forward, so a plain PD
step of a whole inch (which saturates the motor for most of its travel) is not the default. By default the
path is the shortest whose feedforward takes 90 % of the force limit (FEEDBACK_SHARE is left to the loop).
The set point is where the encoder should be on the path: the centre of mass's path plus the belt's
quasi-static stretch m_c a / k under the path's acceleration as the encoder sees it (m_c / M of it ahead on
the motor, m_m / M behind on the carriage), and the path's velocity is fed forward to the derivative term.
`planned_move_time` = 0 makes the set point a step with no feedforward: the loop's step response.

MuJoCo runs the loop (`Setup.controller`: springlab.sim.sampled); the exact answer is the same law on the
two-mass model's exact step map (sampled_loop.held_run, every step: within a sample the force is held), the
tolerance its leading-order error carried through the law (held.py). Quantities: the linear loop's margins
(`gain_margin_db`, `phase_margin_deg` and their crossovers; sampled_loop.margins), its `critical_gain`
(the factor on kp, kd, ki at the stability boundary) and pole radius, the peak force and whether it
saturated, MuJoCo's largest encoder difference from the exact loop at the samples, and the carriage's
`positioning_time_s` into +-positioning_band around D, with its exact `positioning_time_s_exact` (the exact
loop continued until its slowest pole has decayed below a thousandth of the band: "for good" is certified).
Positions [m], forces [N], gains kp [N/m], kd [N s/m], ki [N/(m s)], times [s].
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Callable
from typing import TYPE_CHECKING

import numpy as np

from springlab.errors import ParameterError
from springlab.exact import events, sampled_loop
from springlab.scenes.declarations import Reference
from springlab.sim.controller import Controller, Law
from springlab.sim.sampled import steps_per_sample
from springlab.sim.simulate import Setup

from .control import ENCODERS, belt_plant, output_row
from .held import held_reference, initial_vector
from .moves import BeltRun, Variant, initial_qpos_qvel

if TYPE_CHECKING:
    from springlab.scenes.base import Case

__all__ = ["FEEDBACK_PARAMETERS", "Feedback", "Path", "planned_path"]

#: the loop's own parameters
FEEDBACK_PARAMETERS = frozenset({"kp", "kd", "ki", "control_rate_hz", "planned_move_time"})
#: the share of the force limit the default path leaves to the loop (at full feedforward the loop's corrections
#: are clipped one way only and the carriage overshoots by 0.4 mm at the defaults; at 90 % by 36 um)
FEEDBACK_SHARE = 0.1
#: the exact loop is continued until its modes can no longer move the carriage by this fraction of the band
_CERTIFY = 1e-3
#: the longest continuation [s] the certificate tries (a loop slower than this is reported not settled)
_LONGEST_CERTIFICATE = 100.0


@dataclasses.dataclass(frozen=True)
class Path:
    """The planner's set point for the encoder, its rate and the force fed forward, per controller sample.

    Attributes
    ----------
    half_samples
        Samples per half of the bang-bang path n (0: a step of the set point).
    period
        Controller period T [s].
    distance
        Move distance D [m].
    acceleration
        The path's acceleration a = D / (n T)^2 [m/s^2] (0 for a step).
    total_mass
        M [kg]: the feedforward force is M a.
    lead
        Where the encoder sits relative to the centre of mass per unit acceleration [s^2]: the belt's
        quasi-static stretch m_c a / k seen from the encoder, m_c / M of it ahead on the motor, m_m / M behind on
        the carriage.
    """

    half_samples: int
    period: float
    distance: float
    acceleration: float
    total_mass: float
    lead: float = 0.0

    @property
    def duration(self) -> float:
        """The path's time 2 n T [s]."""
        return 2 * self.half_samples * self.period

    @property
    def force(self) -> float:
        """The feedforward force M a [N]."""
        return self.total_mass * self.acceleration

    def at(self, sample: int) -> tuple[float, float, float]:
        """(set point r_k [m], feedforward force F_k [N], rate v_k [m/s]) at sample k (t = k T)."""
        n, t, a = self.half_samples, sample * self.period, self.acceleration
        if sample >= 2 * n:
            return self.distance, 0.0, 0.0
        if sample < n:
            return 0.5 * a * t * t + self.lead * a, self.force, a * t
        remaining = 2 * n * self.period - t
        return self.distance - 0.5 * a * remaining * remaining - self.lead * a, -self.force, a * remaining


def planned_path(params: dict[str, float], encoder: str = "motor") -> Path:
    """The planner's path of the parameters for the encoder (module docstring).

    Raises
    ------
    ParameterError
        A control rate that is not a positive number.
    """
    rate = params["control_rate_hz"]
    period = 1.0 / rate
    m_c, m_m = params["carriage_mass"], params["motor_mass"]
    total = m_c + m_m
    distance, planned = params["move_distance"], params["planned_move_time"]
    if planned == 0:
        return Path(0, period, distance, 0.0, total)
    n = max(1, math.ceil(planned / 2 / period - 1e-9))
    stretch = m_c / params["belt_stiffness"]  # the belt's quasi-static stretch per unit acceleration [s^2]
    lead = stretch * (m_c / total if encoder == "motor" else -m_m / total)
    return Path(n, period, distance, distance / (n * period) ** 2, total, lead)


def shortest_planned_time(params: dict[str, float], share: float = 1.0) -> float:
    """The shortest path [s] whose feedforward takes `share` [-] of the force limit: 2 sqrt(D M / (share F)),
    rounded up to whole controller periods."""
    period = 1.0 / params["control_rate_hz"]
    total = params["carriage_mass"] + params["motor_mass"]
    half = math.sqrt(params["move_distance"] * total / (share * params["drive_force"]))
    return 2 * max(1, math.ceil(half / period - 1e-9)) * period


@dataclasses.dataclass(frozen=True)
class ExactLoop:
    """The exact closed loop of a case at a step: every step's state, force, and where the law clipped.

    Attributes
    ----------
    states
        x = (q_c, q_m, v_c, v_m) at each step [m, m/s], (m + 1, 4), m at least the run's steps.
    forces
        The held force per step [N], (m,).
    saturated
        Per sample, whether the law clipped its force, (samples,).
    settled
        Whether the continuation reached the certifying decay (the loop is stable and decays in time).
    """

    states: np.ndarray
    forces: np.ndarray
    saturated: np.ndarray
    settled: bool


class Feedback(Variant):
    """feedback_motor's and feedback_carriage's variant: the sampled loop with the encoder `encoder` (module docstring)."""

    parameters = FEEDBACK_PARAMETERS
    instruments = True

    def __init__(self, encoder: str) -> None:
        self.encoder = encoder
        output_row(encoder)  # an unknown encoder fails here, at import

    # -- parameters ---------------------------------------------------------------------------------

    def derive(self, params: dict[str, float], explicit: set[str]) -> dict[str, float]:
        """The planned move time: the shortest whose feedforward leaves the loop FEEDBACK_SHARE of the force."""
        return {"planned_move_time": shortest_planned_time(params, 1.0 - FEEDBACK_SHARE)}

    def check(self, params: dict[str, float]) -> None:
        """A feedforward beyond the force limit is refused (the path cannot be followed)."""
        path = planned_path(params, self.encoder)
        if path.force > params["drive_force"] * (1 + 1e-12):
            raise ParameterError(
                f"planned_move_time = {params['planned_move_time']:g} s needs a feedforward of {path.force:.4g} N,"
                f" more than drive_force = {params['drive_force']:g} N; the shortest path at this force and"
                f" control rate lasts {shortest_planned_time(params):.6g} s (or 0: a step of the set point)"
            )

    def pid(self, params: dict[str, float]) -> sampled_loop.Pid:
        """The law's gains at the control period."""
        return sampled_loop.Pid(params["kp"], params["kd"], params["ki"], 1.0 / params["control_rate_hz"])

    @staticmethod
    def sample_steps(params: dict[str, float], dt: float) -> int:
        """MuJoCo steps per controller period (ParameterError: a rate faster than the step, or not a whole number)."""
        try:
            return steps_per_sample(params["control_rate_hz"], dt)
        except ValueError as error:
            raise ParameterError(str(error)) from None

    # -- the run ------------------------------------------------------------------------------------

    def setup(self, case: Case, steps: int, dt: float) -> Setup:
        """The initial state and the controller in the loop (its law reads the encoder's sensor)."""
        params = case.params
        per_sample = self.sample_steps(params, dt)
        pid, path, limit = self.pid(params), planned_path(params, self.encoder), params["drive_force"]
        address = int(case.model.sensor(ENCODERS[self.encoder][0]).adr[0])

        def law() -> Law:
            pid_law = sampled_loop.PidLaw(pid, limit)

            def control(k: int, sensordata: np.ndarray) -> np.ndarray:
                return np.array([pid_law.update(float(sensordata[address]), *path.at(k))])

            return control

        qpos, qvel = initial_qpos_qvel(case)
        return Setup(qpos=qpos, qvel=qvel, controller=Controller(per_sample, law))

    def exact(self, case: Case, dt: float, steps: int) -> ExactLoop:
        """The exact loop at dt [s] for at least `steps` steps, continued to certify the positioning (kept on the case)."""
        return case.memo(("feedback_exact", dt, steps), lambda: self._exact(case, dt, steps))

    def _held(
        self,
        case: Case,
        dt: float,
        steps: int,
        resume: tuple[np.ndarray, sampled_loop.PidLaw, list[bool], int] | None = None,
    ) -> tuple[np.ndarray, np.ndarray, list[bool], sampled_loop.PidLaw]:
        """The exact loop for `steps` steps: (states, forces, clipped per sample, the law as it ends).

        `resume`: (the last state, the law, the clipped list, the samples done) of a run to continue from its end;
        each step depends only on the state and the held force, so the steps are those a run from the start
        would make, bit for bit.
        """
        params = case.params
        a, b = belt_plant(case.model)
        row = output_row(self.encoder)[0]
        path = planned_path(params, self.encoder)
        if resume is None:
            resume = (initial_vector(case), sampled_loop.PidLaw(self.pid(params), params["drive_force"]), [], 0)
        start, law, saturated, first = resume

        def control(k: int, x: np.ndarray) -> float:
            force = law.update(float(row @ x), *path.at(first + k))
            saturated.append(law.saturated)
            return force

        per_sample = self.sample_steps(params, dt)
        states, forces = sampled_loop.held_run(a, b, dt, steps, start, control, per_sample)
        return states, forces, saturated, law

    def _exact(self, case: Case, dt: float, steps: int) -> ExactLoop:
        params = case.params
        per_sample = self.sample_steps(params, dt)
        path = planned_path(params, self.encoder)
        samples = max(math.ceil(steps / per_sample), 2 * path.half_samples)
        states, forces, saturated, law = self._held(case, dt, samples * per_sample)
        extra = self._certifying_samples(case, dt, states[-1], law)
        if extra is None:
            return ExactLoop(states, forces, np.array(saturated), False)
        if extra:  # continued from the end, not run again from the start
            more, more_forces, saturated, _ = self._held(
                case, dt, extra * per_sample, resume=(states[-1], law, saturated, samples)
            )
            states, forces = np.concatenate([states, more[1:]]), np.concatenate([forces, more_forces])
        return ExactLoop(states, forces, np.array(saturated), True)

    def _certifying_samples(self, case: Case, dt: float, x: np.ndarray, law: sampled_loop.PidLaw) -> int | None:
        """Samples after the path's end x [m, m/s] beyond which the carriage stays within a thousandth of the band
        of D for ever (None: the loop is not stable, or takes too long).

        Once the set point stands at D the loop is linear and time-invariant, z_(k+1) = A_cl z_k + B_cl D, with
        the equilibrium z_eq = (D, D, 0, 0, D[, 0]) (a rigid displacement at rest, the law's memory of it). In
        A_cl's eigenvectors V the deviation is a sum of modes w_i lambda_i^m, and the carriage at step j of a
        sample reads it through a row r_j (the exact map within the sample with the held force), so
        |q_c - D| <= max_j sum_i |(r_j V)_i| |w_i| |lambda_i|^m: exact, whatever the modes' non-normality.
        """
        params = case.params
        pid, target, band = self.pid(params), params["move_distance"], params["positioning_band"]
        a, b = belt_plant(case.model)
        row = output_row(self.encoder)[0]
        phi, gamma = sampled_loop.zoh(a, b, pid.period)
        a_cl, _, c_u, _ = sampled_loop.closed_loop(phi, gamma, row, pid)
        eigenvalues, vectors = np.linalg.eig(a_cl)
        if np.max(np.abs(eigenvalues)) >= 1.0:
            return None
        memory = [target] if pid.ki == 0 else [target, 0.0]
        deviation = np.concatenate([x, [law.previous if law.previous is not None else target]])
        if pid.ki > 0:
            deviation = np.concatenate([deviation, [law.integral]])
        deviation = deviation - np.concatenate([[target, target, 0.0, 0.0], memory])
        modal = np.abs(np.linalg.solve(vectors, deviation))
        per_sample = self.sample_steps(params, dt)
        rows = []
        for j in range(per_sample):
            phi_j, gamma_j = sampled_loop.zoh(a, b, j * dt) if j else (np.eye(4), np.zeros((4, 1)))
            carriage = np.concatenate([phi_j[0], np.zeros(len(a_cl) - 4)]) + gamma_j[0, 0] * c_u
            rows.append(np.abs(carriage @ vectors))
        weights = np.max(np.array(rows) * modal, axis=0)
        decay = np.abs(eigenvalues)

        def bound(extra: int) -> float:
            return float(np.sum(weights * decay**extra))

        longest = math.ceil(_LONGEST_CERTIFICATE / pid.period)
        if bound(longest) > _CERTIFY * band:
            return None
        low, high = -1, longest  # the bound decreases with every sample: bisect for the first one below
        while high - low > 1:
            middle = (low + high) // 2
            low, high = (low, middle) if bound(middle) <= _CERTIFY * band else (middle, high)
        return high

    def reference(self, case: Case, time: np.ndarray, dt: float) -> Reference:
        """The exact loop at the run's steps, its tolerance carried through the law (held.held_reference)."""
        exact = self.exact(case, dt, len(time) - 1)
        per_sample = self.sample_steps(case.params, dt)
        pid, row = self.pid(case.params), output_row(self.encoder)[0]

        def response() -> Callable[[int, np.ndarray], float]:
            linear = sampled_loop.PidLaw(pid)

            def change(k: int, error: np.ndarray) -> float:
                du = linear.update(float(row @ error), 0.0)
                return 0.0 if k < len(exact.saturated) and exact.saturated[k] else du

            return change

        return held_reference(case, time, dt, exact.states, exact.forces, per_sample, response)

    # -- results ------------------------------------------------------------------------------------

    def quantities(self, out: dict, run: BeltRun) -> dict:
        """Margins, the force, the encoder against the exact loop, and the positioning (module docstring)."""
        assert run.case is not None and run.trajectory is not None, "the scene passes the case and the run"
        case, params = run.case, run.params
        pid, path = self.pid(params), planned_path(params, self.encoder)
        a, b = belt_plant(case.model)
        phi, gamma = sampled_loop.zoh(a, b, pid.period)
        row = output_row(self.encoder)
        out["encoder"] = self.encoder
        out["control_period_s"] = pid.period
        out["planned_move_time_s"] = path.duration
        out["planned_acceleration_m_s2"] = path.acceleration
        out["feedforward_force_n"] = path.force
        out.update(sampled_loop.margins(phi, gamma, row, pid))
        out["critical_gain"] = sampled_loop.critical_gain(phi, gamma, row, pid)
        out["closed_loop_pole_radius"] = sampled_loop.spectral_radius(phi, gamma, row, pid)
        out["closed_loop_stable"] = bool(out["closed_loop_pole_radius"] < 1.0)
        control = run.trajectory.control
        out["peak_force_n"] = float(np.max(np.abs(control))) if control is not None and control.size else 0.0
        steps = len(run.time) - 1
        exact = self.exact(case, run.dt, steps)
        out["force_saturated"] = bool(np.any(exact.saturated))
        per_sample = self.sample_steps(params, run.dt)
        encoder = run.q_m if self.encoder == "motor" else run.q_c
        exact_encoder = exact.states[: steps + 1, ENCODERS[self.encoder][1]]
        out["encoder_error_max_m"] = float(np.max(np.abs(encoder[::per_sample] - exact_encoder[::per_sample])))
        band, target = params["positioning_band"], params["move_distance"]
        out["settling_band_m"] = band
        # the run's overshoot between its steps as well (cubic Hermite of position and velocity, O(dt^4))
        turns = events.extrema(run.time, run.q_c - target, run.v_c)
        out["overshoot_m"] = max(0.0, float(np.max(run.q_c - target)), *(float(v) for v in turns[:, 1]))
        # the exact loop's largest excursion between its steps too, not the largest of its samples
        carriage = np.eye(len(a))[0]
        peak = sampled_loop.held_maximum(a, b, run.dt, exact.states, exact.forces, carriage)
        out["overshoot_m_exact"] = max(0.0, peak - target)
        out["final_error_m"] = abs(float(run.q_c[-1]) - target)
        # a root of the exact held motion, not of an interpolant of its steps
        exact_exit = sampled_loop.held_last_exit(a, b, run.dt, exact.states, exact.forces, carriage, band, target)
        # for good: the exact loop, continued until its decay certifies it, leaves the band no more after the run
        out["settled_for_good"] = bool(exact.settled and exact_exit <= run.time[-1])
        out["positioning_time_s_exact"] = exact_exit if exact.settled else math.inf
        out["positioning_time_s"] = (
            events.last_exit(run.time, run.q_c - target, run.v_c, band) if out["settled_for_good"] else math.inf
        )
        return out
