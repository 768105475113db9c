"""Where MuJoCo's one-step map of a model at its operating point starts to grow, per integrator: the
measured stability limit, and the map's growth and most unstable direction just above it.

Numerical instability, as measured here: at timestep dt the one-step map Phi(dt) (springlab.exact.linearize)
amplifies some mode more than the exact flow does, spectral radius
rho(Phi) > (1 + MAP_MARGIN) max(1, exp(sigma dt)), with sigma the largest growth rate of the
continuous linearization (0 unless the model is physically unstable: an upright pole *should* fall,
and that is no integrator's fault). MAP_MARGIN covers the finite differences: a Jordan block's
double eigenvalue 1 (a free body, an unsprung direction) moves by sqrt(error) ~ 1e-5.

The measured limit is the smallest such dt: a doubling scan from SCAN_START / |lambda|_max, then a
geometric bisection to a ratio of 1 + LIMIT_PRECISION. A predicted limit (a closed form from the modes,
springlab.exact.predicted_limits) seeds the measurement: it is tried first as a bracket.

`map_limit` gives one integrator's `MapLimit`: the measured limit and, a given factor above it, the map's
growth, its eigenvalue's size and eigenvector (what a run just above the limit is perturbed along to confirm it).
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np

from springlab.exact.model_at_point import ModelAtPoint

#: growth of the one-step map beyond the exact flow's that counts as numerical instability [-]
MAP_MARGIN = 1e-4
#: the scan starts at SCAN_START / |lambda|_max and doubles ...
SCAN_START = 0.01
#: ... up to SCAN_STOP / |lambda|_max (or the stop given, a run's duration) [s]
SCAN_STOP = 1e4
#: bisection down to this ratio between stable and unstable timesteps
LIMIT_PRECISION = 1e-4
#: a predicted limit p is first bracketed by [p / GUESS_BRACKET, p * GUESS_BRACKET]
GUESS_BRACKET = 1.01


@dataclasses.dataclass(frozen=True, eq=False)
class MapLimit:
    """One integrator's measured one-step-map limit at the operating point, and the map just above it.

    Attributes
    ----------
    integrator
        name.
    limit_s
        the smallest dt at which the map grows (module docstring) [s] (None: stable over the whole scan).
    above_s
        the timestep the map was read at above the limit [s] (None without a limit).
    growth_above
        there, max |mu| / the exact growth of its mode [-] (inf: the map is not finite there).
    size_above
        that eigenvalue's |mu| [-].
    direction_above
        its eigenvector (n,) in the tangent space, complex (None: the map is not finite there, or empty).
    """

    integrator: str
    limit_s: float | None
    above_s: float | None = None
    growth_above: float | None = None
    size_above: float | None = None
    direction_above: np.ndarray | None = None


class _MapProbe:
    """rho(Phi(dt)) relative to the exact flow's growth, per dt [s], for one integrator.

    For a physically stable model the exact flow grows nowhere, so the excess is rho(Phi) itself.
    With a physically unstable mode each eigenvalue mu of Phi is compared with exp(lambda dt) of the
    continuous mode its eigenvector lies along (largest coefficient in A's eigenvector basis), so an
    upright pole's fall does not hide a fast mode's numerical growth.
    """

    def __init__(self, at: ModelAtPoint, integrator: str):
        linear = at.linear
        self.maps = at.step_maps(integrator, at.workspace)  # one copy of the model for every map at this point
        self.basis = None
        if linear.physically_unstable:
            values, vectors = linear.eigenvectors
            self.rates = np.maximum(values.real, 0.0)
            self.basis = np.linalg.pinv(vectors)

    def excess(self, dt: float) -> tuple[float, np.ndarray | None, float]:
        """(max |mu| / exact growth of its mode [-], that mu's eigenvector, that |mu| [-]); the first > 1 +
        MAP_MARGIN is numerical growth."""
        phi = self.maps(dt)
        if not np.isfinite(phi).all():
            return math.inf, None, math.inf
        if not phi.size:
            return 0.0, None, 0.0
        values, vectors = np.linalg.eig(phi)
        if self.basis is None:
            ratios = np.abs(values)
        else:
            modes = np.argmax(np.abs(self.basis @ vectors), axis=0)
            ratios = np.abs(values) * np.exp(-self.rates[modes] * dt)  # no overflow for fast physical growth
        worst = int(np.argmax(ratios))
        return float(ratios[worst]), vectors[:, worst], float(np.abs(values[worst]))

    def unstable(self, dt: float) -> bool:
        return self.excess(dt)[0] > 1 + MAP_MARGIN


def map_limit(
    at: ModelAtPoint, integrator: str, stop_s: float, guess_s: float | None = None, above: float = 1.0
) -> MapLimit:
    """`integrator`'s measured limit at the point (`measured_limit`), and the map at `above` x it [-].

    Parameters
    ----------
    at
        the model at its operating point.
    integrator
        MuJoCo integrator name.
    stop_s
        the largest dt worth scanning [s] (a run's duration).
    guess_s
        a predicted limit [s] (None: none), tried first as a bracket.
    above
        where the map is read above a found limit, as a multiple of it [-].
    """
    fastest = at.linear.fastest
    scale = 1.0 / fastest.rate_rad_s if fastest is not None else float(at.model.opt.timestep)
    probe = _MapProbe(at, integrator)
    limit = measured_limit(probe, scale, stop_s, guess_s)
    if limit is None:
        return MapLimit(integrator, None)
    growth, vector, size = probe.excess(above * limit)
    return MapLimit(integrator, limit, above * limit, growth, size, vector)


def measured_limit(probe: _MapProbe, scale_s: float, stop_s: float, guess_s: float | None = None) -> float | None:
    """The smallest dt [s] at which the probe's one-step map grows (module docstring), or None.

    scale_s: the model's fastest time scale 1/|lambda|_max [s] (or its own timestep without a mode);
    stop_s: the largest dt worth scanning [s] (a run's duration); guess_s: a predicted limit [s], tried
    first as a bracket [guess / GUESS_BRACKET, guess * GUESS_BRACKET] (it only saves map evaluations: a
    wrong guess falls back to the doubling scan from its stable side).
    """
    stop = min(SCAN_STOP * scale_s, stop_s)
    low, high = 0.0, None
    if guess_s is not None and GUESS_BRACKET * guess_s < stop:
        # a good prediction brackets the limit in two maps; a wrong one only costs those two
        below, above = guess_s / GUESS_BRACKET, min(guess_s * GUESS_BRACKET, stop)
        if probe.unstable(below):
            high = below
        elif probe.unstable(above):
            low, high = below, above
        else:
            low = above
    if high is None:
        dt = min(2 * low if low else SCAN_START * scale_s, stop)
        while not probe.unstable(dt):
            if dt >= stop:
                return None
            low, dt = dt, min(2 * dt, stop)
        high = dt
    if low == 0.0:  # unstable at the first probe: go down
        floor = 1e-6 * high
        while high > floor and probe.unstable(high / 2):
            high /= 2
        low = high / 2
    while high / low > 1 + LIMIT_PRECISION:
        mid = math.sqrt(low * high)
        low, high = (low, mid) if probe.unstable(mid) else (mid, high)
    return math.sqrt(low * high)
