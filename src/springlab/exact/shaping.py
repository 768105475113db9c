"""Input shaping: commands convolved with a few impulses timed to a resonance, and their exact residual vibration.

A shaper is a sequence of impulses with amplitudes A_i [-] (sum 1) at times t_i [s] (t_1 = 0). Convolving a
command with it (each step of the command repeated at every t_i, scaled by A_i) keeps the command's net effect
(the rigid body still travels the same distance), keeps a force within its limit when every A_i > 0, and
lengthens the command by the shaper's duration t_N.

Residual vibration (Singer & Seering 1990). A damped mode x'' + 2 zeta omega x' + omega^2 x = u(t) answers a
unit impulse at t_i with Re(c e^{s (t - t_i)}), s = -zeta omega + i omega_d, omega_d = omega sqrt(1 - zeta^2).
After the last impulse the shaped response is Re(c e^{s t} sum_i A_i e^{-s t_i}), so against one unit impulse
at t_N it keeps the fraction

    V(omega, zeta) = e^{-zeta omega t_N} | sum_i A_i e^{zeta omega t_i} e^{-i omega_d t_i} |

of the vibration: exactly, for every command, because a command is a sum of shifted steps and the sum over
the shaper factors out of the sum over the command's steps (exact.positioning uses it that way). The shaper
is designed at (omega_s, zeta_s); the robustness curve is V at the true omega = omega_s (1 + error).

The shapers, each from the equations that define it:

* ZV: V(omega_s) = 0 with two impulses. The complex equation A_1 + A_2 e^{zeta omega_s t_2} e^{-i omega_d t_2}
  = 0 needs omega_d t_2 = pi (half a damped period) and A_2 / A_1 = K = exp(-zeta pi / sqrt(1 - zeta^2)).
* ZVD: V(omega_s) = 0 and dV/domega(omega_s) = 0 with three impulses: the ZV shaper convolved with itself,
  amplitudes (1, 2K, K^2) / (1 + K)^2 at 0, pi / omega_d, 2 pi / omega_d.
* MZV: V(omega_s) = 0 with three impulses a fixed 3/8 of a damped period apart (shorter than ZVD, 3/4 of a
  period, less robust): sum_i A_i e^{(zeta omega_s - i omega_d) t_i} = 0 with t_i = (i - 1) tau,
  omega_d tau = 3 pi / 4 is a (1, sqrt 2, 1) combination of e^{-i (i - 1) 3 pi / 4} after the decay
  e^{-zeta omega_s tau} = K^(3/4) is taken out: A proportional to (1, sqrt(2) K^(3/4), K^(3/2)).
* EI (extra insensitive, Singhose, Seering & Singer 1994): three impulses, the vibration at the design
  frequency held at a tolerance V_tol instead of zero, with zero slope there (a hump of height V_tol), and
  zero vibration at two frequencies omega_lo < omega_s < omega_hi: seven real equations (sum of A = 1,
  V(omega_s) = V_tol, dV/domega(omega_s) = 0, Re and Im of the vibration vector at omega_lo and at omega_hi)
  in seven unknowns (A_1, A_2, A_3, t_2, t_3, omega_lo, omega_hi). Undamped it has the closed form
  A = ((1 + V_tol) / 4, (1 - V_tol) / 2, (1 + V_tol) / 4) at 0, T/2, T; damped it is solved by Newton's method
  continued in zeta from that solution, to round-off (`ei_constraints` gives the residuals). No firmware's
  fitted coefficients are used.

Frequencies [rad/s] in the formulas, [Hz] at the public constructors; times [s]; amplitudes [-].
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Callable

import numpy as np

__all__ = [
    "SHAPERS",
    "Shaper",
    "ei",
    "ei_constraints",
    "insensitivity",
    "make_shaper",
    "mzv",
    "on_grid",
    "residual_vibration",
    "robustness_curve",
    "shape_command",
    "zv",
    "zvd",
]

#: the EI shaper's default vibration tolerance V_tol [-] at the design frequency (5 %, as the literature's)
EI_TOLERANCE = 0.05
#: largest constraint residual [-] an EI solution may keep (the equations are O(1) in their scaled form)
_EI_RESIDUAL = 1e-12


@dataclasses.dataclass(frozen=True)
class Shaper:
    """A sequence of impulses designed for a mode.

    Attributes
    ----------
    name
        "zv", "zvd", "mzv" or "ei".
    amplitudes
        Impulse amplitudes A_i [-], positive, summing to 1.
    times
        Impulse times t_i [s], increasing, the first 0.
    frequency_hz
        Design frequency f_s [Hz] (undamped natural frequency of the mode it is designed for).
    damping_ratio
        Design damping ratio zeta_s [-].
    zeros_hz
        Frequencies [Hz] at which the shaper leaves no vibration on a mode of the design damping (f_s for ZV,
        ZVD and MZV; f_lo and f_hi for EI).
    flat_hz
        Frequencies [Hz] at which its vibration vector's derivative in frequency is zero too (f_s for ZVD).
    """

    name: str
    amplitudes: np.ndarray
    times: np.ndarray
    frequency_hz: float
    damping_ratio: float
    zeros_hz: tuple[float, ...] = ()
    flat_hz: tuple[float, ...] = ()

    @property
    def duration(self) -> float:
        """The time t_N [s] the shaper adds to a command."""
        return float(self.times[-1])

    def vibration(self, frequency_hz: float | np.ndarray, damping_ratio: float | None = None) -> np.ndarray:
        """Residual vibration V [-] on a mode of `frequency_hz` [Hz] (default damping: the design's)."""
        zeta = self.damping_ratio if damping_ratio is None else damping_ratio
        return residual_vibration(self.amplitudes, self.times, 2 * math.pi * np.asarray(frequency_hz), zeta)


def _check_design(frequency_hz: float, damping_ratio: float) -> tuple[float, float]:
    """(omega_s [rad/s], omega_d [rad/s]) of a design, or ValueError naming what is wrong."""
    if not (math.isfinite(frequency_hz) and frequency_hz > 0):
        raise ValueError(f"shaper frequency must be a positive number of Hz, got {frequency_hz!r}")
    if not (math.isfinite(damping_ratio) and 0 <= damping_ratio < 1):
        raise ValueError(f"shaper damping ratio must be in [0, 1), got {damping_ratio!r}")
    omega = 2 * math.pi * frequency_hz
    return omega, omega * math.sqrt(1 - damping_ratio**2)


def residual_vibration(amplitudes: np.ndarray, times: np.ndarray, omega: float | np.ndarray, zeta: float) -> np.ndarray:
    """Residual vibration V [-] of impulses A_i [-] at t_i [s] on a mode (omega [rad/s], zeta [-]).

    V = e^{-zeta omega t_N} |sum_i A_i e^{zeta omega t_i} e^{-i omega_d t_i}| (module docstring): the fraction of
    a single impulse's vibration the sequence leaves, 1 for a single unit impulse. Written with each
    exponent relative to t_N (e^{zeta omega (t_i - t_N)} <= 1), so nothing overflows.
    """
    a = np.asarray(amplitudes, dtype=float)
    t = np.asarray(times, dtype=float)
    w = np.asarray(omega, dtype=float)[..., None]
    exponent = zeta * w * (t - t[-1]) - 1j * w * math.sqrt(1 - zeta * zeta) * t
    return np.abs(np.sum(a * np.exp(exponent), axis=-1))


def _vibration_vector(a: np.ndarray, t: np.ndarray, omega: float, zeta: float) -> tuple[complex, complex]:
    """(P, dP/domega) with P = sum_i A_i e^{(zeta - i sqrt(1 - zeta^2)) omega t_i} (unnormalized)."""
    r = zeta - 1j * math.sqrt(1 - zeta * zeta)
    terms = a * np.exp(r * omega * t)
    return complex(terms.sum()), complex((terms * r * t).sum())


def zv(frequency_hz: float, damping_ratio: float) -> Shaper:
    """The zero-vibration shaper: 1 / (1 + K), K / (1 + K) at 0 and half a damped period [s] (module docstring).

    Parameters
    ----------
    frequency_hz
        Design frequency f_s [Hz].
    damping_ratio
        Design damping ratio [-], in [0, 1).
    """
    _, omega_d = _check_design(frequency_hz, damping_ratio)
    k = math.exp(-damping_ratio * math.pi / math.sqrt(1 - damping_ratio**2))
    times = np.array([0.0, math.pi / omega_d])
    return Shaper("zv", np.array([1.0, k]) / (1 + k), times, frequency_hz, damping_ratio, (frequency_hz,))


def zvd(frequency_hz: float, damping_ratio: float) -> Shaper:
    """The zero-vibration-and-derivative shaper: (1, 2K, K^2) / (1 + K)^2 at 0, T_d / 2, T_d [s].

    Parameters
    ----------
    frequency_hz
        Design frequency f_s [Hz].
    damping_ratio
        Design damping ratio [-], in [0, 1).
    """
    _, omega_d = _check_design(frequency_hz, damping_ratio)
    k = math.exp(-damping_ratio * math.pi / math.sqrt(1 - damping_ratio**2))
    amplitudes = np.array([1.0, 2 * k, k * k]) / (1 + k) ** 2
    times = np.array([0.0, 1.0, 2.0]) * math.pi / omega_d
    return Shaper("zvd", amplitudes, times, frequency_hz, damping_ratio, (frequency_hz,), (frequency_hz,))


def mzv(frequency_hz: float, damping_ratio: float) -> Shaper:
    """Three impulses 3/8 of a damped period apart with zero vibration at the design: (1, sqrt 2 K', K'^2) / sum.

    K' = exp(-(3/4) zeta pi / sqrt(1 - zeta^2)), the mode's decay over the spacing (module docstring).

    Parameters
    ----------
    frequency_hz
        Design frequency f_s [Hz].
    damping_ratio
        Design damping ratio [-], in [0, 1).
    """
    _, omega_d = _check_design(frequency_hz, damping_ratio)
    k = math.exp(-0.75 * damping_ratio * math.pi / math.sqrt(1 - damping_ratio**2))
    weights = np.array([1.0, math.sqrt(2.0) * k, k * k])
    times = np.array([0.0, 1.0, 2.0]) * 0.75 * math.pi / omega_d
    return Shaper("mzv", weights / weights.sum(), times, frequency_hz, damping_ratio, (frequency_hz,))


def ei_constraints(
    amplitudes: np.ndarray,
    times: np.ndarray,
    omega_s: float,
    zeta: float,
    tolerance: float,
    omega_lo: float,
    omega_hi: float,
) -> np.ndarray:
    """The EI shaper's seven defining equations, each 0 at the solution, dimensionless.

    [sum A_i - 1, V(omega_s) - V_tol, omega_s dV/domega(omega_s) written as omega_s e^{...} (Re(conj(P) P') -
    zeta t_N |P|^2) / |P|, Re P(omega_lo), Im P(omega_lo), Re P(omega_hi), Im P(omega_hi)], with
    P(omega) = sum_i A_i e^{(zeta - i sqrt(1 - zeta^2)) omega (t_i - t_N)} (the vibration vector scaled so
    that |P| = V).

    Parameters
    ----------
    amplitudes, times
        A_i [-] and t_i [s] of three impulses.
    omega_s
        Design frequency [rad/s].
    zeta
        Design damping ratio [-].
    tolerance
        V_tol [-].
    omega_lo, omega_hi
        The two frequencies [rad/s] with zero vibration.
    """
    a, t = np.asarray(amplitudes, dtype=float), np.asarray(times, dtype=float)
    shifted = t - t[-1]
    p, dp = _vibration_vector(a, shifted, omega_s, zeta)
    magnitude = abs(p)
    # d|P|/domega with P already scaled by e^{-zeta omega t_N}: Re(conj(P) P') / |P|
    slope = omega_s * (np.conj(p) * dp).real / magnitude if magnitude > 0 else 0.0
    out = [a.sum() - 1.0, magnitude - tolerance, slope]
    for omega in (omega_lo, omega_hi):
        q, _ = _vibration_vector(a, shifted, omega, zeta)
        out += [q.real, q.imag]
    return np.array(out)


def _ei_unknowns(x: np.ndarray, period: float, omega_s: float) -> tuple[np.ndarray, np.ndarray, float, float]:
    """(amplitudes, times [s], omega_lo, omega_hi [rad/s]) from the scaled unknowns of the EI solve."""
    return x[:3], np.array([0.0, x[3] * period, x[4] * period]), x[5] * omega_s, x[6] * omega_s


def ei(frequency_hz: float, damping_ratio: float, tolerance: float = EI_TOLERANCE) -> Shaper:
    """The extra-insensitive shaper solved from its defining equations (module docstring, `ei_constraints`).

    Parameters
    ----------
    frequency_hz
        Design frequency f_s [Hz].
    damping_ratio
        Design damping ratio [-], in [0, 0.3]: beyond, three positive impulses no longer satisfy the equations
        near the undamped solution (the third amplitude heads for zero).
    tolerance
        Vibration V_tol [-] allowed at the design frequency, in (0, 0.25].

    Raises
    ------
    ValueError
        Outside those ranges, or if Newton's method does not reach the equations to 1e-12.
    """
    import scipy.optimize  # here: scipy.optimize costs every command start-up time (tests/cli/test_cli_usage.py)

    omega_s, _ = _check_design(frequency_hz, damping_ratio)
    if not (0 < tolerance <= 0.25):
        raise ValueError(f"EI vibration tolerance must be in (0, 0.25], got {tolerance!r}")
    if damping_ratio > 0.3:
        raise ValueError(f"EI shaper damping ratio must be in [0, 0.3], got {damping_ratio!r}")
    period = 2 * math.pi / omega_s
    # the undamped solution: the zero frequencies solve cos(omega T / 2) = -(1 - V) / (1 + V)
    lo = math.acos(-(1 - tolerance) / (1 + tolerance)) / math.pi
    x = np.array([(1 + tolerance) / 4, (1 - tolerance) / 2, (1 + tolerance) / 4, 0.5, 1.0, lo, 2.0 - lo])

    def equations(zeta: float) -> Callable[[np.ndarray], np.ndarray]:
        def residuals(y: np.ndarray) -> np.ndarray:
            amplitudes, times, omega_lo, omega_hi = _ei_unknowns(y, period, omega_s)
            return ei_constraints(amplitudes, times, omega_s, zeta, tolerance, omega_lo, omega_hi)

        return residuals

    # continuation in zeta from the undamped closed form, steps of at most 0.01
    for zeta in np.linspace(0.0, damping_ratio, max(2, math.ceil(damping_ratio / 0.01) + 1))[1:]:
        x = scipy.optimize.root(equations(float(zeta)), x, method="hybr", tol=1e-15).x
    x = _newton_polish(equations(damping_ratio), x)
    amplitudes, times, omega_lo, omega_hi = _ei_unknowns(x, period, omega_s)
    residual = np.max(np.abs(equations(damping_ratio)(x)))
    ordered = 0 < times[1] < times[2] and omega_lo < omega_s < omega_hi
    if not (residual <= _EI_RESIDUAL and np.all(amplitudes > 0) and ordered):
        raise ValueError(
            f"EI shaper: no solution with positive amplitudes at zeta = {damping_ratio:g}, V_tol = {tolerance:g}"
            f" (equations left at {residual:.2g})"
        )
    zeros = (omega_lo / (2 * math.pi), omega_hi / (2 * math.pi))
    return Shaper("ei", amplitudes, times, frequency_hz, damping_ratio, zeros)


def _newton_polish(function: Callable[[np.ndarray], np.ndarray], x: np.ndarray, iterations: int = 4) -> np.ndarray:
    """A few Newton steps with a centred-difference Jacobian, keeping the best iterate (round-off level)."""
    best, best_norm = x, float(np.max(np.abs(function(x))))
    for _ in range(iterations):
        h = 1e-7 * np.maximum(1.0, np.abs(x))
        jacobian = np.column_stack(
            [(function(x + h[j] * e) - function(x - h[j] * e)) / (2 * h[j]) for j, e in enumerate(np.eye(x.size))]
        )
        x = x - np.linalg.solve(jacobian, function(x))
        norm = float(np.max(np.abs(function(x))))
        if norm < best_norm:
            best, best_norm = x, norm
    return best


#: shaper name -> constructor(frequency_hz, damping_ratio)
SHAPERS: dict[str, Callable[[float, float], Shaper]] = {"zv": zv, "zvd": zvd, "mzv": mzv, "ei": ei}


def make_shaper(name: str, frequency_hz: float, damping_ratio: float) -> Shaper:
    """The shaper `name` designed at `frequency_hz` [Hz] and `damping_ratio` [-].

    Raises
    ------
    ValueError
        An unknown name (the message lists the valid ones) or a bad design point.
    """
    if name not in SHAPERS:
        raise ValueError(f"unknown shaper {name!r}; valid: {', '.join(SHAPERS)}")
    return SHAPERS[name](frequency_hz, damping_ratio)


def robustness_curve(
    shaper: Shaper, damping_ratio: float | None = None, span: float = 0.3, points: int = 121
) -> tuple[np.ndarray, np.ndarray]:
    """(frequency errors [-], residual vibration V [-]): the true frequency f_s (1 + error), error in +-span.

    Parameters
    ----------
    shaper
        The shaper.
    damping_ratio
        The true mode's damping ratio [-] (default: the design's).
    span
        Largest relative frequency error [-].
    points
        Number of errors, evenly spaced.
    """
    errors = np.linspace(-span, span, points)
    return errors, shaper.vibration(shaper.frequency_hz * (1 + errors), damping_ratio)


def insensitivity(shaper: Shaper, level: float = EI_TOLERANCE, damping_ratio: float | None = None) -> float:
    """Width [-] of the frequency band around f_s, relative to f_s, where V <= `level` [-] (0 if none).

    The band is the connected stretch of the robustness curve (sampled at 1e-4 of f_s within +-60 %, the edges
    refined by bisection) that contains the design frequency; an EI shaper's V(f_s) = V_tol counts as inside a
    band of level V_tol (to 1e-9 of it).
    """
    import scipy.optimize  # here: scipy.optimize costs every command start-up time (tests/cli/test_cli_usage.py)

    errors = np.linspace(-0.6, 0.6, 12001)
    vibration = shaper.vibration(shaper.frequency_hz * (1 + errors), damping_ratio)
    below = vibration <= level * (1 + 1e-9)
    centre = errors.size // 2  # error 0: the design frequency
    if not below[centre]:
        return 0.0
    low, high = centre, centre
    while low > 0 and below[low - 1]:
        low -= 1
    while high < errors.size - 1 and below[high + 1]:
        high += 1

    def excess(error: float) -> float:
        return float(shaper.vibration(shaper.frequency_hz * (1 + error), damping_ratio)) - level * (1 + 1e-9)

    edges = []
    for inside, outside in ((low, low - 1), (high, high + 1)):
        if 0 <= outside < errors.size:
            edges.append(scipy.optimize.brentq(excess, errors[outside], errors[inside], xtol=1e-14))
        else:
            edges.append(errors[inside])
    return float(edges[1] - edges[0])


def shape_command(breaks: np.ndarray, values: np.ndarray, shaper: Shaper) -> tuple[np.ndarray, np.ndarray]:
    """A piecewise-constant command convolved with `shaper`: (breakpoints [s], value per segment).

    The command is values[j] on [breaks[j], breaks[j+1]) (the last value held for ever); the shaped command
    is sum_i A_i command(t - t_i), again piecewise constant, its breakpoints every breaks[j] + t_i (merged
    where they coincide to 1e-12 s).

    Parameters
    ----------
    breaks
        Increasing breakpoints [s], the first 0.
    values
        Command value per segment [unit of the command], values before 0 taken as 0.
    shaper
        The shaper.
    """
    b = np.asarray(breaks, dtype=float)
    v = np.asarray(values, dtype=float)
    steps = np.diff(np.concatenate([[0.0], v]))  # the command as steps at its breakpoints
    times = (b[:, None] + shaper.times[None, :]).ravel()
    sizes = (steps[:, None] * shaper.amplitudes[None, :]).ravel()
    order = np.argsort(times, kind="stable")
    times, sizes = times[order], sizes[order]
    merged_times, merged_sizes = [times[0]], [sizes[0]]
    for t, size in zip(times[1:], sizes[1:]):
        if t - merged_times[-1] <= 1e-12:
            merged_sizes[-1] += size
        else:
            merged_times.append(t)
            merged_sizes.append(size)
    shaped = np.cumsum(merged_sizes)
    shaped[-1] = v[-1]  # every step applied in full (the amplitudes sum to 1): the command's own last value
    return np.array(merged_times), shaped


def on_grid(shaper: Shaper, dt: float) -> Shaper:
    """The shaper as a command held over steps of dt [s] can apply it: every impulse on a step boundary.

    A held command can only switch on the step grid, and rounding an impulse's time to it leaves a vibration of
    order omega dt (3 % for ZV at 195 Hz and dt = 0.1 ms). Instead each impulse off the grid is split between
    its two neighbouring steps in proportion to its distance from them (the nearest a held command comes to a
    fractional delay, error O((omega dt)^2)), and then the amplitudes are changed as little as possible (least
    squares) so that they satisfy the shaper's defining linear equations again, exactly: sum A_i = 1, zero
    vibration at each of `zeros_hz` (Re and Im of the vibration vector) and zero derivative at each of
    `flat_hz`. ZV, ZVD and EI (at its two zeros) then have as many amplitudes as equations and the solution is
    unique; MZV keeps two free. The design frequency's vibration of ZV, ZVD and MZV stays exactly 0; EI's hump
    V(f_s) = V_tol is not linear in the amplitudes and moves slightly (4.98 % instead of 5 % at the printer
    head's defaults), its zeros stay.

    Parameters
    ----------
    shaper
        The shaper (its times [s] and design).
    dt
        The step [s] of the command it shapes.

    Raises
    ------
    ValueError
        dt not positive, or so coarse against the shaper's spacing that an amplitude turns negative (the shaped
        command could then exceed the force limit).
    """
    if not (math.isfinite(dt) and dt > 0):
        raise ValueError(f"the step must be a positive number of s, got {dt!r}")
    weights: dict[int, float] = {}
    for amplitude, time in zip(shaper.amplitudes, shaper.times):
        steps = time / dt
        low = math.floor(steps + 1e-9)
        fraction = steps - low if abs(steps - round(steps)) > 1e-9 else 0.0
        weights[low] = weights.get(low, 0.0) + amplitude * (1 - fraction)
        if fraction:
            weights[low + 1] = weights.get(low + 1, 0.0) + amplitude * fraction
    grid = np.array(sorted(weights))
    times, start = grid * dt, np.array([weights[i] for i in grid])
    r = shaper.damping_ratio - 1j * math.sqrt(1 - shaper.damping_ratio**2)
    rows, rhs = [np.ones(len(times))], [1.0]
    for frequencies, derivative in ((shaper.zeros_hz, False), (shaper.flat_hz, True)):
        for frequency in frequencies:
            term = np.exp(r * 2 * math.pi * frequency * (times - times[-1]))
            if derivative:
                term = term * r * (times - times[-1]) / max(times[-1], dt)  # scaled to O(1)
            rows += [term.real, term.imag]
            rhs += [0.0, 0.0]
    equations, targets = np.array(rows), np.array(rhs)
    amplitudes = start + np.linalg.lstsq(equations, targets - equations @ start, rcond=None)[0]
    if np.any(amplitudes <= 0):
        raise ValueError(
            f"the step dt = {dt:g} s is too coarse for the {shaper.name.upper()} shaper at {shaper.frequency_hz:g} Hz"
            f" (impulses {shaper.duration / (len(shaper.times) - 1):.3g} s apart): its amplitudes on the grid turn"
            " negative; use a smaller dt"
        )
    return dataclasses.replace(shaper, amplitudes=amplitudes, times=times)
