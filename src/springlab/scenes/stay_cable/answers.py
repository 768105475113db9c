"""The engineer's questions about a stay and its damper, answered exactly: which damper, how much it buys, what
it does to the RMS in the wind, and the smallest damper that stops rain-wind vibration.

Each answer comes three ways where the theory has three: the continuum with its damper (the transcendental
equation, springlab.exact.cable), the N-element model the run steps (read back from the compiled model) and
the universal curve zeta / (a / L) = kappa / (1 + kappa^2) (the engineer's rule of thumb; its range of validity
in docs/scenes/stay_cable.md).
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Callable

import numpy as np

from springlab.exact import cable as cb

from .modal import modes
from .readback import CableModel


def _optimize():  # noqa: ANN202 - the module
    """scipy.optimize, imported on first use: every command imports the scene registry, which must stay light."""
    import scipy.optimize

    return scipy.optimize


#: how far around the universal optimum the N-element model's best damper is searched (a factor either side)
SEARCH_FACTOR = 30.0
#: the search's tolerance on log c (the ratio is flat at its optimum: c to about sqrt of it)
SEARCH_XATOL = 1e-9
#: machine epsilon
EPS = float(np.finfo(float).eps)


@dataclasses.dataclass(frozen=True)
class DamperOptimum:
    """The damper that damps mode 1 most at the damper's position, and the ratio it gives.

    Attributes
    ----------
    coefficient_continuum, ratio_continuum
        the continuum's: the transcendental equation, maximized (c [N s/m], zeta [-]).
    coefficient_exact, ratio_exact
        the N-element model's: the model as it is (its intrinsic damping included), the damper varied.
    coefficient_universal, ratio_universal
        the universal curve's: c = sqrt(T m) L / (pi a), zeta = a / (2 L).
    """

    coefficient_continuum: float
    ratio_continuum: float
    coefficient_exact: float
    ratio_exact: float
    coefficient_universal: float
    ratio_universal: float


def mode_1_ratio(lumped: cb.LumpedCable) -> float:
    """Mode 1's damping ratio [-] of an N-element model (its slowest oscillatory mode)."""
    return float(lumped.complex_modes().damping_ratios[0])


def damper_optimum(cable: CableModel) -> DamperOptimum:
    """Mode 1's best damper at the damper's node, three ways (see DamperOptimum).

    The N-element model's optimum is a bounded Brent search on log c of mode 1's damping ratio, each ratio from
    Newton on the model's determinant (`LumpedCable.eigenvalue_near`, started at the continuum's mode 1 with the same
    damper): a tenth of a dense eigensolve of the state matrix each. The root at the optimum is confirmed to be
    mode 1 of the dense eigenvalues (within their error, N eps |lambda_max|); where it is not, or Newton does not
    apply (a damping matrix that is not diagonal) or fails, the search is made again on the dense eigenvalues.
    """
    position = cable.damper_node * cable.cable.spacing(cable.size)  # where the model's damper sits
    ratio = position / cable.cable.length
    eta, zeta = cb.exact_optimum(1, ratio)
    eta_u, zeta_u = cb.universal_optimum(1, ratio)
    impedance = cable.cable.impedance
    guess = math.log(eta_u * impedance)
    bounds = (guess - math.log(SEARCH_FACTOR), guess + math.log(SEARCH_FACTOR))
    try:
        coefficient, best = _optimum_by_newton(cable, bounds)
    except ArithmeticError:
        coefficient, best = _optimum_by_eigenvalues(cable, bounds)
    return DamperOptimum(eta * impedance, zeta, coefficient, best, eta_u * impedance, zeta_u)


def _search(negative_ratio: Callable[[float], float], bounds: tuple[float, float]) -> tuple[float, float]:
    """(log c, zeta [-]) at the least of `negative_ratio` (of log c [ln N s/m]) within `bounds`: bounded Brent."""
    found = _optimize().minimize_scalar(
        negative_ratio, bounds=bounds, method="bounded", options={"xatol": SEARCH_XATOL}
    )
    return float(found.x), -float(found.fun)


