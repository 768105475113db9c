"""Closed-form stability limits of any model, per integrator, from its modes at the operating point.

euler / implicit / implicitfast make the velocity update (M + dt D) v' = (M + dt D) v + dt f(q, v),
q' = q + dt v', with springs explicit and D the part of the damping each treats implicitly (MuJoCo's computation chapter, "Integrators"): euler only joint damping
(`dof_damping`; none with the eulerdamp flag off); implicit and implicitfast every velocity derivative
(joint and tendon damping, actuator gains on velocity...) but only inside the sparsity of M, so a tendon
between two branches of the tree keeps its diagonal implicit and its coupling explicit
(`implicit_damping` reads D from MuJoCo's own qDeriv). Per oscillatory mode (omega, zeta, real
M-normalised shape phi) the map reduces to x' = x + dt v', v' = v + dt g (-omega^2 x - 2 zeta omega v)
with g(dt) = phi' M (M + dt D)^-1 M phi; its trace condition is the limit,
dt^2 g omega^2 + 2 dt g (2 zeta omega) < 4. When D phi = c_i M phi (D keeps the mode to itself) g is
1 / (1 + dt c_i), and with zeta_i = c_i / (2 omega) the implicit and zeta_e = zeta - zeta_i the explicit
damping ratio: omega dt < 2 s + 2 sqrt(s^2 + 1), s = zeta_i - zeta_e (all implicit: the classic
2 zeta + 2 sqrt(zeta^2 + 1) of `exact.limits.stability_limit`; all explicit: -2 zeta + 2 sqrt(zeta^2 + 1)).
Otherwise (printer_head: the belt's implicit diagonal also pushes the rigid mode) the trace condition is
solved for dt. rk4 is R(dt A) on a linear model, R(z) = 1 + z + z^2/2 + z^3/6 + z^4/24, so its limit is
the first dt at which |R(dt lambda)| > 1 for a stable lambda (2.83/omega undamped); discrete has none.

`predict(linear, integrator, damping, spring)` gives the smallest per-mode limit and whether it is the
linearization's exact limit (every mode kept to itself) or an estimate; `implicit_damping` and
`explicit_stiffness` read what each integrator treats implicitly from MuJoCo at the operating point.
`predictions` gives them per integrator; springlab.exact.map_limits measures them on MuJoCo's one-step map and
springlab.studies.audit.limits confirms them.
"""

from __future__ import annotations

import copy
import dataclasses
import math
from collections.abc import Iterable

import mujoco
import numpy as np

from springlab.exact.limits import rk4_limit, stability_limit
from springlab.exact.linearize import Linearization, Mode
from springlab.exact.model_at_point import ModelAtPoint
from springlab.sim.simulate import integrator_id, quiet_mujoco


def _rk4_limit(eigenvalue: complex) -> float:
    """Largest h |lambda| [-] with |R(h lambda)| <= 1 for a stable eigenvalue (2.828 on the imaginary axis)."""
    unit = eigenvalue / abs(eigenvalue)
    unit = complex(min(unit.real, 0.0), unit.imag)  # a stable mode's round-off growth is no growth
    return rk4_limit(np.array([unit]))


#: implicit damping integrators (the velocity update with M + dt D; `implicit_damping`)
IMPLICIT_DAMPING_INTEGRATORS = ("euler", "implicit", "implicitfast")
#: an explicit share of a mode's damping below this is finite-difference noise in C [-]: C is good to
#: ~1e-8 relative (centred differences at FD_STEP), so 1e-6 leaves two decades
EXPLICIT_SHARE_NOISE = 1e-6
#: D keeps a mode to itself when |D phi - c_i M phi| <= this x |D phi| (D is MuJoCo's analytic qDeriv)
COUPLING_NOISE = 1e-9
#: the coupled trace condition is bracketed around the closed form by at most this many halvings/doublings
BRACKET_DOUBLINGS = 60


