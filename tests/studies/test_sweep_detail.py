"""A sweep row that does not pass says why in `detail`; a row that passes says nothing.

Independent reference for the car over the bump: the quarter-car equations in deviations from
the static equilibrium, written out here,

    ms xs'' = -ks (xs - xw) - cs (xs' - xw')
    mu xw'' =  ks (xs - xw) + cs (xs' - xw') + kt (r(t) - xw),   r(t) = H sin(w t) on the bump,

solved by the matrix exponential (scipy.linalg.expm) of the state (xs, xw, vs, vw, r, r') on the
bump and of (xs, xw, vs, vw) after it. The tire force is (ms + mu) g + kt (r - xw); it first goes
negative (the tire would have to pull on the road) where brentq finds its root. The bump ends on a
step boundary at every speed used here (L / v a multiple of dt), so the simulation's input and this
one switch at the same instant.
"""

from __future__ import annotations

import math
import re

import numpy as np
import pytest
from scipy.linalg import expm
from scipy.optimize import brentq

import springlab

G = 9.81  # models/car.xml's gravity [m/s^2]
RADIUS = 0.3  # unloaded tire radius [m] (the wheel geoms of models/car.xml)


class ExactQuarterCar:
    """The linear quarter car of one sweep row's parameters, by the matrix exponential."""

    def __init__(self, p: dict[str, float]):
        ms, mu, ks, cs, kt = (
            p["mass"] / 4,
            p["unsprung_mass"],
            p["stiffness"] / 4,
            p["damping"] / 4,
            p["tire_stiffness"],
        )
        self.kt, self.weight = kt, (ms + mu) * G
        self.wheel_rest = RADIUS - self.weight / kt
        self.omega = math.pi * p["speed"] / p["bump_length"]
        self.end = p["bump_length"] / p["speed"]
        off = np.zeros((4, 4))
        off[0, 2] = off[1, 3] = 1.0
        off[2] = [-ks / ms, ks / ms, -cs / ms, cs / ms]
        off[3] = [ks / mu, -(ks + kt) / mu, cs / mu, -cs / mu]
        on = np.zeros((6, 6))
        on[:4, :4] = off
        on[3, 4] = kt / mu  # the tire follows the road
        on[4, 5], on[5, 4] = 1.0, -(self.omega**2)
        self.on, self.off = on, off
        self.start = np.array([0, 0, 0, 0, 0, p["bump_height"] * self.omega])
        self.at_end = expm(on * self.end) @ self.start

    def state(self, t: float) -> tuple[np.ndarray, float, float]:
        """(xs, xw, vs, vw), road height r [m] and its rate r' [m/s] at time t [s]."""
        if t <= self.end:
            z = expm(self.on * t) @ self.start
            return z[:4], z[4], z[5]
        return expm(self.off * (t - self.end)) @ self.at_end[:4], 0.0, 0.0

    def tire_force(self, t: float) -> float:
        """Compressive tire force [N] (negative: the tire pulls on the road)."""
        z, road, _ = self.state(t)
        return self.weight + self.kt * (road - z[1])

    def wheel_and_force(self, duration: float, h: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Times [s], wheel deviation xw [m] and tire force [N] on a grid of step h [s] (the bump's end on it),
        stepped by the exact one-step maps expm(A h)."""
        on, off = expm(self.on * h), expm(self.off * h)
        n_on = round(self.end / h)
        z = np.empty((round(duration / h) + 1, 6))
        z[0] = self.start
        for k in range(1, len(z)):
            if k <= n_on:
                z[k] = on @ z[k - 1]
            else:
                z[k, :4], z[k, 4:] = off @ z[k - 1, :4], 0.0
        return np.arange(len(z)) * h, z[:, 1], self.weight + self.kt * (z[:, 4] - z[:, 1])

    def lift_off(self, duration: float, h: float) -> float | None:
        """First time [s] the tire force is negative (None: never within `duration`), to brentq's xtol."""
        time, _, force = self.wheel_and_force(duration, h)
        below = np.flatnonzero(force < 0.0)
        if not below.size:
            return None
        k = below[0]
        return brentq(self.tire_force, time[k - 1], time[k], xtol=1e-13)


@pytest.fixture(scope="module")
def bump_sweep():
    # at 20 m/s over the 4 m bump (0.2 s, 200 steps of 1 ms): soft dampers let the wheel hop off the
    # road, firm ones keep it down (issue 26 item 7's grid, one speed)
    return springlab.sweep("car", "road_bump", vary={"damping": (1000.0, 4000.0, 4)}, speed=20.0)


def test_a_tire_leaving_the_road_is_named_in_detail_at_the_exact_lift_off_time(bump_sweep):
    lifted = passed = 0
    for row in bump_sweep.rows:
        exact = ExactQuarterCar(row.parameters)
        assert exact.end / bump_sweep.dt == pytest.approx(round(exact.end / bump_sweep.dt), abs=1e-9)
        t_lift = exact.lift_off(bump_sweep.duration, bump_sweep.dt / 4)
        if t_lift is None:
            passed += 1
            assert row.passed is True and row.detail == "", row.detail
            continue
        lifted += 1
        assert row.passed is False and not row.diverged
        assert row.detail.startswith("outside the scene's model: the tire leaves the road at t = "), row.detail
        printed = float(re.search(r"leaves the road at t = ([0-9.e+-]+) s", row.detail).group(1))
        # the simulation's wheel-height error moves the force's zero by kt dx / |F'(t)|; dx bounded by
        # the row's own max_rel of the wheel position times its largest value (the rest height + the
        # motion); the detail prints 6 significant digits (<= 5e-7 s here)
        z, _, road_rate = exact.state(t_lift)
        slope = exact.kt * abs(road_rate - z[3])
        peak = exact.wheel_rest + np.max(np.abs(exact.wheel_and_force(bump_sweep.duration, bump_sweep.dt)[1]))
        dx = row.errors["wheel_pos"] * peak
        assert abs(printed - t_lift) <= 2 * exact.kt * dx / slope + 5e-7, (printed, t_lift)
        # which check, and by how much: the worst compared column against its tolerance
        worst = re.search(r"worst (\w+): max relative error ([0-9.e+-]+) (<=|>) ([0-9.e+-]+)\)$", row.detail)
        assert worst and float(worst.group(2)) == pytest.approx(row.errors[worst.group(1)], rel=5e-3)
    assert lifted >= 1 and passed >= 1  # both kinds of row are exercised


def test_a_row_outside_its_tolerance_names_each_column_with_error_and_tolerance():
    # explicit Euler at 20 ms on the 10 rad/s slider: first order, several per cent off the closed form
    result = springlab.sweep("slider", "free", vary={"damping": (5.0, 10.0, 2)}, integrator="euler", dt=0.02)
    for row in result.rows:
        single = springlab.run("slider", "free", integrator="euler", dt=0.02, damping=row.values["damping"])
        assert row.passed is False and single.passed is False
        assert row.detail.startswith("outside its tolerance: ")
        named = re.findall(r"(\w+): max relative error ([0-9.e+-]+) > tolerance ([0-9.e+-]+)", row.detail)
        assert named, row.detail
        for column, error, tolerance in named:
            assert float(error) == pytest.approx(row.errors[column], rel=5e-3)  # printed to 3 digits
            assert float(error) > float(tolerance) == pytest.approx(single.column_tolerances[column], rel=5e-3)
        # every column over its tolerance is named, and no other
        over = {c for c, e in single.errors.items() if e.max_rel > single.column_tolerances[c]}
        assert {c for c, _, _ in named} == over
