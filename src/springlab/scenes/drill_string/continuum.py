"""The exact torsional rod: a uniform drill string held at the top, the bottom-hole assembly at the bit.

    rho J_p theta_tt = G J_p theta_xx,   0 < x < L (x down from the top drive)
    theta(0, t) = theta_top(t)                                   (the top drive)
    J_b theta_tt(L, t) = -G J_p theta_x(L, t) - T_friction(t)    (the bit)

Three exact answers, each without a lumped model:

* `roots` / `Rod.frequencies`: the natural frequencies omega_n = c beta_n, c = sqrt(G / rho), with
  (beta_n L) tan(beta_n L) = mu = rho J_p L / J_b, solved to machine precision (bracketed on
  ((n - 1) pi, (n - 1/2) pi), then Newton on the pole-free form x sin x - mu cos x = 0); mode
  shapes sin(beta_n x).
* `modal_spin_up`: the start-up from rest with the top drive accelerating uniformly (alpha for
  0 <= t < T_r, then constant speed) and the bit free, as a modal series with the quasi-static part
  summed in closed form (the mode-acceleration method) and a stated bound on the truncated modes.
* `WaveSolution`: the same rod as travelling waves (d'Alembert), exact at every x and t without
  truncation. With the bit stuck the torque on it is a finite sum, T_b(t) = 2 Z sum_k Omega(t - (2k + 1) L / c)
  (Z = rho c J_p, the rod's torsional impedance), so the first breakaway time is a root of a known
  piecewise-linear function; with dry friction at the bit the bit's speed w obeys the delay equation

      J_b w' = Z (2 F(t) - w) - T_f sign(w),   F(t) = sum_k Omega(t - (2k + 1) L/c) - sum_{k >= 1} w(t - 2k L/c)

  (F the wave arriving at the bit), integrated by steps of the delay with DOP853 at rtol 1e-12 between
  every kink of its history, with stick and slip switched exactly where they happen.
"""

from __future__ import annotations

import bisect
import dataclasses
import functools
import hashlib
import math

import numpy as np


def _optimize():  # noqa: ANN202 - the module
    """scipy.optimize, imported on first use: every command imports the scene registry, which must stay light."""
    import scipy.optimize

    return scipy.optimize


def _integrate():  # noqa: ANN202 - the module
    """scipy.integrate, imported on first use (see `_optimize`)."""
    import scipy.integrate

    return scipy.integrate


#: the bound on the modal series uses M_n >= (1/2 - 1/(4 pi)) rho J_p L for n >= 2 (see `modal_tail_bound`)
_MODAL_MASS_FLOOR = 0.5 - 1.0 / (4.0 * math.pi)
#: relative and absolute (times the top speed) tolerances of the delay equation's integration
WAVE_RTOL = 1e-12
WAVE_ATOL = 1e-13


def roots(mu: float, count: int) -> np.ndarray:
    """The first `count` roots x_n = beta_n L of x tan x = mu, to machine precision.

    Kept per (mu, count) (`_roots`): thousands of Brent searches cost a tenth of a second, and every
    run of one rod asks for the same ones.

    Parameters
    ----------
    mu
        rho J_p L / J_b [-], the rod's inertia over the bit's (inf: no bit, a fixed-free rod).
    count
        how many roots.

    Returns
    -------
    np.ndarray
        (count,) roots [-], x_n in ((n - 1) pi, (n - 1/2) pi].
    """
    if count < 1:
        raise ValueError(f"count must be >= 1, got {count}")
    if mu < 0 or math.isnan(mu):
        raise ValueError(f"mu must be >= 0, got {mu}")
    return _roots(float(mu), int(count)).copy()