def implicit_damping(at: ModelAtPoint, integrator: str) -> np.ndarray:
    """The damping matrix D [N s/m, N m s/rad] (nv, nv) `integrator` treats implicitly at the operating point.

    euler: diag(dof_damping) (zero with the eulerdamp flag disabled); implicit / implicitfast: -qDeriv,
    MuJoCo's own analytic velocity derivative restricted to the sparsity of M (and symmetrised for
    implicitfast), read after one mj_step from the point; any other integrator: zero.
    """
    model = at.model
    nv = model.nv
    if integrator == "euler":
        if model.opt.disableflags & int(mujoco.mjtDisableBit.mjDSBL_EULERDAMP):
            return np.zeros((nv, nv))
        return np.diag(np.asarray(model.dof_damping, float))
    if integrator not in ("implicit", "implicitfast"):
        return np.zeros((nv, nv))
    work, data = at.workspace
    work.opt.integrator = integrator_id(integrator)
    work.opt.timestep = model.opt.timestep
    at.point.load(work, data)
    with quiet_mujoco():
        mujoco.mj_step(work, data)  # qDeriv is taken at the step's start state
    dense = np.zeros((nv, nv))
    for row in range(nv):
        start, count = work.D_rowadr[row], work.D_rownnz[row]
        dense[row, work.D_colind[start : start + count]] = -data.qDeriv[start : start + count]
    # implicitfast factorises a symmetrised D (MuJoCo's computation chapter); symmetric already in
    # every model seen here, so this only guards the documented contract
    return 0.5 * (dense + dense.T) if integrator == "implicitfast" else dense


def _closed_form_omega_dt(zeta_implicit: float, zeta_explicit: float) -> float:
    """omega dt [-] at which x' = x + dt v', v' = v + dt (-omega^2 x - 2 zeta omega v) / (1 + 2 zeta_i omega dt)
    leaves the unit disc: 2 s + 2 sqrt(s^2 + 1), s = zeta_i - zeta_e (module docstring)."""
    s = zeta_implicit - zeta_explicit
    root = math.hypot(s, 1.0)
    return 2 * (s + root) if s >= 0 else 2 / (root - s)  # no cancellation for a mostly explicit damping


def _mode_shape(linear: Linearization, eigenvalue: complex) -> np.ndarray:
    """The real, M-normalised position part phi (nv,) of `eigenvalue`'s eigenvector of A [1/sqrt(kg)]."""
    nv = linear.M.shape[0]
    values, vectors = linear.eigenvectors
    psi = vectors[:nv, int(np.argmin(np.abs(values - eigenvalue)))]
    phi = np.real(psi * np.exp(-1j * np.angle(psi[int(np.argmax(np.abs(psi)))])))  # a damped mode's phase
    return phi / math.sqrt(float(phi @ linear.M @ phi))


