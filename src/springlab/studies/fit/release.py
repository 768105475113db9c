"""Where the motion in a record starts: a held start is found only when the data show it beyond their noise.

A record may begin before the release (the joint held still, then let go) or at it (a release from rest at
the first sample, or a record started in mid-motion). A release from rest leaves the first samples close to
their level for a while in either case: the motion departs quadratically. A band rule ("the first samples
within 5 noise levels are held") therefore calls the start of every noisy release from rest a hold; the fit
then starts later, and its x0, v0 describe a later moment than the record's start.

So the decision is a change-point test between two models of the record's beginning, both the scene's own
closed form (springlab.studies.fit.models), fitted by least squares:

* H0, moving from the first sample: the closed form from the record's start with the fit's free names;
* H1(tau), held until tau, then released: the joint at rest before tau (the position it is released from,
  or zero velocity and acceleration plus the sensor offset), the closed form from tau on.

H1(tau) with tau at the first sample is H0. The statistic is the largest drop of the residual sum of squares
a hold gives over the candidate release times, in units of H1's own noise estimate:
F = max_tau (RSS_H0 - RSS_H1(tau)) / (RSS_H1(tau) / dof), both models linearised about the H0 estimate
(exactly so in x0, v0 and the offset, which enter linearly). Its false-alarm threshold is the
(1 - FALSE_ALARM) quantile of the same statistic on H0's fitted signal plus noise of H0's residual level
(a parametric bootstrap: DRAWS draws of a generator with a fixed seed, the same linearised models): a
record moving from its first sample is called held at the rate FALSE_ALARM (measured: 1 to 3 false holds in
200 records of each kind in docs/fit.md, p-values uniform within their scatter). The candidates tau run from the
MIN_HELD-th sample to the first sample BAND noise levels off the first samples' level (the motion is
surely under way there); the test looks at the record up to WINDOW_PERIODS periods of the motion's fastest
mode after that point (the whole record for a polynomial), every k-th sample of it when it is longer than
MAX_POINTS.

When the hold is shown, the fit starts at the first sample after the estimated release that is BAND noise
levels off the held level: surely after the release, and the initial state there is fitted, so the unknown
moment of the release between samples biases nothing.
"""

from __future__ import annotations

import dataclasses
import functools
import math
from typing import Any

import numpy as np

from springlab.errors import SpringlabError

from . import data as fit_data
from . import reductions
from .data import Record
from .models import FitModel

#: rate of false holds the threshold allows on a record that moves from its first sample [-]
FALSE_ALARM = 0.01
#: pure-noise draws that calibrate the threshold, and their generator's seed (fixed: the same decision every time)
DRAWS = 1000
SEED = 20260526
#: noise levels off a level that mark a sample as moving [-] (a false mark has probability 6e-7 per sample)
BAND = 5.0
#: fewest samples a hold must have to be considered
MIN_HELD = 3
#: periods of the fastest mode the test looks at after the motion is surely under way
WINDOW_PERIODS = 2.0
#: most samples the test looks at (longer windows are read every k-th sample), and most candidate release times
MAX_POINTS = 600
MAX_CANDIDATES = 200
#: names that enter the response linearly (exact linearisation)
LINEAR = ("x0", "v0", "offset", "a0", "jerk")


@dataclasses.dataclass(frozen=True)
class Release:
    """What the fit decided about the start of the motion, and why (fit.json's `release`).

    Attributes
    ----------
    decision
        'held' (a hold before the release was shown and dropped), 'moving' (the record moves from its first
        sample), 'given' (`start` was given), 'not tested' (a fitted delay models the hold).
    start_s
        Time [s] the fit starts at (the model's t = 0), on the record's clock.
    release_s
        The estimated moment of the release [s] (held only; None otherwise).
    statistic
        F, the largest drop of the residual sum of squares a hold gives, in H1's noise variances [-] (None untested).
    threshold
        F's (1 - false_alarm) quantile for records moving from the first sample like this one [-].
    false_alarm
        The test's rate of false holds [-].
    noise
        The record's noise level sigma [signal unit] the test used.
    held_samples
        Samples before the release (held) or before `start` (given).
    reason
        The one line the terminal prints.
    """

    decision: str
    start_s: float
    release_s: float | None = None
    statistic: float | None = None
    threshold: float | None = None
    false_alarm: float = FALSE_ALARM
    noise: float | None = None
    held_samples: int = 0
    reason: str = ""

    def to_dict(self) -> dict[str, Any]:
        """fit.json's `release`: decision, start_s, release_s, statistic, threshold, false_alarm, noise,
        held_samples, reason."""
        return dataclasses.asdict(self)


