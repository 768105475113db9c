"""First-order harmonic balance of the forced Duffing oscillator, and the size of what it neglects.

    m x'' + c x' + k x + k3 x^3 = F cos(omega t)

Harmonic balance with x ~ a cos(omega t - phi) keeps the cubic's first harmonic, k3 a^3 cos^3 -> 3/4 k3 a^3 cos,
and gives the frequency-amplitude relation

    [(k - m omega^2 + 3/4 k3 a^2)^2 + (c omega)^2] a^2 = F^2,

a cubic in A = a^2 (`amplitudes`: its positive real roots, numpy.roots). Where it has three roots the
sweep up and the sweep down follow different branches; the band's ends are the fold points (`folds`: the
cubic's discriminant is zero there), where a sweep jumps (`branch_end`: the fold where the branch a sweep
starts on ends, followed root to root). A sine held over MuJoCo's steps of dt drives the oscillator with its
first harmonic F sinc(omega dt / 2) (`held`): the folds take `hold_dt` and evaluate that force at every
frequency they try, so each fold solves the relation with the force at its own frequency.

What it neglects, derived (`third_harmonic_ratio`, `amplitude_bound`): the cubic's other part,
1/4 k3 a^3 cos 3 theta, drives a third harmonic b3 cos 3 theta whose own balance, with the stiffness the
block sees on average, k + 3/2 k3 a^2 (k3 x^2 averaged over the fundamental is k3 a^2 / 2, times 3), gives

    r3 = |b3| / a = (k3 a^2 / 4) / |k + 3/2 k3 a^2 - 9 m omega^2 + 3 j c omega|

(near the resonance, omega^2 ~ (k + 3/4 k3 a^2) / m, this is k3 a^2 / (32 k + 21 k3 a^2): a few per cent at
k3 a^2 ~ k). Fed back, b3 changes the cubic's first harmonic from 3/4 k3 a^3 to 3/4 k3 a^3 (1 + b3 / a) + O(b3^2):
the relation's cubic coefficient is off by the relative r3. The amplitude that solves the perturbed relation
moves by

    |delta a| = |dP/d(delta)| r3 / (2 a |dP/dA|),   P(A, delta) = [(K0 + 3/4 k3 (1 + delta) A)^2 + (c omega)^2] A - F^2,

K0 = k - m omega^2, to first order in r3; `amplitude_bound` doubles it to cover the second-order remainder
(the next terms are r3^2 relative, below r3 while r3 < 1/2). At a fold dP/dA = 0: the bound is infinite
there, as it must be (the amplitude's condition number is). The folds move with the same perturbation:
`folds` at k3 (1 +- r3(fold)) bracket the fold a first-order relation can promise.

`cubic_oscillator` reads m, c, k, k3 and the input's force per unit back from a one-degree-of-freedom MuJoCo
model (its forward dynamics sampled and fitted by a cubic polynomial, exact for a polynomial spring), and
says None when the model is not of that form.
"""

from __future__ import annotations

import copy
import dataclasses
import math

import mujoco
import numpy as np

from springlab.sim.simulate import quiet_mujoco

from .linearize import OperatingPoint

_EPS = float(np.finfo(float).eps)
#: a fit residual within this many eps of the force scale is round-off (the model is a cubic oscillator)
FIT_ROUNDING = 1e4
#: grid points per band for the discriminant's sign changes before brentq refines them
FOLD_GRID = 2000


@dataclasses.dataclass(frozen=True)
class Duffing:
    """m x'' + c x' + k x + k3 x^3 = gain u: a cubic oscillator read from a model.

    Attributes
    ----------
    m
        mass [kg] (or inertia [kg m^2]).
    c
        viscous damping [N s/m].
    k
        linear stiffness [N/m].
    k3
        cubic stiffness [N/m^3] (> 0 hardening, < 0 softening).
    gain
        force per unit of the input [N per input unit] (a motor's gear; 1 for a joint force).
    """

    m: float
    c: float
    k: float
    k3: float
    gain: float

    def to_dict(self) -> dict[str, float]:
        """{"m", "c", "k", "k3", "gain"}."""
        return dataclasses.asdict(self)


