"""The settings kernel (springlab.studies.settings): one front, one order fit, one verified recommendation.

The claims: counted work is steps x evaluations per step x the model's work per evaluation; the Pareto front
holds exactly the valid runs no other valid run beats, and a diverged run or one beyond its stability limit is
never on it however cheap and accurate it looks; the observed order of an exact power law is its exponent;
the recommendation is the cheapest candidate whose verification passes, skipping one that fails, names the
settings that tie with it in counted work, and does not move when the timer returns noise.
"""

from __future__ import annotations

import math
import random

import mujoco
import numpy as np
import pytest

from springlab.studies import settings, tradeoff
from springlab.studies.settings import Run, Setting, Verification, cheapest_verified, pareto_front


def _run(integrator: str, dt: float, steps: int, error: float | None, **flags) -> Run:
    return Run(Setting(integrator, dt), steps, error, settings.counted_cost(integrator, steps), **flags)


def test_counted_work_is_steps_times_evaluations_times_the_models_work_per_evaluation():
    assert settings.counted_cost("rk4", 250) == 1000.0 and settings.counted_cost("euler", 250) == 250.0
    assert settings.counted_cost("implicitfast", 10, work=3.5) == 35.0
    spec = mujoco.MjSpec()
    for i in range(3):
        body = spec.worldbody.add_body(name=f"b{i}")
        body.add_joint(type=mujoco.mjtJoint.mjJNT_SLIDE, axis=[1, 0, 0])
        body.add_geom(size=[0.1, 0, 0])
    model = spec.compile()
    assert settings.work_per_evaluation(model) == 3.0  # three degrees of freedom
    model.opt.noslip_iterations = 5
    assert settings.work_per_evaluation(model) == pytest.approx(3.0 * (1 + 5 * settings.NOSLIP_ITERATION_WORK))


def test_the_front_holds_the_undominated_valid_runs_and_never_a_diverged_or_beyond_limit_one():
    rows = [
        _run("euler", 1.0, 8, 0.17, beyond_limit=True),  # the cheapest and accurate enough: past its limit
        _run("euler", 0.5, 16, None, diverged=True),
        _run("euler", 0.1, 80, 0.05),
        _run("euler", 0.05, 160, 0.06),  # dominated: dearer and less accurate than the run above
        _run("euler", 0.01, 800, 0.01),
        _run("rk4", 0.1, 80, 1e-4),  # 320 evaluations
        _run("rk4", 0.2, 40, 2e-3),  # 160 evaluations
        _run("implicit", 0.1, 80, 0.05),  # the same cost and error as euler at 0.1 s: the first listed stands
        _run("rk4", 0.01, 800, math.inf),  # an error that is no number: not a result
    ]
    front = pareto_front(rows)
    assert front == [rows[2], rows[6], rows[5]]
    assert [r.cost for r in front] == [80.0, 160.0, 320.0]
    valid = [r for r in rows if r.valid]
    for row in valid:  # exactly the valid rows no other valid row beats in both cost and error
        dominated = any(
            o.cost <= row.cost and (o.error or 0) <= (row.error or 0) and (o.cost, o.error) != (row.cost, row.error)
            for o in valid
        )
        assert (row in front) == (not dominated and row is not rows[7])


def test_the_observed_order_of_an_exact_power_law_is_its_exponent_without_round_off_or_saturated_points():
    # err = 50 dt^4 exactly, with a round-off plateau at the fine end and a saturated top
    runs = []
    for dt in np.geomspace(0.3, 1e-4, 15):
        steps = round(5.0 / dt)
        error = max(min(50 * dt**4, 0.9), 1e-13 * steps)
        runs.append(_run("rk4", float(dt), steps, float(error)))
    assert settings.observed_order(runs) == pytest.approx(4.0, abs=1e-9)
    assert settings.observed_order(runs[4:6]) is None  # two usable points claim no order