def _implicit_limit(linear: Linearization, mode: Mode, damping: np.ndarray) -> float:
    """The euler / implicit / implicitfast limit [s] of one stable oscillatory mode with implicit damping
    `damping` (D, (nv, nv)): the trace condition of the module docstring."""
    assert mode.damping_ratio is not None  # an oscillatory mode always has one
    omega, zeta = mode.rate_rad_s, float(mode.damping_ratio)
    if not np.any(damping) or zeta <= 0:
        # nothing implicit, or nothing to split: the classic bound with all of zeta explicit or implicit
        return stability_limit("euler", zeta) / omega if zeta <= 0 else _closed_form_omega_dt(0.0, zeta) / omega
    phi = _mode_shape(linear, mode.eigenvalue)
    mass_phi = linear.M @ phi
    c_total, c_implicit = float(phi @ linear.C @ phi), float(phi @ damping @ phi)  # [1/s]
    explicit_share = (c_total - c_implicit) / c_total if c_total > 0 else 0.0
    if abs(explicit_share) < EXPLICIT_SHARE_NOISE:
        explicit_share = 0.0
    zeta_explicit = zeta * explicit_share
    closed = _closed_form_omega_dt(zeta - zeta_explicit, zeta_explicit) / omega
    pushed = damping @ phi
    if np.linalg.norm(pushed - c_implicit * mass_phi) <= COUPLING_NOISE * np.linalg.norm(pushed):
        return closed
    # D couples the mode to others (the implicit solve spreads its force): g(dt) from the solve itself

    def trace_excess(dt: float) -> float:
        g = float(mass_phi @ np.linalg.solve(linear.M + dt * damping, mass_phi))
        return dt * dt * g * omega**2 + 2 * dt * g * 2 * zeta * omega - 4

    low, high = closed, closed
    try:
        for _ in range(BRACKET_DOUBLINGS):
            if trace_excess(low) <= 0:
                break
            low /= 2
        for _ in range(BRACKET_DOUBLINGS):
            if trace_excess(high) >= 0:
                break
            high *= 2
    except np.linalg.LinAlgError:  # M + dt D singular: D is not dissipative there, no closed form
        return closed
    if not (trace_excess(low) <= 0 <= trace_excess(high)):
        return closed  # a D that feeds energy in (an actuator's positive velocity gain): no bracket
    for _ in range(100):  # bisection to round-off: each evaluation is one nv x nv solve
        mid = 0.5 * (low + high)
        if mid in (low, high):
            break
        low, high = (low, mid) if trace_excess(mid) > 0 else (mid, high)
    return low


def explicit_stiffness(at: ModelAtPoint) -> np.ndarray:
    """K_e [N/m, N m/rad] (nv, nv): the stiffness left when passive springs and actuators are switched off
    (gravity, and whatever else depends on position): what `discrete` integrates explicitly. Its metric
    M + dt D + dt^2 K_i takes joint, tendon and actuator stiffness (K_i = K - K_e) implicitly."""
    work = copy.copy(at.model)
    work.opt.disableflags |= int(mujoco.mjtDisableBit.mjDSBL_SPRING) | int(mujoco.mjtDisableBit.mjDSBL_ACTUATION)
    return ModelAtPoint(work, at.point, at.step).linear.K


def _scalar_limit(k: float, c: float, d: float, k_implicit: float) -> float:
    """The first dt [s] at which one mode's map leaves the unit disc, or inf (module docstring).

    Per unit modal mass: stiffness k [1/s^2], damping c [1/s], its implicit part d [1/s] and implicit
    stiffness k_implicit [1/s^2]. The update (1 + dt d + dt^2 k_i)(v' - v) = dt (-k x - (c + dt k_i) v),
    x' = x + dt v' has det = 1 - b and trace = 2 - a - b (a = dt^2 k / m_h, b = dt (c + dt k_i) / m_h), so
    (Jury, k >= 0) it is stable while a + 2 b < 4: dt^2 (k - 2 k_i) + 2 dt (c - 2 d) - 4 < 0.
    """
    quad, lin = k - 2 * k_implicit, 2 * (c - 2 * d)
    if abs(quad) <= 1e-12 * max(abs(k), abs(k_implicit), 1e-300):
        return 4 / lin if lin > 0 else math.inf
    disc = lin * lin + 16 * quad
    if quad > 0:
        return (-lin + math.sqrt(disc)) / (2 * quad) if lin <= 0 else 8 / (lin + math.sqrt(disc))
    if lin <= 0 or disc < 0:
        return math.inf  # the parabola opens downward and never reaches 0
    return (lin - math.sqrt(disc)) / (-2 * quad)


def _keeps(matrix: np.ndarray, mass_phi: np.ndarray, phi: np.ndarray) -> bool:
    """Whether `matrix` maps the mode shape onto itself (matrix phi = s M phi up to COUPLING_NOISE)."""
    pushed = matrix @ phi
    size = float(np.linalg.norm(pushed))
    if size == 0.0:
        return True
    scale = float(phi @ pushed)
    return float(np.linalg.norm(pushed - scale * mass_phi)) <= MODAL_NOISE * max(
        size, float(np.linalg.norm(mass_phi)) * abs(scale)
    )