def _coefficients(duffing: Duffing, force: float, omega: float, k3: float) -> np.ndarray:
    """The relation as a cubic in A = a^2, highest power first."""
    k0 = duffing.k - duffing.m * omega**2
    kappa = 0.75 * k3
    return np.array([kappa**2, 2 * kappa * k0, k0**2 + (duffing.c * omega) ** 2, -(force**2)])


def amplitudes(duffing: Duffing, force: float, omega: float) -> np.ndarray:
    """The first-harmonic amplitudes a [m] > 0 that solve the relation at omega [rad/s] for the force
    amplitude `force` [N], ascending (one or three; numpy.roots of the cubic in a^2)."""
    coefficients = _coefficients(duffing, force, omega, duffing.k3)
    if coefficients[0] == 0:  # linear: one root
        return np.array([abs(force) / math.hypot(duffing.k - duffing.m * omega**2, duffing.c * omega)])
    roots = np.roots(coefficients)
    scale = max(float(np.max(np.abs(roots))), 1e-300)
    real = roots[(np.abs(roots.imag) <= 1e-7 * scale) & (roots.real > 0)].real
    return np.sort(np.sqrt(real))


def held(force: float, omega: float, hold_dt: float = 0.0) -> float:
    """The first harmonic [N] of a sine of amplitude `force` [N] at omega [rad/s] held over steps of `hold_dt`
    [s], force sinc(omega hold_dt / 2) (MuJoCo holds a control over each step); `force` itself when hold_dt is
    0 (a continuous sine)."""
    return force * float(np.sinc(omega * hold_dt / (2 * math.pi))) if hold_dt else force


def _discriminant(duffing: Duffing, force: float, omega: float, k3: float) -> float:
    """The cubic's discriminant, normalized by its leading coefficient (> 0: three real roots)."""
    a, b, c, d = _coefficients(duffing, force, omega, k3)
    b, c, d = b / a, c / a, d / a
    return float(18 * b * c * d - 4 * b**3 * d + b**2 * c**2 - 4 * c**3 - 27 * d**2)


def folds(
    duffing: Duffing, force: float, band_hz: tuple[float, float], k3: float | None = None, *, hold_dt: float = 0.0
) -> list[float]:
    """The fold frequencies [Hz] inside the band: where the relation's three roots begin or end
    (its discriminant changes sign, refined by scipy.optimize.brentq), ascending; `k3` [N/m^3] overrides
    the oscillator's (None: its own); the force [N] held over steps of `hold_dt` [s] (`held`)."""
    from scipy.optimize import brentq

    k3 = duffing.k3 if k3 is None else k3
    if k3 == 0:
        return []
    grid = 2 * math.pi * np.geomspace(band_hz[0], band_hz[1], FOLD_GRID)
    values = np.array([_discriminant(duffing, held(force, w, hold_dt), w, k3) for w in grid])
    out = []
    for i in np.nonzero(np.sign(values[:-1]) * np.sign(values[1:]) < 0)[0]:
        omega = brentq(
            lambda w: _discriminant(duffing, held(force, w, hold_dt), w, k3),
            grid[i],
            grid[i + 1],
            xtol=1e-14,
            rtol=1e-13,
        )
        out.append(omega / (2 * math.pi))
    return out


def third_harmonic_ratio(duffing: Duffing, a: float, omega: float) -> float:
    """r3 = |b3| / a [-]: the third harmonic the first-order balance neglects (module docstring)."""
    stiffness = duffing.k + 1.5 * duffing.k3 * a**2 - 9 * duffing.m * omega**2
    return abs(0.25 * duffing.k3 * a**2) / abs(complex(stiffness, 3 * duffing.c * omega))