def test_the_order_fit_uses_the_finest_steps_and_refuses_errors_that_follow_no_power_law():
    dts = np.geomspace(0.03, 3e-5, 13)
    # second order at coarse steps, first as dt -> 0 (symplectic Euler: phase error vs bounded O(dt) error)
    mixed = [_run("euler", float(dt), round(1 / dt), float(40 * dt**2 + 0.4 * dt)) for dt in dts]
    assert settings.observed_order(mixed) == pytest.approx(1.0, abs=0.05)
    errors = [1e-2, 1e-3, 4e-4, 1e-5, 4e-5, 1e-4, 3e-6, 3e-8, 4e-6, 8e-7, 2e-7, 7e-9, 4e-8]
    scattered = [_run("rk4", float(dt), round(1 / dt), e) for dt, e in zip(dts, errors)]
    assert settings.observed_order(scattered) is None


def test_the_recommendation_skips_a_candidate_whose_verification_fails_and_never_tries_an_invalid_one():
    rows = [
        _run("euler", 1.0, 8, 1e-3, beyond_limit=True),  # cheapest, within tol: never a candidate
        _run("euler", 0.1, 80, 5e-3),  # the cheapest candidate: its verification fails
        _run("rk4", 0.2, 40, 8e-3),  # 160 evaluations
        _run("euler", 0.01, 800, 1e-3),
        _run("rk4", 0.1, 80, 0.5),  # outside tol
    ]
    tried = []

    def verify(row):
        tried.append(row)
        return Verification(row is not rows[1], 0.9 * row.error, time_s=1e-3)

    pick = cheapest_verified(rows, 1e-2, verify)
    assert tried == [rows[1], rows[2]]
    assert pick.found and pick.row is rows[2] and pick.setting == Setting("rk4", 0.2)
    assert pick.error == pytest.approx(0.9 * 8e-3) and pick.rejected == 1 and pick.cost == 160.0
    assert "rk4 at dt = 0.2 s" in pick.text and "1 cheaper candidate failed" in pick.text
    assert "160 DOF-evaluations" in pick.text
    none = cheapest_verified(rows, 1e-2, lambda row: Verification(False, None))
    assert not none.found and none.row is None and none.rejected == 3
    assert none.text.startswith("No setting of the sweep meets tol 0.01")


def test_ties_in_counted_work_go_to_the_more_accurate_then_the_first_listed_and_are_named():
    rows = [
        _run("euler", 0.1, 80, 4e-3),
        _run("implicit", 0.1, 80, 2e-3),  # the same work, more accurate: chosen
        _run("implicitfast", 0.1, 80, 2e-3),  # equal in both: listed after implicit
        _run("euler", 0.09, 90, 1e-3),  # within TIMING_NOISE of the pick's work: named as near
        _run("euler", 0.05, 160, 1e-4),  # twice the work: neither
    ]
    pick = cheapest_verified(rows, 1e-2, lambda row: Verification(True, row.run.error))
    assert pick.row is rows[1]
    assert pick.ties == (Setting("implicitfast", 0.1), Setting("euler", 0.1))
    assert pick.near == (Setting("euler", 0.09),)
    assert "ties in counted work with implicitfast at dt = 0.1 s; euler at dt = 0.1 s" in pick.text
    assert "Within 1.25x of its counted work: euler at dt = 0.09 s" in pick.text
    # the order the rows come in decides only between rows equal in cost and error
    again = cheapest_verified(rows[::-1], 1e-2, lambda row: Verification(True, row.run.error))
    assert again.row is rows[2] and again.setting == Setting("implicitfast", 0.1)


def test_the_tradeoffs_recommendation_does_not_move_when_the_timer_returns_noise(monkeypatch):
    def sweep_and_pick():
        sweep = tradeoff.sweep("slider", "free", duration=1.0, integrators=("euler", "implicit", "rk4"))
        return sweep, tradeoff.recommend(sweep, 1e-4, timing_repeats=1)

    noise = random.Random(1)
    monkeypatch.setattr(tradeoff, "time_run", lambda job, **options: noise.uniform(1e-6, 1.0))
    first_sweep, first = sweep_and_pick()
    second_sweep, second = sweep_and_pick()
    assert first.found and (first.integrator, first.dt, first.error) == (second.integrator, second.dt, second.error)
    assert first.text == second.text and first.ties == second.ties and first.near == second.near
    assert [r.run.setting for r in first_sweep.pareto] == [r.run.setting for r in second_sweep.pareto]
    # the noise reached the measured times: they differ, the answer does not
    assert [r.wall_time_s for r in first_sweep.runs] != [r.wall_time_s for r in second_sweep.runs]
