"""springlab.exact.resonance.accelerance_response against the same ZOH map stepped in extended precision.

The reference runs x_{k+1} = Phi x_k + Gamma F_k, y_k = C x_k step by step in numpy's longdouble (64-bit mantissa on
x86-64), from the exponential computed here with scipy.linalg.expm; the blocked response sums at most
RESPONSE_BLOCK terms per sample plus the carried state, so each sample is within a few B eps of the l1 size of the
response (sum |C Phi^m Gamma| max |F|). The transfer-function form it replaced (scipy.signal.ss2tf and lfilter)
agrees within its own, larger, round-off.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
import scipy.linalg
import scipy.signal

from springlab.exact import resonance

EPS = float(np.finfo(float).eps)
LONG_EPS = float(np.finfo(np.longdouble).eps)


def _map(omega, zeta, inverse_mass, dt):
    a = np.array([[0.0, 1.0], [-(omega**2), -2 * zeta * omega]])
    block = np.zeros((3, 3))
    block[:2, :2], block[1, 2] = a * dt, -inverse_mass * dt
    step = scipy.linalg.expm(block)
    return step[:2, :2], step[:2, 2], np.array([-(omega**2), -2 * zeta * omega])


def _stepped(force, every, phi, gamma, c):
    """(y at steps 0, every, ... in longdouble, sum_m |C Phi^m Gamma| over the record)."""
    p, g, row = (np.asarray(v, np.longdouble) for v in (phi, gamma, c))
    x = np.zeros(2, np.longdouble)
    impulse = g.copy()
    out, gain = [], 0.0
    for k, f in enumerate(force):
        if k % every == 0:
            out.append(row @ x)
        x = p @ x + g * np.longdouble(f)
        gain += abs(float(row @ impulse))
        impulse = p @ impulse
    return np.array(out, np.longdouble), gain


@pytest.mark.parametrize(
    "dt, every, steps, hz, zeta",
    [
        (1e-4, 3, 20000, 120.0, 0.03),
        (2e-4, 2, 9001, 80.0, 0.005),
        (1e-4, 1, 777, 80.0, 0.1),
        (1e-4, 7, 12345, 140.0, 0.2),
    ],
)
def test_the_blocked_response_is_the_zoh_map_stepped_in_extended_precision(dt, every, steps, hz, zeta):
    omega, inverse_mass = 2 * math.pi * hz, 0.7
    force = resonance.chirp(1.0, 50.0, 400.0, steps * dt, dt)
    response = resonance.accelerance_response(force, dt, every, omega, zeta, inverse_mass)
    phi, gamma, c = _map(omega, zeta, inverse_mass, dt)
    reference, gain = _stepped(force, every, phi, gamma, c)
    assert response.shape == reference.shape == (-(-steps // every),)
    size = gain * float(np.max(np.abs(force)))
    # ours: sums of at most B terms and a carried state (a few B eps); the reference's own rounding, steps long
    tolerance = 4 * resonance.RESPONSE_BLOCK * EPS * size + 4 * steps * LONG_EPS * size
    assert float(np.max(np.abs(response - reference))) <= tolerance
    # the transfer-function form: the same map, its recursion's round-off growing along the record
    num, den = scipy.signal.ss2tf(phi, gamma[:, None], c[None, :], np.zeros((1, 1)))
    filtered = scipy.signal.lfilter(num[0], den, force)[::every]
    assert float(np.max(np.abs(filtered - response))) <= 4 * steps * EPS * size