def amplitude_bound(duffing: Duffing, force: float, a: float, omega: float) -> float:
    """|delta a| [m]: twice the first-order move of the root a [m] at omega [rad/s] when the cubic term is
    off by the relative r3 (module docstring); inf at a fold."""
    big_a = a * a
    k0 = duffing.k - duffing.m * omega**2
    kappa = 0.75 * duffing.k3
    inner = k0 + kappa * big_a
    d_big_a = inner**2 + 2 * kappa * big_a * inner + (duffing.c * omega) ** 2
    d_delta = 2 * inner * kappa * big_a * big_a
    if d_big_a == 0:
        return math.inf
    shift = abs(d_delta / d_big_a) * third_harmonic_ratio(duffing, a, omega) / (2 * a)
    return 2.0 * shift


def branch_end(
    duffing: Duffing,
    force: float,
    start_hz: float,
    stop_hz: float,
    start_amplitude: float,
    k3: float | None = None,
    *,
    hold_dt: float = 0.0,
) -> float | None:
    """Where the branch a sweep from `start_hz` to `stop_hz` [Hz] (up or down) rides ends [Hz]: the relation's root
    nearest `start_amplitude` [m] at the start, followed root to root (the nearest in log a) over FOLD_GRID
    frequencies until it merges with the middle root and vanishes (a fold, refined by scipy.optimize.brentq on
    the discriminant); None: it reaches `stop_hz`. `k3` [N/m^3] overrides the oscillator's; the force [N] is held
    over steps of `hold_dt` [s] (`held`, evaluated at each frequency tried)."""
    from scipy.optimize import brentq

    k3 = duffing.k3 if k3 is None else k3
    model = dataclasses.replace(duffing, k3=k3)
    grid = np.geomspace(start_hz, stop_hz, FOLD_GRID)
    omega0 = 2 * math.pi * grid[0]
    roots = amplitudes(model, held(force, omega0, hold_dt), omega0)
    tracked = float(roots[np.argmin(np.abs(np.log(roots / start_amplitude)))])
    old = roots
    for before, after in zip(grid[:-1], grid[1:]):
        omega = 2 * math.pi * after
        new = amplitudes(model, held(force, omega, hold_dt), omega)
        if len(old) == 3 and len(new) == 1:
            # the two closest roots merged; if the tracked one was among them, its branch ends here
            merged = (0, 1) if old[1] - old[0] < old[2] - old[1] else (1, 2)
            index = int(np.argmin(np.abs(np.log(old / tracked))))
            if index in merged:
                fold = brentq(
                    lambda w: _discriminant(model, held(force, w, hold_dt), w, k3),
                    2 * math.pi * min(before, after),
                    2 * math.pi * max(before, after),
                    xtol=1e-14,
                    rtol=1e-13,
                )
                return fold / (2 * math.pi)
        tracked = float(new[np.argmin(np.abs(np.log(new / tracked)))])
        old = new
    return None


def fold_bracket(
    duffing: Duffing, force: float, start_hz: float, stop_hz: float, start_amplitude: float, *, hold_dt: float = 0.0
) -> tuple[float, float, float] | None:
    """(f, lowest, highest) [Hz]: `branch_end`, and where it falls with k3 (1 +- 2 r3), r3 at the fold's own
    amplitude and frequency: the jump first-order balance can promise (None: the branch does not end); the
    force [N] held over steps of `hold_dt` [s] (`held`)."""
    f = branch_end(duffing, force, start_hz, stop_hz, start_amplitude, hold_dt=hold_dt)
    if f is None:
        return None
    omega = 2 * math.pi * f
    near = amplitudes(duffing, held(force, omega * (1 + 1e-9), hold_dt), omega * (1 + 1e-9))
    if near.size != 3:
        near = amplitudes(duffing, held(force, omega * (1 - 1e-9), hold_dt), omega * (1 - 1e-9))
    a = float(np.median(near))  # the double root is the middle one just inside the three-root band
    r3 = third_harmonic_ratio(duffing, a, omega)
    moved = [f]
    for sign in (-1.0, 1.0):
        k3 = duffing.k3 * (1 + sign * 2 * r3)
        other = branch_end(duffing, force, start_hz, stop_hz, start_amplitude, k3, hold_dt=hold_dt)
        if other is not None:
            moved.append(other)
    return f, min(moved), max(moved)