@functools.lru_cache(maxsize=32)
def _roots(mu: float, count: int) -> np.ndarray:
    """`roots`, computed once per (mu, count); callers get a copy."""
    out = np.empty(count)
    # pole-free forms, scaled so the function is O(1): x sin x - mu cos x (mu <= 1) or x sin x / mu - cos x; the
    # same for every n, as are Brent's search and tolerance (set up once: 4096 roots ask for them)
    scale = 1.0 / mu if mu > 1.0 else 1.0

    def f(x: float) -> float:
        return x * math.sin(x) * scale - mu * scale * math.cos(x)

    def df(x: float) -> float:
        return (math.sin(x) + x * math.cos(x) + mu * math.sin(x)) * scale

    brentq = _optimize().brentq if 0.0 < mu < math.inf else None
    rtol = 4 * np.finfo(float).eps
    for n in range(1, count + 1):
        low, high = (n - 1) * math.pi, (n - 0.5) * math.pi
        if math.isinf(mu):
            out[n - 1] = high  # cos x = 0
            continue
        if brentq is None:  # mu = 0
            out[n - 1] = low  # sin x = 0: fixed-fixed (the first root, 0, is the rigid bit on a massless spring)
            continue
        x = brentq(f, low, high, xtol=1e-300, rtol=rtol, maxiter=500)
        for _ in range(3):  # Newton polishes the last bits (brentq stops within a few ulp)
            step = f(x) / df(x)
            if not math.isfinite(step) or abs(step) > 1e-6 * max(x, 1.0):
                break
            x -= step
        out[n - 1] = x
    return out


#: the last few start-up series (`Rod.modal_spin_up`), by rod, times and drive
_SPIN_UPS: dict[tuple, tuple[np.ndarray | None, np.ndarray]] = {}


