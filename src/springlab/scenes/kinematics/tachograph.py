"""kinematics' tachograph: a bus's recorded v(t), piecewise linear, driven step by step (module kinematics).

    x(t) = x0 + integral of v,   a(t) = the slope of v(t) on each segment [m/s^2]

The acceleration is piecewise constant and switches only at the record's knot
times, which must lie on the step grid (dt must divide 4 s and 8 s): the
`force_step` motor then carries the exact force m a on every step, and the
motion is a quadratic on each step, which RK4 reproduces to round-off.
"""

from __future__ import annotations

from collections.abc import Callable

import mujoco
import numpy as np

from springlab.errors import BadInputError, ParameterError
from springlab.exact import analytic
from springlab.sim.simulate import Setup, Trajectory

from .bus import dress_as_bus

#: the tachograph record: knot times [s] and the velocities there [m/s]; v(t) is linear between them
TACHOGRAPH_TIMES = (0.0, 4.0, 8.0, 12.0)
TACHOGRAPH_VELOCITIES = (0.0, 6.0, 6.0, 0.0)
#: parameters that the tachograph's profile replaces
_PROFILE_PARAMETERS = ("v0", "a0", "jerk")


def reject_profile_parameters(params: dict[str, float], explicit: set[str]) -> dict[str, float]:
    """Tachograph preset: its v(t) profile fixes v0, a0 and jerk, so setting them is an error."""
    clash = sorted(explicit & set(_PROFILE_PARAMETERS))
    if clash:
        raise ParameterError(
            f"tachograph takes its velocity from the recorded v(t) profile, so {', '.join(clash)}"
            " cannot be set; valid for tachograph: mass, x0"
        )
    return {"v0": TACHOGRAPH_VELOCITIES[0], "a0": 0.0, "jerk": 0.0}


class Tachograph:
    """The tachograph scenario's variant: the record's v(t), drawn as the chapter's touring bus."""

    @staticmethod
    def accelerations() -> np.ndarray:
        """Acceleration on each segment of the tachograph record [m/s^2] (the slopes of v(t))."""
        return np.diff(TACHOGRAPH_VELOCITIES) / np.diff(TACHOGRAPH_TIMES)

    def edit(self, spec: mujoco.MjSpec) -> None:
        """The chapter's tachograph is a bus's (the other examples are a car's): pictures only."""
        dress_as_bus(spec)

    def setup(self, m: float, params: dict[str, float], steps: int, dt: float) -> Setup:
        """Released from x0 at rest; the motor carries m a(t) [N] on each step of `dt` [s]."""
        qpos = np.array([params["x0"]])
        self._check_knots_on_grid(dt)
        if steps * dt > TACHOGRAPH_TIMES[-1] * (1 + 1e-12):
            raise BadInputError(
                f"the tachograph record covers {TACHOGRAPH_TIMES[-1]:g} s;"
                f" duration must be <= {TACHOGRAPH_TIMES[-1]:g} s, got {steps * dt:g} s"
            )
        # the motor carries m a on each step; a is read at the step's midpoint, which lies
        # strictly inside one segment because every knot is a step boundary
        midpoints = (np.arange(steps) + 0.5) * dt
        accel = self._acceleration(midpoints)
        control = np.column_stack([np.zeros(steps), m * accel])
        return Setup(qpos=qpos, qvel=np.array([TACHOGRAPH_VELOCITIES[0]]), act=np.array([0.0]), control=control)

    @staticmethod
    def _acceleration(time: np.ndarray) -> np.ndarray:
        """a(t) [m/s^2] of the tachograph record; at a knot, the segment that starts there."""
        slopes = Tachograph.accelerations()
        index = np.clip(np.searchsorted(TACHOGRAPH_TIMES, time, side="right") - 1, 0, len(slopes) - 1)
        return slopes[index]

    @staticmethod
    def _check_knots_on_grid(dt: float) -> None:
        """The acceleration may switch only at step boundaries, else the run is not exact."""
        for knot in TACHOGRAPH_TIMES[1:-1]:
            ratio = knot / dt
            if abs(ratio - round(ratio)) > 1e-9 * max(ratio, 1.0):
                knots = ", ".join(f"{k:g}" for k in TACHOGRAPH_TIMES[1:-1])
                raise BadInputError(
                    f"tachograph switches its acceleration at t = {knots} s, so dt must divide them"
                    f" (e.g. 0.01, 0.005, 0.001 s), got dt = {dt:g} s"
                )

    def exact(
        self, m: float, params: dict[str, float], time: np.ndarray
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """(x [m], v [m/s], state matrix, states) of the record at `time` [s]: z = (x, v, F)."""
        # MuJoCo's accumulated time may overshoot the record's end by round-off
        inside = np.clip(time, TACHOGRAPH_TIMES[0], TACHOGRAPH_TIMES[-1])
        x, v, a = analytic.piecewise_linear_velocity(inside, TACHOGRAPH_TIMES, TACHOGRAPH_VELOCITIES, x0=params["x0"])
        # z = (x, v, F): the force is constant on every step
        system = np.array([[0.0, 1.0, 0.0], [0.0, 0.0, 1.0 / m], [0.0, 0.0, 0.0]])
        states = np.column_stack([x, v, m * np.asarray(a, float) * np.ones_like(time)])
        return x, v, system, states

    def phase_field(self, params: dict[str, float]) -> Callable | None:
        """None: a(t) varies in time, so the phase plane has no fixed vector field."""
        return None

    def quantities(
        self, m: float, params: dict[str, float], trajectory: Trajectory, t_end: float, x_sim: float, v_sim: float
    ) -> dict:
        """The record read as the chapter does: v(t) and a(t) by segment, displacement = area [m]."""
        times = np.array(TACHOGRAPH_TIMES)
        velocities = np.array(TACHOGRAPH_VELOCITIES)
        slopes = self.accelerations()
        areas = 0.5 * (velocities[1:] + velocities[:-1]) * np.diff(times)
        pieces = []
        for i, slope in enumerate(slopes):
            start, v_start = times[i], velocities[i]
            shifted = "t" if start == 0 else f"(t - {start:g})"
            if slope == 0:
                v_text = f"{v_start:g}"
            else:
                lead = f"{v_start:g} {'+' if slope > 0 else '-'} " if v_start else ("-" if slope < 0 else "")
                v_text = f"{lead}{abs(slope):g} {shifted}"
            pieces.append(f"{v_text} m/s for {start:g} <= t <= {times[i + 1]:g} s")
        x_end, v_end, a_end = analytic.piecewise_linear_velocity(
            np.array([min(t_end, TACHOGRAPH_TIMES[-1])]), TACHOGRAPH_TIMES, TACHOGRAPH_VELOCITIES, x0=params["x0"]
        )
        return {
            "velocity_profile": "v(t) = " + "; ".join(pieces),
            "acceleration_profile": "a(t) = "
            + "; ".join(f"{s:g} m/s^2 for {times[i]:g} < t < {times[i + 1]:g} s" for i, s in enumerate(slopes)),
            "knot_times_s": times.tolist(),
            "knot_velocities_m_s": velocities.tolist(),
            "segment_accelerations_m_s2": slopes.tolist(),
            "segment_displacements_m": areas.tolist(),
            "displacement_m": float(np.sum(areas)),
            "max_velocity_m_s": float(np.max(velocities)),
            "end_time_s": t_end,
            "x_end_m": float(np.asarray(x_end).ravel()[0]),
            "v_end_m_s": float(np.asarray(v_end).ravel()[0]),
            "x_end_simulated_m": x_sim,
            "v_end_simulated_m_s": v_sim,
        }
