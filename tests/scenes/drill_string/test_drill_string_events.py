"""One definition per event (issue 34 item 2): the drill string's re-stick and breakaway are the same events in
the run's quantities, its checks and its figure, whatever the number of elements.

The re-stick is the bit, after breaking free, slowing below RESTICK_FRACTION of the top drive's speed; the
breakaway is the string's torque on the stuck bit reaching its friction torque. Here each figure mark is found
again in the quantities and the checks, and at one element (a rotor pulled through one spring, the textbook's
driven stick-slip oscillator) the exact slip is checked against its two-body closed form: the bit's speed falls
back to (nearly) zero about one natural period after the breakaway, below the threshold, and `sticks_again`
says so.
"""

from __future__ import annotations

import math
import re

import pytest
import scipy.optimize

from springlab.runs.run import run_scenario
from springlab.scenes.drill_string import answers

_RUNS: dict = {}


def _breakaway(n: int):
    """The breakaway run at n elements (computed once per process: results are immutable)."""
    if n not in _RUNS:
        _RUNS[n] = run_scenario("drill_string", "breakaway", n_elements=n)
    return _RUNS[n]


@pytest.mark.slow
@pytest.mark.parametrize("n", [1, 32])
def test_the_restick_is_one_event_in_the_quantities_the_checks_and_the_figure(n, scenario_run):
    # at the scene's own 32 elements, the session's run of the scenario (tests/conftest.py)
    breakaway = scenario_run("drill_string", "breakaway") if n == 32 else _breakaway(n)
    assert breakaway.parameters["n_elements"] == n
    q = breakaway.quantities
    checks = {c.name: c for c in breakaway.checks}
    assert q["sticks_again"] is math.isfinite(q["restick_time_s_exact"]) is True
    assert checks["restick_time_s"].reference == q["restick_time_s_exact"]
    assert checks["breakaway_time_s"].reference == q["breakaway_time_s_exact"]
    assert q["restick_speed_rad_s"] == answers.RESTICK_FRACTION * q["top_speed_rad_s"]
    speeds, _ = breakaway.case.scene.figure(breakaway.case, breakaway.trajectory)
    marks = {label.split(" ")[0]: t for t, label in speeds.marks}
    assert marks == {"breakaway": q["breakaway_time_s_exact"], "re-stick": q["restick_time_s_exact"]}
    # and the label states the threshold it uses
    level = [label for _, label in speeds.marks if label.startswith("re-stick")][0]
    assert float(re.search(r"below ([\d.]+) rpm", level).group(1)) == pytest.approx(
        answers.RESTICK_FRACTION * q["top_speed_rad_s"] * 60 / (2 * math.pi), rel=0.05
    )


@pytest.mark.slow
def test_one_element_slips_as_the_two_body_closed_form_says():
    breakaway = _breakaway(1)
    q = breakaway.quantities
    lumped = answers.lumped_of(breakaway.case)
    assert breakaway.model.nv == 2
    # top drive m0 and bit J on one spring k, friction T_f at the bit. While the bit is stuck the top is a
    # mass on the spring: q0'' + nu^2 q0 = alpha (the drive's torque alpha m0) until the ramp ends, then 0,
    # nu^2 = k / m0. It breaks free when k q0 = T_f. Slipping: momentum P = m0 v0 - T_f s; the stretch
    # r = q0 - q1 oscillates at w^2 = k (1/m0 + 1/J) about r_eq = T_f / (J w^2); the bit turns at (P - m0 r') / (m0 + J)
    m0, bit_inertia, k = float(lumped.mass[0]), float(lumped.mass[-1]), float(lumped.stiffness[-1, -1])
    friction, omega, ramp = lumped.friction, q["top_speed_rad_s"], q["spin_up_time_realized_s"]
    alpha, nu = omega / ramp, math.sqrt(k / m0)
    # written without 1 - cos (the drive's inertia is huge: nu ramp ~ 1e-4, so 1 - cos would lose 8 digits)
    q_ramp = 2 * alpha * (math.sin(nu * ramp / 2) / nu) ** 2
    v_ramp = alpha / nu * math.sin(nu * ramp)

    def top(t: float) -> tuple[float, float]:  # the top's angle and speed while the bit is stuck, after the ramp
        s = t - ramp
        return (
            q_ramp * math.cos(nu * s) + v_ramp / nu * math.sin(nu * s),
            -q_ramp * nu * math.sin(nu * s) + v_ramp * math.cos(nu * s),
        )

    assert k * q_ramp < friction  # still stuck when the ramp ends
    t_b = scipy.optimize.brentq(lambda t: k * top(t)[0] - friction, ramp, ramp + 0.5 * math.pi / nu, xtol=1e-15)
    r0, v0 = top(t_b)
    w = math.sqrt(k * (1 / m0 + 1 / bit_inertia))
    r_eq = friction / (bit_inertia * w**2)

    def bit_speed(s: float) -> float:
        slower = 2 * v0 * math.sin(w * s / 2) ** 2 + (r0 - r_eq) * w * math.sin(w * s)  # v0 - r', no cancellation
        return (m0 * slower - friction * s) / (m0 + bit_inertia)

    period = 2 * math.pi / w
    level = answers.RESTICK_FRACTION * omega
    # it rises from 0, peaks near half a period, and falls below the level near the end of the period
    restick = scipy.optimize.brentq(lambda s: bit_speed(s) - level, 0.5 * period, period, xtol=1e-15)
    peak = scipy.optimize.minimize_scalar(
        lambda s: -bit_speed(s), bounds=(0.25 * period, 0.75 * period), method="bounded", options={"xatol": 1e-12}
    )
    assert q["breakaway_time_s_exact"] == pytest.approx(t_b, abs=1e-11)
    # the twist as it breaks free is the top's angle (the bit still at 0): T_f / k
    assert q["windup_turns_exact"] == pytest.approx(r0 / (2 * math.pi), rel=1e-12)
    # the exact values are roots found to about 1e-13 s (answers' EVENT_ROOT_ERROR) on a two-segment solution
    assert q["restick_time_s_exact"] == pytest.approx(t_b + restick, abs=1e-11)
    assert q["peak_bit_speed_rad_s_exact"] == pytest.approx(-peak.fun, rel=1e-12)