def _optimum_by_eigenvalues(cable: CableModel, bounds: tuple[float, float]) -> tuple[float, float]:
    """The optimum's (c, zeta), each ratio from the dense eigenvalues of the state matrix."""
    bare = cable.without_damper()
    log_c, best = _search(lambda log_c: -mode_1_ratio(bare.with_damper(cable.damper_node, math.exp(log_c))), bounds)
    return math.exp(log_c), best


def _optimum_by_newton(cable: CableModel, bounds: tuple[float, float]) -> tuple[float, float]:
    """The optimum's (c, zeta), each ratio by Newton on the determinant; ArithmeticError where that is not mode 1."""
    bare = cable.without_damper()
    position = cable.damper_node * cable.cable.spacing(cable.size)
    roots: dict[float, complex] = {}

    def negative_ratio(log_c: float) -> float:
        coefficient = math.exp(log_c)
        start = cb.damped_eigenvalue(cable.cable, 1, position, coefficient)
        root = roots[log_c] = bare.with_damper(cable.damper_node, coefficient).eigenvalue_near(start)
        return root.real / abs(root)

    log_c, best = _search(negative_ratio, bounds)
    coefficient, root = math.exp(log_c), roots.get(log_c)
    dense = bare.with_damper(cable.damper_node, coefficient).complex_modes()
    values = np.concatenate([dense.oscillatory, dense.overdamped])
    error = bare.size * EPS * float(np.max(np.abs(values)))
    if root is None or not dense.oscillatory.size or abs(root - dense.oscillatory[0]) > error:
        raise ArithmeticError(f"Newton's root at the optimum {root!r} is not mode 1 {dense.oscillatory[:1]!r}")
    return coefficient, best


def continuum_mode_1(cable: CableModel) -> complex:
    """lambda_1 [1/s] of the continuum with the model's damper where the model puts it (its node's position)."""
    position = cable.damper_node * cable.cable.spacing(cable.size)
    return cb.damped_eigenvalue(cable.cable, 1, position, cable.damper_coefficient)


def universal_mode_1_ratio(cable: CableModel) -> float:
    """Mode 1's damping ratio [-] by the universal curve at the model's damper."""
    position = cable.damper_node * cable.cable.spacing(cable.size)
    return cb.universal_damping_ratio(
        1, position / cable.cable.length, cable.damper_coefficient / cable.cable.impedance
    )


@dataclasses.dataclass(frozen=True)
class Stabilising:
    """The smallest damper at the damper's node that keeps every mode from growing.

    Attributes
    ----------
    coefficient
        c_stop [N s/m] of the N-element model (the lower root of its growth rate, Brent to 1e-12): 0 when the
        cable without a damper does not grow; nan when no damper there stops it.
    universal
        the universal curve's estimate [N s/m]: each growing mode k's deficit -zeta_k met by the lower root of
        (a / L) kappa / (1 + kappa^2), kappa = eta k pi a / L (nan when the deficit exceeds the curve's maximum).
    growth_without
        the growth rate [1/s] of the cable without a damper.
    """

    coefficient: float
    universal: float
    growth_without: float


def stabilising(cable: CableModel) -> Stabilising:
    """The damper that stops rain-wind's growth at the damper's node (see Stabilising)."""
    bare = cable.without_damper()
    position = cable.damper_node * cable.cable.spacing(cable.size)
    ratio = position / cable.cable.length
    needed = 0.0
    for mode in modes(bare):
        if mode.growth_rate <= 0:
            continue
        deficit = -mode.damping_ratio / ratio  # kappa / (1 + kappa^2) must reach it
        if deficit > 0.5:
            needed = math.nan
            break
        kappa = (1.0 - math.sqrt(1.0 - 4.0 * deficit**2)) / (2.0 * deficit)
        needed = max(needed, kappa / (mode.number * math.pi * ratio) * cable.cable.impedance)
    c_stop = cb.stabilising_damper(bare, cable.damper_node, guess=needed, tendons=cable.aero)
    return Stabilising(c_stop, needed, bare.growth_rate())