def cubic_oscillator(
    model: mujoco.MjModel, point: OperatingPoint, kind: str, index: int, reach: float
) -> Duffing | None:
    """m, c, k, k3 and the input's gain of a one-degree-of-freedom model, read from MuJoCo's forward dynamics;
    None unless it is m x'' + c x' + k x + k3 x^3 = gain u (to FIT_ROUNDING eps of the force scale).

    The block's force -m qacc is sampled at 9 positions over +-reach [m or rad] around the operating point
    (at rest) and at 9 velocities (at the point) and fitted by polynomials (numpy.polynomial): degree 3 in x,
    degree 1 in v; a quadratic term, a residual above round-off or a velocity term that is not linear means
    another model. The input's gain is the force of a unit input ('ctrl' or 'force', index as
    springlab.exact.linearize.input_column).
    """
    if model.nv != 1 or model.nq != 1 or model.na != 0 or not (reach > 0 and math.isfinite(reach)):
        return None
    work = copy.copy(model)
    work.opt.integrator = int(mujoco.mjtIntegrator.mjINT_EULER)  # the continuous forward pass
    data = mujoco.MjData(work)

    def acceleration(x: float, v: float, u: float = 0.0, on: str = kind) -> float:
        point.load(work, data)
        data.qpos[0] = point.qpos[0] + x
        data.qvel[0] = point.qvel[0] + v
        if on == "ctrl":
            data.ctrl[index] += u
        else:
            data.qfrc_applied[0] += u
        mujoco.mj_forward(work, data)
        return float(data.qacc[0])

    with quiet_mujoco():
        # the mass as MuJoCo's dynamics sees it (armature included): a unit generalized force's acceleration
        mass = 2.0 / (acceleration(0.0, 0.0, 1.0, "force") - acceleration(0.0, 0.0, -1.0, "force"))
        xs = reach * np.linspace(-1.0, 1.0, 9)
        force = np.array([-mass * acceleration(x, 0.0) for x in xs])
        spring = np.polynomial.Polynomial.fit(xs, force, 3).convert()
        stiffness = abs(float(spring.deriv()(0.0))) + abs(float(spring.deriv(3)(0.0))) * reach**2
        speed = reach * math.sqrt(stiffness / mass) if stiffness > 0 else reach  # the motion's own speed scale
        vs = speed * np.linspace(-1.0, 1.0, 9)
        drag = np.array([-mass * acceleration(0.0, v) for v in vs])
        gain = mass * (acceleration(0.0, 0.0, 1.0) - acceleration(0.0, 0.0, -1.0)) / 2.0
    damper = np.polynomial.Polynomial.fit(vs, drag, 1).convert()
    k0, k1, k2, k3 = (float(v) for v in np.pad(np.asarray(spring.coef, float), (0, 4))[:4])
    d0, c = (float(v) for v in np.pad(np.asarray(damper.coef, float), (0, 2))[:2])
    scale = max(float(np.max(np.abs(force))), float(np.max(np.abs(drag))), 1e-300)
    rounding = FIT_ROUNDING * _EPS * scale
    residual = max(float(np.max(np.abs(spring(xs) - force))), float(np.max(np.abs(damper(vs) - drag))))
    if residual > rounding or abs(k2) * reach**2 > rounding or abs(k0) > rounding or abs(d0) > rounding:
        return None
    if abs(k3) * reach**3 <= rounding:
        k3 = 0.0  # a linear spring: the fit's round-off is no cubic term
    return Duffing(m=mass, c=float(c), k=float(k1), k3=float(k3), gain=float(gain))
