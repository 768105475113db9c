"""The drill string's exact side computed the short way is the long way's answer.

* The continuum's peak speed of the start-up, searched only on the steps the series' slope bound leaves open,
  against the series evaluated on every step (with its angle: the other code path) and refined the same way.
* The slope bound itself against the series' largest difference quotient on a grid 10 times finer than the run's.
* The series' sums of sines and cosines on a run's grid by angle addition (`continuum._trig_sums`) against the
  sines taken directly, within the round-off both carry.
* The delay equation's history read in floats (`continuum._history`) against scipy's own OdeSolution of the same
  DOP853 solve: the same bits at every point, the steps' ends included.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
import scipy.integrate
import scipy.optimize

from springlab.scenes.drill_string import answers, continuum

#: the shipped rod (5 in drill pipe, steel, 1000 m, a 100 kg m^2 BHA)
ROD = continuum.Rod(1000.0, 79.3e9, 7850.0, math.pi * (0.127**4 - 0.10861**4) / 32, 100.0)
DT = 2e-3


def _drive(speed: float, ramp: float) -> answers.Drive:
    steps = round(ramp / DT)
    return answers.Drive(speed, steps * DT, speed / (steps * DT), steps)


def _series(time: np.ndarray, drive: answers.Drive) -> np.ndarray:
    _, speed = ROD.modal_spin_up(time, ROD.length, drive.acceleration, drive.ramp_time, answers.CONTINUUM_MODES)
    return np.abs(speed)


@pytest.mark.parametrize("speed, ramp, steps", [(2 * math.pi, 2.0, 5000), (4.0, 0.3, 3000)])
def test_the_continuum_peak_is_the_series_largest_on_every_step_refined(speed, ramp, steps):
    drive = _drive(speed, ramp)
    time = np.arange(steps + 1) * DT  # a coarse grid of every third (every second) step, as spin_up's
    values = _series(time, drive)  # every step, angle and all
    i = int(np.argmax(values))
    found = scipy.optimize.minimize_scalar(
        lambda s: -float(_series(np.array([s]), drive)[0]),
        bounds=(time[max(i - 1, 0)], time[min(i + 1, len(time) - 1)]),
        method="bounded",
        options={"xatol": 1e-13},
    )
    brute = max(float(values[i]), float(-found.fun))
    # the same maximum of the same series; the two evaluations sum the modes in other blocks (round-off of the
    # 4096-term sum, a few eps times the sum of its terms' sizes, below 1e-13 of the peak)
    assert answers._continuum_peak(ROD, drive, time) == pytest.approx(brute, rel=1e-13, abs=0)


def test_the_slope_bound_holds_the_series_steepest_difference_quotient():
    drive = _drive(2 * math.pi, 0.3)  # a short ramp: the steepest fronts
    fine = np.arange(10 * 1000 + 1) * (DT / 10)  # 2 s (past the first reflections) at a tenth of the run's step
    _, w = ROD.modal_spin_up(fine, ROD.length, drive.acceleration, drive.ramp_time, answers.CONTINUUM_MODES)
    steepest = float(np.max(np.abs(np.diff(w)) / np.diff(fine)))
    # a difference quotient is a mean of w' over its interval: never above the bound of |w'|
    assert steepest <= answers._slope_bound(ROD, drive)


@pytest.mark.parametrize("steps, jitter", [(5000, 0.0), (1666, 0.0), (3000, 1e-7)])
def test_the_sums_by_angle_addition_are_the_direct_sines(steps, jitter):
    # a run's times: dt added step by step (uniform but for round-off), or a grid jittered past the addition's range
    rng = np.random.default_rng(steps)
    time = np.cumsum(np.full(steps + 1, DT)) - DT + jitter * rng.standard_normal(steps + 1)
    w = ROD.frequencies(answers.CONTINUUM_MODES)
    vectors = [rng.standard_normal(len(w)) / np.arange(1, len(w) + 1) ** 2, rng.standard_normal(len(w))]
    sines, cosines = continuum._trig_sums(time, w, vectors, vectors)
    phase = np.outer(time, w)
    eps = np.finfo(float).eps
    for v, by_addition, direct in zip(
        vectors * 2, sines + cosines, [np.sin(phase) @ v for v in vectors] + [np.cos(phase) @ v for v in vectors]
    ):
        # each term: its phase w t rounded to eps of itself either way (w t_i + w D_j and w delta_k here), the
        # products of the addition a few eps; each sum of N terms within N eps of the sum of the terms' sizes
        terms = np.abs(v) * (4 * eps * np.abs(w) * np.max(np.abs(time)) + 8 * eps)
        tolerance = float(np.sum(terms)) + 2 * len(w) * eps * float(np.sum(np.abs(v)))
        assert np.max(np.abs(by_addition - direct)) <= tolerance


def test_the_history_read_in_floats_is_scipys_dense_output_bit_for_bit():
    def rate(t: float, y: np.ndarray) -> np.ndarray:  # a smooth, kinked-free stand-in for the bit's equation
        return np.array([math.cos(3.0 * t) - 0.7 * y[0]])

    found = scipy.integrate.solve_ivp(rate, (0.25, 6.0), [0.4], method="DOP853", rtol=1e-12, dense_output=True)
    fast = continuum._history(found.sol)
    assert isinstance(fast, continuum._DenseSpeed)
    points = np.concatenate([found.t, np.linspace(0.25, 6.0, 997), 0.5 * (found.t[1:] + found.t[:-1])])
    for t in points:
        assert fast(float(t)) == float(found.sol(float(t))[0]), t
