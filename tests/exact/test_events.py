"""Events between samples (springlab.exact.events): excursions and band exits of the cubic Hermite
interpolant, against a damped cosine whose peaks and crossings are known in closed form."""

import math

import numpy as np
import pytest

from springlab.exact import events

OMEGA, SIGMA = 2 * math.pi * 50.0, 3.0  # a 50 Hz vibration decaying at 3 /s


def _signal(t):
    """y = e^(-sigma t) cos(omega t) and its derivative: peaks near t = j pi / omega."""
    e = np.exp(-SIGMA * t)
    return e * np.cos(OMEGA * t), -e * (SIGMA * np.cos(OMEGA * t) + OMEGA * np.sin(OMEGA * t))


def _exact_exit(level, lo, hi):
    """The exit of |y| from `level` between the extremum lo and the next one hi [s], by bisection."""
    y_lo = _signal(lo)[0]
    sign = math.copysign(1.0, y_lo)
    for _ in range(200):
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if sign * _signal(mid)[0] > level else (lo, mid)
    return lo


def _peak_time(j):
    """The j-th extremum of y: omega t = j pi - atan(sigma / omega)."""
    return (j * math.pi - math.atan(SIGMA / OMEGA)) / OMEGA


def test_hermite_peaks_are_fourth_order_between_samples():
    # one interval straddling the 3rd extremum, its centre at the peak: the samples read low by
    # about (omega h)^2 / 8, the interpolant's peak by O(h^4)
    errors = []
    for h in (0.1 / OMEGA, 0.05 / OMEGA):
        t_peak = _peak_time(3)
        t0, t1 = t_peak - 0.3 * h, t_peak + 0.7 * h
        (y0, y1), (dy0, dy1) = _signal(np.array([t0, t1]))
        peak, interior = events.hermite_peaks(h, np.array(y0), np.array(y1), np.array(dy0), np.array(dy1))
        exact = abs(_signal(t_peak)[0])
        assert max(abs(y0), abs(y1)) < exact * (1 - (OMEGA * h) ** 2 / 8 * 0.3)  # the samples miss it
        assert float(interior) < 0  # the 3rd extremum is a minimum, and the sign is kept
        errors.append(abs(float(peak) - exact))
    # cubic Hermite: |y - H| <= h^4 / 384 max|y''''|, and halving h divides the error by about 16
    assert errors[0] <= (0.1) ** 4 / 384 * 1.01 * abs(_signal(_peak_time(3) - 0.1 / OMEGA)[0])
    assert 8 <= errors[0] / errors[1] <= 32


def test_last_exit_finds_a_peak_that_crosses_the_band_between_samples():
    h = 0.1 / OMEGA
    j = 40  # a level just under the 40th peak, the last above it: outside only between samples
    level = abs(_signal(_peak_time(j))[0]) * (1 - 2e-4)
    # the sample grid shifted so that the peak falls mid-interval
    time = np.arange(0.0, 0.5, h) + _peak_time(j) - (math.floor(_peak_time(j) / h) + 0.5) * h
    y, dy = _signal(time)
    assert np.all(np.abs(y[time > _peak_time(j) - h]) <= level)  # every sample around it inside
    exact = _exact_exit(level, _peak_time(j), _peak_time(j + 1))
    found = events.last_exit(time, y, dy, level)
    # the interpolant is within h^4/384 |y''''| of y; the exit moves by that over the slope there
    slope = abs(_signal(exact)[1])
    bound = h**4 / 384 * OMEGA**4 * 1.01 * math.exp(-SIGMA * _peak_time(j))
    assert abs(found - exact) <= bound / slope
    # read at the samples the last exit is a whole half period earlier
    outside = np.flatnonzero(np.abs(y) > level)
    assert time[outside[-1]] < exact - 0.4 * math.pi / OMEGA


def test_last_exit_at_the_record_ends():
    h = 0.05 / OMEGA
    time = np.arange(0.0, 0.004, h)  # y from 1 down to cos(0.4 pi) = 0.31: one exit from 0.5
    y, dy = _signal(time)
    assert events.last_exit(time, 0.1 * y, 0.1 * dy, 0.5) == time[0]  # never outside
    exact = _exact_exit(0.5, 0.0, _peak_time(1))
    slope = abs(_signal(exact)[1])
    assert events.last_exit(time, y, dy, 0.5) == pytest.approx(exact, abs=h**4 / 384 * OMEGA**4 / slope)
    assert events.last_exit(time[:2], y[:2], dy[:2], 0.5) == time[1]  # ends outside


def test_band_exit_takes_the_sign_of_the_latest_excursion():
    # from +2 down through a minimum at -1.8 and back to -0.5 in one interval: the exit is from -1
    t = np.array([0.0, 1.0])
    y0, y1, dy0, dy1 = 2.0, -0.5, -14.0, 6.0
    exit_time = events.band_exit(t[0], t[1], y0, y1, dy0, dy1, 1.0)
    assert events.hermite_value(0.0, 1.0, y0, y1, dy0, dy1, exit_time) == pytest.approx(-1.0, abs=1e-12)
    after = np.linspace(exit_time + 1e-9, 1.0, 50)
    assert all(abs(events.hermite_value(0.0, 1.0, y0, y1, dy0, dy1, s)) <= 1.0 for s in after)