def decide(
    how: FitModel,
    record: Record,
    base: dict[str, float],
    fixed: dict[str, float],
    free: list[str],
    force: float,
    *,
    given: float | None,
    delay: bool,
) -> tuple[Record, Release]:
    """The record the fit uses (a shown hold dropped) and the decision.

    Parameters
    ----------
    how
        The scene's fit model.
    record
        The loaded record (already cut at `given` when a start was given).
    base
        The scene's parameters (SI).
    fixed
        Fit names given values (x0 [m], v0 [m/s], offset, ...).
    free
        The fit's free names.
    force
        The scenario's step force [N] (0 for a free decay).
    given
        The start [s] the user gave, or None.
    delay
        Whether a delay is fitted (it models the hold itself: nothing is tested).
    """
    if given is not None:
        why = f"start given at t = {given:.6g} s: {record.dropped_before_start} earlier sample(s) left out, not tested"
        return record, Release("given", float(given), held_samples=record.dropped_before_start, reason=why)
    if delay:
        why = "not tested: the fitted delay models a held start itself"
        return record, Release("not tested", record.origin, reason=why)
    found = held_start(how, record, base, fixed, free, force)
    if found.decision != "held":
        return record, found
    return fit_data.cut_at_release(record, found.start_s), found


def held_start(
    how: FitModel, record: Record, base: dict[str, float], fixed: dict[str, float], free: list[str], force: float
) -> Release:
    """The change-point test of the module docstring on a record that starts at its first sample."""
    y = record.values
    t0 = float(record.time[0])
    span = float(np.ptp(y))
    sigma = max(fit_data.noise_level(y), 1e-9 * span)
    unit = "" if record.unit == "-" else f" {record.unit}"
    first = f"moving from the first sample (t = {t0:.6g} s)"
    if span == 0:
        return Release("moving", t0, noise=sigma, reason=f"{first}: the signal never changes")
    level = float(np.median(y[:5]))
    off = _first_off(y, level, BAND * sigma)
    if off is None or off < MIN_HELD:
        band = f"the band of {BAND:g} noise levels around its first level"
        why = (
            f"{first}: it leaves {band} within {off + 1} sample(s)"
            if off is not None
            else f"{first}: it never leaves {band}"
        )
        return Release("moving", t0, noise=sigma, reason=why)
    exit_ = off
    names = [n for n in free if n != "delay"]
    for name in ("x0", "v0"):  # the test needs the motion's own state at the start, unless the user gave it
        if name in how.units() and name not in names and name not in fixed:
            names.append(name)
    try:
        with np.errstate(all="ignore"):  # trial parameters far off may overflow the closed form: rejected, not shown
            statistic, threshold, release_index = _change_point(
                _Window(how, record, base, fixed, names, force, sigma, exit_)
            )
    except (SpringlabError, ValueError, ArithmeticError, np.linalg.LinAlgError) as error:
        return Release("moving", t0, noise=sigma, reason=f"{first}: a held start could not be tested ({error})")
    held = statistic > threshold
    odds = f"change statistic {statistic:.3g} {'above' if held else 'below'} {threshold:.3g}"
    rate = f"the {100 * FALSE_ALARM:g} % false-alarm level for noise {sigma:.3g}{unit}"
    if not held:
        why = f"{first}: a held start explains the first {exit_} samples no better than the motion ({odds}, {rate})"
        return Release("moving", t0, statistic=statistic, threshold=threshold, noise=sigma, reason=why)
    held_level = float(np.mean(y[:release_index]))
    after = _first_off(y, held_level, BAND * sigma, release_index)
    start_index = after if after is not None else exit_
    release = float(record.time[release_index])
    start = float(record.time[start_index])
    why = (
        f"held at {held_level:.4g}{unit} until about t = {release:.4g} s, then released ({odds}, {rate});"
        f" the fit starts at t = {start:.6g} s, the first sample {BAND:g} noise levels off the held level"
    )
    return Release(
        "held",
        start,
        release_s=release,
        statistic=statistic,
        threshold=threshold,
        noise=sigma,
        held_samples=start_index,
        reason=why,
    )