@dataclasses.dataclass(frozen=True)
class Rod:
    """A uniform torsional rod with the bit's inertia at its lower end.

    Attributes
    ----------
    length
        L [m].
    shear_modulus
        G [Pa].
    density
        rho [kg/m^3].
    polar_moment
        J_p [m^4], the cross-section's polar second moment of area.
    bit_inertia
        J_b [kg m^2] (the bottom-hole assembly).
    """

    length: float
    shear_modulus: float
    density: float
    polar_moment: float
    bit_inertia: float

    @property
    def wave_speed(self) -> float:
        """c = sqrt(G / rho) [m/s], the speed of torsional waves."""
        return math.sqrt(self.shear_modulus / self.density)

    @property
    def travel_time(self) -> float:
        """L / c [s], the time a wave takes from the top drive to the bit."""
        return self.length / self.wave_speed

    @property
    def impedance(self) -> float:
        """Z = rho c J_p [N m s/rad]: torque per angular speed of a travelling wave."""
        return self.density * self.wave_speed * self.polar_moment

    @property
    def rod_inertia(self) -> float:
        """rho J_p L [kg m^2], the whole rod's inertia about its axis."""
        return self.density * self.polar_moment * self.length

    @property
    def stiffness(self) -> float:
        """G J_p / L [N m/rad], the whole rod's torsional stiffness."""
        return self.shear_modulus * self.polar_moment / self.length

    @property
    def mu(self) -> float:
        """rho J_p L / J_b [-] (inf without a bit inertia)."""
        return self.rod_inertia / self.bit_inertia if self.bit_inertia > 0 else math.inf

    def betas(self, count: int) -> np.ndarray:
        """beta_n [1/m] of the first `count` modes."""
        return roots(self.mu, count) / self.length

    def frequencies(self, count: int) -> np.ndarray:
        """omega_n = c beta_n [rad/s] of the first `count` modes."""
        return self.wave_speed * self.betas(count)

    def shapes(self, count: int, x: np.ndarray) -> np.ndarray:
        """(count, len(x)) mode shapes sin(beta_n x) [-] at depths x [m], 1 at most."""
        return np.sin(np.outer(self.betas(count), np.asarray(x, float)))

    def modal_masses(self, betas: np.ndarray) -> np.ndarray:
        """M_n = int rho J_p sin^2(beta x) dx + J_b sin^2(beta L) [kg m^2] of the shapes sin(beta_n x)."""
        b = np.asarray(betas, float)
        L = self.length
        return (
            self.density * self.polar_moment * (L / 2 - np.sin(2 * b * L) / (4 * b))
            + self.bit_inertia * np.sin(b * L) ** 2
        )

    # -- the start-up, bit free -------------------------------------------------------

    def static_twist(self, x: np.ndarray) -> np.ndarray:
        """u_s(x) [rad per rad/s^2]: the rod's lag behind the top drive under a steady unit acceleration.

        Solves G J_p u'' = rho J_p, u(0) = 0, G J_p u'(L) = -J_b (the bit's inertia resists).
        """
        x = np.asarray(x, float)
        G, rho, L = self.shear_modulus, self.density, self.length
        return rho * x**2 / (2 * G) - x * (rho * L / G + self.bit_inertia / (G * self.polar_moment))

    def modal_tail_bound(self, modes: int, acceleration: float) -> tuple[float, float]:
        """Bounds on the modes beyond `modes` of `modal_spin_up` at any x and t: (angle [rad], speed [rad/s]).

        Mode n contributes (P_n alpha / K_n) sin(beta_n x) [cos(w_n t) - cos(w_n (t - T_r))], with
        P_n = rho J_p / beta_n (the eigen-equation turns the bit's share into this), K_n = w_n^2 M_n
        and M_n >= (1/2 - 1/(4 pi)) rho J_p L; beta_n >= (n - 1) pi / L. So the angle's tail is at
        most 2 alpha L^2 / (c^2 m pi^3) sum_{k >= modes} k^-3 and the speed's 2 alpha L / (c m pi^2)
        sum_{k >= modes} k^-2, each sum bounded by its integral plus its first term.
        """
        if modes < 2:
            raise ValueError("the tail bound needs at least 2 modes")
        m, c, L, a = _MODAL_MASS_FLOOR, self.wave_speed, self.length, abs(acceleration)
        cubes = 1.0 / modes**3 + 1.0 / (2.0 * modes**2)
        squares = 1.0 / modes**2 + 1.0 / modes
        return 2 * a * L**2 / (c**2 * m * math.pi**3) * cubes, 2 * a * L / (c * m * math.pi**2) * squares

    def modal_spin_up(
        self, time: np.ndarray, x: float, acceleration: float, ramp_time: float, modes: int
    ) -> tuple[np.ndarray, np.ndarray]:
        """Angle [rad] and speed [rad/s] at depth x [m] of the start-up from rest, bit free, as `modes` modes.

        The top drive accelerates at `acceleration` [rad/s^2] for 0 <= t < `ramp_time` [s], then turns
        at constant speed. theta = theta_top + u, u = a(t) u_s(x) + sum_n (P_n alpha / K_n) sin(beta_n x)
        [cos w_n t - H(t - T_r) cos w_n (t - T_r)]; `modal_tail_bound` bounds what the truncation leaves out.
        """
        angle, speed = self._kept_spin_up(time, x, acceleration, ramp_time, modes, with_angle=True)
        assert angle is not None
        return angle, speed

    def modal_spin_up_speed(
        self, time: np.ndarray, x: float, acceleration: float, ramp_time: float, modes: int
    ) -> np.ndarray:
        """The speed [rad/s] of `modal_spin_up` alone (the same values, bit for bit; the angle's three products of
        the times x modes tables left out)."""
        return self._kept_spin_up(time, x, acceleration, ramp_time, modes, with_angle=False)[1]

    def _kept_spin_up(
        self, time: np.ndarray, x: float, acceleration: float, ramp_time: float, modes: int, *, with_angle: bool
    ) -> tuple[np.ndarray | None, np.ndarray]:
        """`_modal_spin_up`, kept in `_SPIN_UPS` for long grids of times; copies of the kept arrays."""
        t = np.ascontiguousarray(time, dtype=float)
        args = (float(x), float(acceleration), float(ramp_time), int(modes))
        if t.size < 64:  # a point of a search: cheap, and kept it would push the long series out
            return self._modal_spin_up(t, *args, with_angle=with_angle)
        digest = hashlib.blake2b(t.tobytes(), digest_size=16).digest()
        key = (self, digest, t.shape, *args, with_angle)
        if key not in _SPIN_UPS:
            _SPIN_UPS[key] = self._modal_spin_up(t, *args, with_angle=with_angle)
            while len(_SPIN_UPS) > 8:
                _SPIN_UPS.pop(next(iter(_SPIN_UPS)))
        angle, speed = _SPIN_UPS[key]
        return None if angle is None else angle.copy(), speed.copy()

    def _modal_spin_up(
        self, t: np.ndarray, x: float, acceleration: float, ramp_time: float, modes: int, *, with_angle: bool
    ) -> tuple[np.ndarray | None, np.ndarray]:
        """`modal_spin_up` computed (its times x modes sines and cosines summed by `_trig_sums`); the angle None
        unless `with_angle`."""
        alpha, ramp = acceleration, ramp_time
        on = t < ramp
        top_angle = np.where(on, 0.5 * alpha * t**2, 0.5 * alpha * ramp**2 + alpha * ramp * (t - ramp))
        top_speed = alpha * np.minimum(t, ramp)
        angle = top_angle + np.where(on, alpha, 0.0) * self.static_twist(np.array([x]))[0]
        speed = top_speed.copy()
        betas = self.betas(modes)
        omegas = self.wave_speed * betas
        amplitude = alpha * (self.density * self.polar_moment / betas) / (omegas**2 * self.modal_masses(betas))
        amplitude *= np.sin(betas * x)
        switched = ~on
        # after the ramp, cos w(t - T_r) = cos wt cos wT_r + sin wt sin wT_r (and sin likewise): sums of sin wt and
        # cos wt alone; before the ramp's end the switched terms are 0
        cos_r, sin_r = np.cos(omegas * ramp), np.sin(omegas * ramp)
        aw = amplitude * omegas
        sines = [aw, aw * cos_r] + ([amplitude * sin_r] if with_angle else [])
        cosines = [aw * sin_r] + ([amplitude, amplitude * cos_r] if with_angle else [])
        sin_sums, cos_sums = _trig_sums(t, omegas, sines, cosines)
        speed += -sin_sums[0] + np.where(switched, sin_sums[1] - cos_sums[0], 0.0)
        if with_angle:
            angle += cos_sums[1] - np.where(switched, cos_sums[2] + sin_sums[2], 0.0)
        return (angle if with_angle else None), speed


