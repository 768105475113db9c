"""The wind's seeded load sequence: white noise of intensity S held over each step, as MuJoCo holds `ctrl`.

The motor `wind` (springlab.scenes.stay_cable.build) takes the load p [N/m]; a white load of intensity S
[N^2 s/m^2] (E[p(t) p(t + tau)] = S delta(tau)) held over steps of dt is the sequence p_k ~ N(0, S / dt), the
same low-frequency spectral density S (springlab.exact.random_vibration discretizes it exactly). Each seed draws
its own stream (numpy's PCG64 seeded with that seed alone), so a seed's sequence is the same whichever batch,
worker or order it runs in.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np

from springlab.errors import ParameterError


def wind_controls(intensity: float, dt: float, steps: int, seeds: Sequence[int]) -> np.ndarray:
    """(len(seeds), steps, 1) controls [N/m]: seed i's p_k ~ N(0, S / dt), k = 0 ... steps - 1.

    Parameters
    ----------
    intensity
        S [N^2 s/m^2], finite and >= 0.
    dt
        the step over which each sample is held [s], > 0.
    steps
        samples per seed.
    seeds
        one stream per seed (non-negative integers).

    Raises
    ------
    ParameterError
        an intensity that is not a finite number >= 0, dt not > 0, a negative seed.
    """
    intensity = float(intensity)
    if not (math.isfinite(intensity) and intensity >= 0.0):
        raise ParameterError(f"wind_intensity must be a finite number >= 0 N^2 s/m^2, got {intensity!r}")
    if not (math.isfinite(dt) and dt > 0.0):
        raise ParameterError(f"dt must be a finite number > 0 s, got {dt!r}")
    scale = math.sqrt(intensity / dt)
    out = np.empty((len(seeds), int(steps), 1))
    for row, seed in enumerate(seeds):
        if int(seed) != seed or seed < 0:
            raise ParameterError(f"seed must be a whole number >= 0, got {seed!r}")
        out[row, :, 0] = np.random.default_rng(int(seed)).standard_normal(int(steps)) * scale
    return out