#: a matrix keeps a mode to itself when |X phi - (phi' X phi) M phi| <= this x |X phi| (finite differences
#: give C and K to ~1e-8 relative)
MODAL_NOISE = 1e-6


@dataclasses.dataclass(frozen=True)
class Prediction:
    """The closed-form limit of one integrator from the linearization.

    Attributes
    ----------
    limit_s
        the smallest per-mode limit [s] (None: no mode limits the timestep).
    exact
        True when every mode keeps to itself under K, C and the integrator's implicit D and K_i (the
        per-mode closed forms are then the linearization's exact limit; rk4 always); False: an
        estimate (damping or implicit terms couple modes), which may lie on either side.
    """

    limit_s: float | None
    exact: bool


def predict(
    linear: Linearization,
    integrator: str,
    damping: np.ndarray | None = None,
    spring: np.ndarray | None = None,
) -> Prediction:
    """The closed-form stability limit of `integrator` from the stable modes (module docstring).

    `damping`: the (nv, nv) damping `integrator` treats implicitly (`implicit_damping`) [N s/m, N m s/rad];
    None: all of C (joint damping, as `exact.limits.stability_limit` assumes). `spring`: the (nv, nv)
    stiffness it treats implicitly [N/m, N m/rad] (discrete: K - `explicit_stiffness`; None: zero).
    """
    stable = [m for m in linear.modes if m.kind != "rigid" and not m.physically_unstable]
    if integrator == "rk4":
        limits = [_rk4_limit(m.eigenvalue) / m.rate_rad_s for m in stable]
        finite = [limit for limit in limits if math.isfinite(limit)]
        return Prediction(min(finite) if finite else None, True)
    nv = linear.M.shape[0]
    implicit_d = linear.C if damping is None else damping
    implicit_k = np.zeros((nv, nv)) if spring is None else spring
    limits, exact = [], True
    for mode in stable:
        phi = _mode_shape(linear, mode.eigenvalue)
        mass_phi = linear.M @ phi
        exact = exact and all(_keeps(x, mass_phi, phi) for x in (linear.K, linear.C, implicit_d, implicit_k))
        k_i = float(phi @ implicit_k @ phi)
        if mode.kind == "oscillatory" and integrator != "discrete" and not np.any(implicit_k):
            assert mode.damping_ratio is not None, "an oscillatory mode has a damping ratio"
            if damping is None:
                limits.append(stability_limit(integrator, mode.damping_ratio) / mode.rate_rad_s)
            else:
                limits.append(_implicit_limit(linear, mode, damping))
            continue
        if mode.kind == "oscillatory":
            assert mode.damping_ratio is not None, "an oscillatory mode has a damping ratio"
            k, c = mode.rate_rad_s**2, 2 * float(mode.damping_ratio) * mode.rate_rad_s
        else:  # a real root: the mode shape's own stiffness and damping
            k, c = float(phi @ linear.K @ phi), float(phi @ linear.C @ phi)
        limits.append(_scalar_limit(max(k, 0.0), c, float(phi @ implicit_d @ phi), k_i))
    finite = [limit for limit in limits if math.isfinite(limit)]
    return Prediction(min(finite) if finite else None, exact)


def predictions(at: ModelAtPoint, integrators: Iterable[str]) -> dict[str, Prediction]:
    """integrator -> its closed-form limit at the operating point (`predict`), each with what it treats
    implicitly: `implicit_damping` for euler, implicit and implicitfast (and discrete, whose velocity update is
    implicitfast's), and the stiffness discrete makes implicit (K - `explicit_stiffness`)."""
    names = list(integrators)
    spring = at.linear.K - explicit_stiffness(at) if "discrete" in names else None
    out = {}
    for name in names:
        damping = None
        if name in IMPLICIT_DAMPING_INTEGRATORS or name == "discrete":
            damping = implicit_damping(at, "implicitfast" if name == "discrete" else name)
        out[name] = predict(at.linear, name, damping, spring if name == "discrete" else None)
    return out