def _change_point(window: _Window) -> tuple[float, float, int]:
    """(F, its false-alarm threshold, the index of the estimated release) on the record's beginning `window`."""
    t, candidates = window.t, window.candidates
    x0 = window.fitted(np.array([window.start[n] for n in window.names], float), 0.0)
    noise, noise_sums = _draws(t.size)
    h0 = window.signals(x0, np.zeros(1))[0]
    [(rss0, _, dof0)] = window.residual_sums(x0, np.zeros(1))
    # the draws' noise: H0's own residual (studentised below, so the record's noise level cancels)
    spread = math.sqrt(max(rss0, 1e-300) / max(dof0, 1))
    [(_, noise0, _)] = window.residual_sums(x0, np.zeros(1), (h0, noise, noise_sums, spread))
    best, best_noise, best_j = -math.inf, np.full(DRAWS, -math.inf), candidates[0]
    sums = window.residual_sums(x0, t[candidates], (h0, noise, noise_sums, spread))
    for j, (rss, noise_rss, dof) in zip(candidates, sums):
        # F = (RSS_H0 - RSS_H1) / (RSS_H1 / dof): the drop in units of H1's own noise estimate
        statistic = (rss0 - rss) / max(rss / dof, 1e-300)
        if statistic > best:
            best, best_j = statistic, j
        best_noise = np.maximum(best_noise, (noise0 - noise_rss) / np.maximum(noise_rss / dof, 1e-300))
    threshold = float(np.quantile(best_noise, 1.0 - FALSE_ALARM))
    if best > threshold:
        # H0's estimate is a poor centre for a held record: locate the release with H1 refitted, twice
        coarse = max(1, len(candidates) // 24)
        for _ in range(2):
            x1 = window.fitted(x0, float(t[best_j]))
            best_j = window.least_misfit(x1, candidates[::coarse])  # every coarse-th candidate, then its neighbours
            near = candidates.index(best_j)
            best_j = window.least_misfit(x1, candidates[max(near - coarse, 0) : near + coarse + 1])
    return best, threshold, int(window.rows[best_j])


@functools.lru_cache(maxsize=64)
def _draws(size: int) -> tuple[np.ndarray, np.ndarray]:
    """The threshold's pure-noise draws, (size, DRAWS) standard normal from the fixed SEED, and each draw's sum of
    squares (DRAWS,) [-], read-only: the first `size` rows of one draw of MAX_POINTS rows, made once (the generator
    fills an array row by row, so they are the numbers a draw of `size` rows gives)."""
    assert size <= MAX_POINTS, "a window holds at most MAX_POINTS samples"
    noise = _all_draws()[:size]
    sums = np.sum(noise * noise, axis=0)
    sums.flags.writeable = False
    return noise, sums


@functools.cache
def _all_draws() -> np.ndarray:
    """(MAX_POINTS, DRAWS) standard normal draws from SEED, read-only (4.8 MB, made once per process)."""
    noise = np.random.default_rng(SEED).standard_normal((MAX_POINTS, DRAWS))
    noise.flags.writeable = False
    return noise


class _Window:
    """The record's beginning the test looks at (module docstring), and H1(tau) on it for many tau at once."""

    def __init__(
        self,
        how: FitModel,
        record: Record,
        base: dict[str, float],
        fixed: dict[str, float],
        names: list[str],
        force: float,
        sigma: float,
        exit_: int,
    ):
        self.how, self.record, self.base, self.names, self.force, self.sigma = how, record, base, names, force, sigma
        self.modal = how.modal(names)
        self.start = how.start(record, base, fixed, names, force)
        rate = how.fastest_rate(self.start, base, self.modal)
        t_all = record.model_time
        end = t_all.size
        if rate > 0:
            end = int(np.searchsorted(t_all, t_all[exit_] + WINDOW_PERIODS * 2 * math.pi / rate, side="right"))
        end = max(end, min(t_all.size, 2 * exit_ + 4 * len(names)))
        stride = max(1, math.ceil(end / MAX_POINTS))
        #: the window's sample indices in the record, their times since the origin [s] and values [signal unit]
        self.rows = np.arange(0, end, stride)
        self.t, self.y = t_all[self.rows], record.values[self.rows]
        candidates = [int(j) for j in range(1, self.rows.size) if MIN_HELD <= self.rows[j] <= exit_]
        if not candidates:
            raise ValueError("the record is read too sparsely near its start")
        #: the candidate release times' places in the window
        self.candidates = candidates[:: max(1, math.ceil(len(candidates) / MAX_CANDIDATES))]
        bounds = np.array([how.bounds(n, self.start[n], record) for n in names]).T
        self.inside = (bounds[0] + 1e-9 * (bounds[1] - bounds[0]), bounds[1] - 1e-9 * (bounds[1] - bounds[0]))

    def values_of(self, vector: np.ndarray) -> dict[str, float]:
        """Every fit name's value: the start, with `names` from `vector`."""
        values = dict(self.start, delay=0.0)
        values.update(zip(self.names, (float(v) for v in vector)))
        return values

    def signals(self, vector: np.ndarray, releases: np.ndarray) -> np.ndarray:
        """(releases, window) H1(release) at the window's times for each release [s] (H0 at 0): one closed-form
        call for them all, element by element the calls one release at a time would make."""
        values = self.values_of(vector)
        params = self.how.scene_params(values, self.base, self.modal)
        t, signal = self.t, self.record.signal
        s = np.maximum(t[None, :] - releases[:, None], 0.0)
        moving = self.how.closed_form(s.ravel(), params, values, signal, self.force).reshape(s.shape)
        if signal == "pos":
            rest = self.how.closed_form(np.zeros(1), params, values, signal, self.force)[0]
        else:
            rest = values["offset"]
        return np.where(t[None, :] < releases[:, None], rest, moving)

    def fitted(self, vector: np.ndarray, release: float) -> np.ndarray:
        """The least-squares estimate of H1(release) (H0 at 0) from `vector` on."""
        import scipy.optimize  # here: scipy.optimize costs start-up time to every command

        at = np.array([release])
        return scipy.optimize.least_squares(
            lambda v: (self.signals(v, at)[0] - self.y) / self.sigma,
            np.clip(vector, *self.inside),
            bounds=self.inside,
            x_scale="jac",
        ).x

    def least_misfit(self, x: np.ndarray, among: list[int]) -> int:
        """The candidate of `among` whose H1, linearised at x, leaves the least residual (the first such)."""
        misfits = [rss for rss, _, _ in self.residual_sums(x, self.t[among])]
        return among[min(range(len(among)), key=misfits.__getitem__)]

    def residual_sums(
        self,
        x: np.ndarray,
        releases: np.ndarray,
        draws: tuple[np.ndarray, np.ndarray, np.ndarray, float] | None = None,
    ) -> list[tuple[float, np.ndarray, int]]:
        """For each release [s], H1(release) linearised at x: RSS / sigma^2 of the data, of H0's signal h0 plus
        each noise draw of standard deviation `spread` sigma (in spread^2 sigma^2; empty without `draws`, which
        are (h0, noise, noise's sums of squares, spread)), and the residual's degrees of freedom."""
        names, t, y, sigma = self.names, self.t, self.y, self.sigma
        steps = np.array([max(abs(v), 1e-3 * _typical(n, y, t)) for n, v in zip(names, x)])
        steps *= np.array([1.0 if n in LINEAR else 1e-6 for n in names])
        base_signals = self.signals(x, releases)
        moved = [self.signals(x + step * np.eye(len(names))[i], releases) for i, step in enumerate(steps)]
        out = []
        for k, base_signal in enumerate(base_signals):
            columns = np.column_stack([(moved[i][k] - base_signal) / step for i, step in enumerate(steps)])
            u, s, _ = np.linalg.svd(columns, full_matrices=False)
            basis = u[:, s > 1e-10 * s[0]] if s.size and s[0] > 0 else u[:, :0]
            data = (y - base_signal) / sigma
            explained = basis.T @ data
            rss, dof = float(data @ data - explained @ explained), t.size - basis.shape[1]
            if draws is None:
                out.append((rss, np.empty(0), dof))
                continue
            h0, noise, noise_sums, spread = draws
            # |d + e|^2 - |B^T (d + e)|^2 for each draw e, with d the gap between H0's signal and this model's base
            gap = (h0 - base_signal) / (sigma * spread)
            # einsum, not BLAS: a threaded BLAS on a busy machine takes 10-40 ms for this 5 x n x DRAWS product
            projected = np.einsum("ij,ik->jk", basis, noise) + (basis.T @ gap)[:, None]
            sums = noise_sums + 2.0 * np.einsum("i,ik->k", gap, noise) + gap @ gap - np.sum(projected**2, axis=0)
            out.append((rss, sums, dof))
        return out


def _first_off(y: np.ndarray, level: float, band: float, begin: int = 0) -> int | None:
    """Index of the first sample from `begin` on more than `band` off `level` [signal unit] (None: none), read in
    blocks of samples: the answer is near the start, and a long record is never copied whole."""
    for start, stop in reductions.blocks(y.size - begin):
        off = np.flatnonzero(np.abs(y[begin + start : begin + stop] - level) > band)
        if off.size:
            return begin + start + int(off[0])
    return None


def _typical(name: str, y: np.ndarray, t: np.ndarray) -> float:
    """A magnitude of a fit name for finite-difference steps when its value is near 0."""
    amplitude = float(np.ptp(y)) or 1.0
    span = float(t[-1] - t[0]) or 1.0
    return {"v0": amplitude / span, "a0": amplitude / span**2, "jerk": amplitude / span**3}.get(name, amplitude)