#: rows from which `_trig_sums` takes a near-uniform grid by angle addition
_ADDITION_ROWS = 256
#: the largest w |delta| (the grid's departure from uniform, in radians) the addition's second-order correction takes
_ADDITION_DEPARTURE = 1e-5


def _trig_sums(
    t: np.ndarray, w: np.ndarray, sines: list[np.ndarray], cosines: list[np.ndarray]
) -> tuple[list[np.ndarray], list[np.ndarray]]:
    """([sin(t w^T) @ v for v in sines], [cos(t w^T) @ u for u in cosines]) at times t [s] and frequencies w [rad/s].

    A long grid that is uniform but for round-off (a run's times) is split into blocks of b rows, t_k = t_i + D_j +
    delta_k (k = j b + i, D_j = t_(j b) - t_0), and sin(w t_k) = sin(w (t_i + D_j)) cos(w delta_k) +
    cos(w (t_i + D_j)) sin(w delta_k), the first factors by angle addition from b + J rows of sines and cosines
    (about 2 sqrt(len(t)) instead of len(t)) and the sums over w as matrix products; w delta_k (below
    `_ADDITION_DEPARTURE`) enters to second order, its third-order term under 2e-16 of a term. Each term is good to a
    few eps, as a sine taken directly is (both round the phase w t to eps of itself). A short or irregular grid
    takes its sines directly.
    """
    n = len(t)
    block = max(1, math.isqrt(max(n - 1, 0)) + 1)
    starts = np.arange(0, n, block)
    index = np.arange(n)
    offsets = t[starts] - t[0]
    departure = t - t[index % block] - offsets[index // block] if n >= _ADDITION_ROWS else None
    scale = float(np.max(np.abs(w), initial=0.0))
    if departure is None or not float(np.max(np.abs(departure)) * scale) <= _ADDITION_DEPARTURE:
        sin_sums, cos_sums = [np.zeros(n) for _ in sines], [np.zeros(n) for _ in cosines]
        for chunk in range(0, len(w), 512):  # (times x modes) in slices keeps memory flat
            part = slice(chunk, chunk + 512)
            phase = np.outer(t, w[part])
            sine, cosine = np.sin(phase), np.cos(phase)
            for total, v in zip(sin_sums, sines, strict=True):
                total += sine @ v[part]
            for total, u in zip(cos_sums, cosines, strict=True):
                total += cosine @ u[part]
        return sin_sums, cos_sums
    base, shift = np.outer(t[:block], w), np.outer(offsets, w)
    base_cos, base_sin, shift_cos, shift_sin = np.cos(base), np.sin(base), np.cos(shift), np.sin(shift)

    def sin_sum(v: np.ndarray) -> np.ndarray:
        """sin(w (t_i + D_j)) @ v for every row k, by angle addition: two matrix products."""
        summed = base_sin @ (shift_cos * v).T + base_cos @ (shift_sin * v).T  # (b, J): row i of block j
        return summed.T.reshape(-1)[:n]

    def cos_sum(v: np.ndarray) -> np.ndarray:
        """cos(w (t_i + D_j)) @ v for every row k, by angle addition: two matrix products."""
        summed = base_cos @ (shift_cos * v).T - base_sin @ (shift_sin * v).T
        return summed.T.reshape(-1)[:n]

    half_square = 0.5 * departure * departure
    sin_sums = [sin_sum(v) + departure * cos_sum(w * v) - half_square * sin_sum(w * w * v) for v in sines]
    cos_sums = [cos_sum(u) - departure * sin_sum(w * u) - half_square * cos_sum(w * w * u) for u in cosines]
    return sin_sums, cos_sums


def top_speed(time: np.ndarray | float, acceleration: float, ramp_time: float) -> np.ndarray:
    """Omega(t) [rad/s]: 0 before t = 0, alpha t up to the ramp time, then alpha T_r."""
    t = np.asarray(time, float)
    return float(acceleration) * np.clip(t, 0.0, float(ramp_time))


def stuck_bit_torque(rod: Rod, time: np.ndarray | float, acceleration: float, ramp_time: float) -> np.ndarray:
    """The torque on a bit held still [N m]: T_b(t) = 2 Z sum_k Omega(t - (2k + 1) L / c), a finite sum (exact)."""
    t = np.atleast_1d(np.asarray(time, float))
    tau = rod.travel_time
    total = np.zeros_like(t)
    k = 0
    while True:
        shifted = t - (2 * k + 1) * tau
        if np.all(shifted <= 0):
            break
        total += top_speed(shifted, acceleration, ramp_time)
        k += 1
    return 2 * rod.impedance * total


def stuck_breakaway_time(rod: Rod, friction_torque: float, acceleration: float, ramp_time: float) -> float:
    """The first time [s] the torque on the stuck bit reaches the friction torque (inf: never).

    T_b is piecewise linear and never decreasing (each travelling copy of the top speed adds a ramp),
    so the root is bracketed between the kink after which it first exceeds T_f and the one before.
    """
    if friction_torque <= 0:
        return 0.0
    if acceleration <= 0:
        return math.inf
    tau = rod.travel_time
    full = alpha_end = acceleration * ramp_time  # each copy adds at most this speed
    copies = math.ceil(friction_torque / (2 * rod.impedance * full)) + 1
    kinks = sorted({(2 * k + 1) * tau + s for k in range(copies + 1) for s in (0.0, ramp_time)})
    del alpha_end

    def excess(t: float) -> float:
        return float(stuck_bit_torque(rod, t, acceleration, ramp_time)[0]) - friction_torque

    previous = 0.0
    for kink in kinks:
        if excess(kink) >= 0.0:
            return float(_optimize().brentq(excess, previous, kink, xtol=1e-15, rtol=4 * np.finfo(float).eps))
        previous = kink
    return math.inf


@dataclasses.dataclass(frozen=True)
class StickSlip:
    """The bit's motion on the exact rod under dry friction (`WaveSolution.solve`).

    Attributes
    ----------
    time, speed
        the bit's speed w [rad/s] at `time` [s] (dense: each integration step's end and the events).
    events
        [(time [s], 'slip' or 'stick')] in order: when the bit breaks free and when it sticks again.
    peak_speed
        the bit's largest speed [rad/s] over the solution.
    peak_time
        when [s].
    """

    time: np.ndarray
    speed: np.ndarray
    events: tuple[tuple[float, str], ...]
    peak_speed: float
    peak_time: float

    def first(self, kind: str) -> float:
        """The first event of `kind` ('slip', 'stick') [s], nan where none happened."""
        return next((t for t, k in self.events if k == kind), math.nan)


class WaveSolution:
    """The bit's speed on the exact rod (travelling waves), with Coulomb friction T_f at the bit.

    The delay equation of the module docstring is integrated over [0, duration] piece by piece:
    between consecutive kinks of F (the top speed's kinks delayed by odd multiples of L/c, the bit's
    own stick/slip events delayed by even multiples) with scipy's DOP853, whose dense output of w
    supplies the history; stuck pieces (w = 0 while |2 Z F| <= T_f) end exactly at the root of
    |2 Z F| = T_f.
    """

    def __init__(self, rod: Rod, friction_torque: float, acceleration: float, ramp_time: float):
        if rod.bit_inertia <= 0:
            raise ValueError("the wave solution needs a bit inertia > 0")
        self.rod = rod
        self.friction = float(friction_torque)
        self.alpha = float(acceleration)
        self.ramp = float(ramp_time)
        self._pieces: list[tuple[float, float, object]] = []  # (start, end, w(t) or None for stuck)
        self._starts: list[float] = []
        self._tau = rod.travel_time  # L / c, read at every right-hand side

    # -- the history ------------------------------------------------------------------

    def speed(self, t: float) -> float:
        """w(t) [rad/s] from the pieces solved so far (0 before t = 0)."""
        if t <= 0.0 or not self._pieces:
            return 0.0
        i = max(bisect.bisect_right(self._starts, t) - 1, 0)
        start, end, dense = self._pieces[i]
        if dense is None:
            return 0.0
        return dense(min(max(t, start), end))  # type: ignore[operator]

    def incoming(self, t: float) -> float:
        """F(t) [rad/s], the wave arriving at the bit: sum_k Omega(t - (2k+1) tau) - sum_{k>=1} w(t - 2k tau).

        The delay equation reads it at every right-hand side (about 5,000 times a breakaway, each a dozen reads of
        the history): `speed` is written out here, the same floats in the same order (a stuck piece's or an empty
        history's 0.0 is left out of the sum, which subtracting it leaves unchanged).
        """
        tau, alpha, ramp = self._tau, self.alpha, self.ramp
        total = 0.0
        k = 0
        shifted = t - tau
        while shifted > 0:
            # top_speed of a positive time, in floats: numpy's scalar clip costs more than the rest of the sum, and
            # min() as a call more than its comparison written out (the same value: min keeps the first of equals)
            total += alpha * (ramp if ramp < shifted else shifted)
            k += 1
            shifted = t - (2 * k + 1) * tau
        pieces, starts = self._pieces, self._starts
        if not pieces:
            return total
        find = bisect.bisect_right
        k = 1
        earlier = t - 2 * tau
        while earlier > 0:
            index = find(starts, earlier) - 1
            start, end, dense = pieces[index if index > 0 else 0]
            if dense is not None:
                inside = start if start > earlier else earlier  # clamped to the piece, as min(max(...)) does
                total -= dense(end if end < inside else inside)  # type: ignore[operator]
            k += 1
            earlier = t - 2 * k * tau
        return total

    def _drive(self, t: float) -> float:
        """2 Z F(t) [N m]: the torque the rod would exert on a bit held still."""
        return 2 * self.rod.impedance * self.incoming(t)

    # -- the solution -----------------------------------------------------------------

    def solve(self, duration: float) -> StickSlip:
        """Integrate from rest to `duration` [s]."""
        rod, tau = self.rod, self.rod.travel_time
        J, Z, Tf = rod.bit_inertia, rod.impedance, self.friction
        scale = max(abs(self.alpha) * max(self.ramp, tau), 1e-300)
        kinks = {(2 * k + 1) * tau + s for k in range(int(duration / (2 * tau)) + 2) for s in (0.0, self.ramp)}
        kinks = {k for k in kinks if 0.0 < k < duration}
        times: list[float] = [0.0]
        speeds: list[float] = [0.0]
        events: list[tuple[float, str]] = []
        t, w = 0.0, 0.0
        stuck = Tf > 0  # a bit under friction starts stuck (at rest); a free bit (Tf = 0) never sticks
        direction = 0.0

        def add_event_kinks(at: float) -> None:
            k = 1
            while at + 2 * k * tau < duration:
                kinks.add(at + 2 * k * tau)
                k += 1

        while t < duration * (1 - 1e-15):
            following = [k for k in kinks if k > t * (1 + 1e-15) + 1e-15]
            end = min(min(following, default=duration), duration)
            if stuck:
                drive = self._drive  # a bound method: nothing of the loop is captured
                if abs(drive(end)) < Tf:
                    self._append(t, end, None)
                    t = end
                    times.append(t)
                    speeds.append(0.0)
                    continue
                # |2 Z F| reaches T_f inside (t, end]: F is smooth there, so bracket the first crossing
                grid = np.linspace(t, end, 33)
                values = [abs(drive(s)) - Tf for s in grid]
                j = next(i for i, v in enumerate(values) if v >= 0)
                lo, hi = (grid[j - 1], grid[j]) if j > 0 else (t, t)
                at = hi if lo == hi else _optimize().brentq(lambda s: abs(self._drive(s)) - Tf, lo, hi, xtol=1e-15)
                if at > t:
                    self._append(t, at, None)
                    times.append(at)
                    speeds.append(0.0)
                t = float(at)
                direction = math.copysign(1.0, drive(t))
                stuck = False
                events.append((t, "slip"))
                add_event_kinks(t)
                continue

            def rate(s: float, y: np.ndarray, direction: float = direction) -> np.ndarray:
                return np.array([(Z * (2 * self.incoming(s) - y[0]) - Tf * direction) / J])

            def stops(s: float, y: np.ndarray) -> float:
                return y[0]

            stops.terminal = True  # type: ignore[attr-defined]
            stops.direction = -direction  # type: ignore[attr-defined]
            if Tf > 0 and direction != 0.0:
                found = _integrate().solve_ivp(
                    rate,
                    (t, end),
                    [w],
                    method="DOP853",
                    rtol=WAVE_RTOL,
                    atol=WAVE_ATOL * scale,
                    dense_output=True,
                    events=stops,
                )
            else:
                found = _integrate().solve_ivp(
                    rate, (t, end), [w], method="DOP853", rtol=WAVE_RTOL, atol=WAVE_ATOL * scale, dense_output=True
                )
            stop = float(found.t[-1])
            self._append(t, stop, _history(found.sol))
            times.extend(float(s) for s in found.t[1:])
            speeds.extend(float(v) for v in found.y[0, 1:])
            t, w = stop, float(found.y[0, -1])
            if found.status == 1:  # the bit's speed reached 0: it sticks, or turns and slips back
                w = 0.0
                speeds[-1] = 0.0
                if abs(self._drive(t)) <= Tf:
                    stuck = True
                    events.append((t, "stick"))
                else:
                    direction = -direction
                    events.append((t, "reverse"))
                add_event_kinks(t)
        time_array, speed_array = np.array(times), np.array(speeds)
        peak_time, peak_speed = self._peak(time_array, speed_array)
        return StickSlip(time_array, speed_array, tuple(events), peak_speed, peak_time)

    def _append(self, start: float, end: float, dense: object) -> None:
        self._pieces.append((start, end, dense))
        self._starts.append(start)

    def _peak(self, time: np.ndarray, speed: np.ndarray) -> tuple[float, float]:
        """(time [s], speed [rad/s]) of the bit's largest speed: the best node, refined on the dense output."""
        i = int(np.argmax(speed))
        best_t, best = float(time[i]), float(speed[i])
        lo, hi = float(time[max(i - 1, 0)]), float(time[min(i + 1, len(time) - 1)])
        if hi > lo:
            found = _optimize().minimize_scalar(
                lambda s: -self.speed(s), bounds=(lo, hi), method="bounded", options={"xatol": 1e-12}
            )
            if -found.fun > best:
                best_t, best = float(found.x), float(-found.fun)
        return best_t, best


class _DenseSpeed:
    """w(t) [rad/s] of one DOP853 piece: its dense output evaluated in Python floats, the same bits as scipy's.

    The delay equation reads its own history at every right-hand side (about 55,000 reads per breakaway);
    scipy's OdeSolution takes a numpy round trip per read (a 0-d array, a search, a 1-element polynomial). Here
    the search is `bisect_left` (numpy's searchsorted with side='left') and each step's polynomial is
    Dop853DenseOutput's own Horner-like sequence on floats: the same IEEE operations in the same order, so the
    history, and everything integrated from it, is bit for bit what scipy's evaluation gives.
    """

    def __init__(self, times: list[float], steps: list[tuple[float, float, tuple[float, ...], float]]):
        self._times = times  # step boundaries, increasing
        self._steps = steps  # per step: (t_old, h, the F rows' values last first, y_old)
        self._last = len(steps) - 1

    def __call__(self, t: float) -> float:
        segment = bisect.bisect_left(self._times, t) - 1
        segment = 0 if segment < 0 else (self._last if segment > self._last else segment)
        t_old, h, c, y_old = self._steps[segment]
        x = (t - t_old) / h
        rest = 1 - x
        if len(c) == 7:  # DOP853's seven rows, the loop below written out: the same operations in the same order
            y = ((((((0.0 + c[0]) * x + c[1]) * rest + c[2]) * x + c[3]) * rest + c[4]) * x + c[5]) * rest
            return (y + c[6]) * x + y_old
        y = 0.0
        odd = False
        for f in c:  # y += f, then y *= x (even rows) or 1 - x (odd rows): scipy's order
            y = (y + f) * (rest if odd else x)
            odd = not odd
        return y + y_old


def _history(solution: object) -> object:
    """A piece's w(t) for `WaveSolution.speed`: `_DenseSpeed` of a DOP853 OdeSolution, else the solution itself."""
    interpolants = getattr(solution, "interpolants", None)
    ts = np.asarray(getattr(solution, "ts", ()), float)
    if (
        not interpolants
        or not all(type(step).__name__ == "Dop853DenseOutput" for step in interpolants)
        or not (ts.size == len(interpolants) + 1 and np.all(np.diff(ts) > 0))
    ):
        return lambda t: float(solution(t)[0])  # type: ignore[operator]
    steps = [
        (float(step.t_old), float(step.h), tuple(float(f[0]) for f in reversed(step.F)), float(step.y_old[0]))
        for step in interpolants
    ]
    return _DenseSpeed([float(v) for v in ts], steps)
