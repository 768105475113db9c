"""Input shaping and the damped bang-bang move on the printer head's belt, against references built here.

References: each shaper's defining equations evaluated here with cos/sin sums (not the module's complex
form), the two-mass model's exact motion by scipy.linalg.expm of the augmented system (q_c, q_m, v_c, v_m, F),
and raw MuJoCo runs (mujoco.rollout over a list of models, no scene API). The MuJoCo runs are held to an error
bound derived from RK4's order: on a linear system RK4 multiplies each mode by R(z) = 1 + z + ... + z^4/24,
z = lambda dt, where the exact map is e^z, and |R(z) - e^z| <= |z|^5 / 120 / (1 - |z| / 6); with a control
constant over each step the belt mode's error grows by at most that times its distance from the step's
equilibrium, each step (|R| < 1 on the damped mode; the rigid-body motion, a quadratic, RK4 integrates exactly).
"""

import math

import mujoco
import numpy as np
import pytest
import scipy.linalg
from mujoco import rollout

import springlab.sim.model_files
from helpers.printer_head import BAND, DISTANCE, F_N, FORCE, M_C, M_M, MU, OMEGA, TOTAL, ZETA, C, K
from springlab.exact import positioning, shaping

EPS = np.finfo(float).eps


def _vibration(amplitudes, times, omega, zeta):
    """Residual vibration written out: e^{-zeta w t_N} sqrt((sum A e^{zeta w t} cos w_d t)^2 + (... sin ...)^2)."""
    omega = np.asarray(omega, dtype=float)[..., None]
    decay = np.exp(zeta * omega * (times - times[-1]))
    angle = omega * math.sqrt(1 - zeta**2) * times
    return np.hypot(np.sum(amplitudes * decay * np.cos(angle), -1), np.sum(amplitudes * decay * np.sin(angle), -1))


def _vibration_slope(amplitudes, times, omega, zeta):
    """d/domega of _vibration, differentiated term by term (cos/sin form)."""
    root = math.sqrt(1 - zeta**2)
    decay = np.exp(zeta * omega * (times - times[-1]))
    angle = omega * root * times
    c = np.sum(amplitudes * decay * np.cos(angle))
    s = np.sum(amplitudes * decay * np.sin(angle))
    dc = np.sum(amplitudes * decay * (zeta * (times - times[-1]) * np.cos(angle) - root * times * np.sin(angle)))
    ds = np.sum(amplitudes * decay * (zeta * (times - times[-1]) * np.sin(angle) + root * times * np.cos(angle)))
    return (c * dc + s * ds) / math.hypot(c, s)


# -- the shapers' defining equations -------------------------------------------------------------------------


@pytest.mark.parametrize("name", ["zv", "zvd", "mzv"])
@pytest.mark.parametrize("zeta", [0.0, ZETA, 0.2])
def test_zero_vibration_shapers_cancel_the_design_mode(name, zeta):
    shaper = shaping.make_shaper(name, F_N, zeta)
    a, t = shaper.amplitudes, shaper.times
    assert np.all(a > 0) and a.sum() == pytest.approx(1.0, abs=4 * EPS) and t[0] == 0.0
    # the vibration vector's terms are O(1): cancellation to a few ulps of them
    assert _vibration(a, t, OMEGA, zeta) <= 16 * EPS
    omega_d = OMEGA * math.sqrt(1 - zeta**2)
    spacing = {"zv": math.pi, "zvd": math.pi, "mzv": 0.75 * math.pi}[name] / omega_d
    assert np.diff(t) == pytest.approx(spacing, rel=4 * EPS)
    assert shaper.duration == pytest.approx(spacing * (len(t) - 1), rel=4 * EPS)


def test_zvd_also_has_zero_slope_at_the_design():
    shaper = shaping.zvd(F_N, ZETA)
    # the slope of |P| is undefined where P = 0; that of |P|^2 / |P'| is the derivative condition: P' = 0 too
    root = math.sqrt(1 - ZETA**2)
    r = ZETA - 1j * root
    derivative = np.sum(shaper.amplitudes * shaper.times * r * np.exp(r * OMEGA * shaper.times))
    assert abs(derivative) * OMEGA <= 64 * EPS * np.sum(
        shaper.amplitudes * shaper.times * OMEGA * np.exp(ZETA * OMEGA * shaper.times)
    )


@pytest.mark.parametrize("zeta", [0.0, ZETA, 0.1])
def test_ei_satisfies_its_defining_equations_to_1e_12(zeta):
    shaper = shaping.ei(F_N, zeta, tolerance=0.05)
    a, t = shaper.amplitudes, shaper.times
    assert np.all(a > 0) and abs(a.sum() - 1) <= 1e-12
    assert abs(_vibration(a, t, OMEGA, zeta) - 0.05) <= 1e-12
    assert abs(_vibration_slope(a, t, OMEGA, zeta) * OMEGA) <= 1e-12
    low, high = (2 * math.pi * f for f in shaper.zeros_hz)
    assert low < OMEGA < high
    assert _vibration(a, t, low, zeta) <= 1e-12 and _vibration(a, t, high, zeta) <= 1e-12
    # the zero-vibration frequencies bound a hump: V_tol is the largest vibration between them
    between = _vibration(a, t, np.linspace(low, high, 2001), zeta)
    assert between.max() <= 0.05 + 1e-12


def test_undamped_ei_is_the_closed_form():
    shaper = shaping.ei(F_N, 0.0, tolerance=0.05)
    period = 1 / F_N
    assert shaper.amplitudes == pytest.approx([1.05 / 4, 0.95 / 2, 1.05 / 4], abs=1e-12)
    assert shaper.times == pytest.approx([0.0, period / 2, period], abs=1e-12 * period)


def test_robustness_curve_is_the_residual_vibration_over_30_percent():
    for name in shaping.SHAPERS:
        shaper = shaping.make_shaper(name, F_N, ZETA)
        errors, curve = shaping.robustness_curve(shaper, span=0.3, points=61)
        assert errors[0] == -0.3 and errors[-1] == 0.3
        expected = _vibration(shaper.amplitudes, shaper.times, OMEGA * (1 + errors), ZETA)
        assert np.max(np.abs(curve - expected)) <= 1e-13


def test_robust_shapers_are_wider_than_zv():
    widths = {name: shaping.insensitivity(shaping.make_shaper(name, F_N, ZETA), 0.05) for name in shaping.SHAPERS}
    # every point strictly inside the band has V <= 5 %, and the band ends where V = 5 %
    for name, width in widths.items():
        shaper = shaping.make_shaper(name, F_N, ZETA)
        errors = np.linspace(-0.3, 0.3, 6001)
        inside = _vibration(shaper.amplitudes, shaper.times, OMEGA * (1 + errors), ZETA) <= 0.05 * (1 + 1e-9)
        run = np.flatnonzero(inside)
        assert width == pytest.approx(errors[run[-1]] - errors[run[0]], abs=2e-4)  # the grid's spacing, twice
    assert widths["zv"] < widths["mzv"] < widths["zvd"] < widths["ei"]


def test_shaped_command_keeps_the_force_limit_and_the_distance():
    breaks, accelerations = positioning.bang_bang(DISTANCE, 2 * math.sqrt(DISTANCE * TOTAL / FORCE))
    for name in shaping.SHAPERS:
        shaper = shaping.make_shaper(name, F_N, ZETA)
        b, a = shaping.shape_command(breaks, accelerations, shaper)
        assert np.max(np.abs(a)) <= FORCE / TOTAL * (1 + 4 * EPS)
        assert a[-1] == 0.0 and b[-1] == pytest.approx(breaks[-1] + shaper.duration, rel=4 * EPS)
        durations = np.diff(b)
        velocity = np.concatenate([[0.0], np.cumsum(a[:-1] * durations)])
        travel = np.sum(velocity[:-1] * durations + a[:-1] * durations**2 / 2)
        assert velocity[-1] == pytest.approx(0.0, abs=64 * EPS * FORCE / TOTAL * b[-1])
        assert travel == pytest.approx(DISTANCE, rel=1e-13)


def test_unknown_shaper_names_the_valid_ones():
    with pytest.raises(ValueError, match="unknown shaper 'zvdd'; valid: zv, zvd, mzv, ei"):
        shaping.make_shaper("zvdd", F_N, ZETA)
    with pytest.raises(ValueError, match="shaper frequency must be a positive"):
        shaping.zv(-1.0, ZETA)


# -- MuJoCo runs of shaped moves -------------------------------------------------------------------------------


def _shaped_runs(shaper, errors, dt, n_half, force):
    """Raw MuJoCo runs of the shaped bang-bang move on belts detuned by `errors`; (end states, steps, controls).

    The belt's stiffness is scaled by (1 + error)^2 and its damping by (1 + error): the same damping ratio at
    the frequency omega (1 + error). Every switch lies on the step grid (n_half and the shaper's times are
    whole steps), so the held control is the shaped force exactly.
    """
    spec = mujoco.MjSpec.from_file(str(springlab.sim.model_files.path("printer_head")))
    models = []
    for error in errors:
        spec.tendon("belt").stiffness = [K * (1 + error) ** 2, 0.0, 0.0]
        spec.tendon("belt").damping = [C * (1 + error), 0.0, 0.0]
        model = spec.compile()
        model.opt.timestep = dt
        models.append(model)
    offsets = np.round(shaper.times / dt).astype(int)
    assert np.all(np.abs(offsets * dt - shaper.times) <= 1e-9 * dt)
    steps = 2 * n_half + offsets[-1]
    control = np.zeros(steps)
    for amplitude, offset in zip(shaper.amplitudes, offsets):
        control[offset : offset + n_half] += amplitude * force
        control[offset + n_half : offset + 2 * n_half] -= amplitude * force
    data = mujoco.MjData(models[0])
    state0 = np.zeros(mujoco.mj_stateSize(models[0], mujoco.mjtState.mjSTATE_FULLPHYSICS))
    mujoco.mj_getState(models[0], data, state0, mujoco.mjtState.mjSTATE_FULLPHYSICS)
    states, _ = rollout.rollout(models, [mujoco.MjData(m) for m in models], state0, control[None, :, None])
    return states[:, -1, :], steps, control


def _envelope(q_c, q_m, v_c, v_m, omega, zeta):
    """The carriage's ring-down envelope [m] from a force-free state: (m_m / M) hypot(s, (s' + sigma s) / omega_d)."""
    s, rate = q_m - q_c, v_m - v_c
    return M_M / TOTAL * math.hypot(s, (rate + zeta * omega * s) / (omega * math.sqrt(1 - zeta**2)))


def _expm_move(stiffness, damping, segments):
    """Exact (q_c, q_m, v_c, v_m) after force segments [(duration [s], force [N]), ...] from rest (expm)."""
    a = np.zeros((5, 5))
    a[0:2, 2:4] = np.eye(2)
    a[2, :2], a[3, :2] = np.array([-1.0, 1.0]) * stiffness / M_C, np.array([1.0, -1.0]) * stiffness / M_M
    a[2, 2:4], a[3, 2:4] = np.array([-1.0, 1.0]) * damping / M_C, np.array([1.0, -1.0]) * damping / M_M
    a[3, 4] = 1 / M_M
    z = np.zeros(5)
    for duration, force in segments:
        z[4] = force
        z = scipy.linalg.expm(a * duration) @ z
    return z[:4]


def _rk4_bound(stiffness, damping, dt, control, omega):
    """Derived bound [m] on RK4's error in the carriage's ring-down envelope over this control sequence.

    Sum over steps of |R(z) - e^z| (|z| = omega dt) times the belt mode's envelope about the step's static
    equilibrium, the latter from the exact (expm) motion at every step.
    """
    z = omega * dt
    per_step = z**5 / 120 / (1 - z / 6)
    a = np.zeros((5, 5))
    a[0:2, 2:4] = np.eye(2)
    a[2, :2], a[3, :2] = np.array([-1.0, 1.0]) * stiffness / M_C, np.array([1.0, -1.0]) * stiffness / M_M
    a[2, 2:4], a[3, 2:4] = np.array([-1.0, 1.0]) * damping / M_C, np.array([1.0, -1.0]) * damping / M_M
    a[3, 4] = 1 / M_M
    step = scipy.linalg.expm(a * dt)
    zeta = damping / (2 * math.sqrt(stiffness * MU))
    state, total = np.zeros(5), 0.0
    for force in control:
        state[4] = force
        stretch_eq = force * M_C / (TOTAL * stiffness)  # the belt's static stretch under this force
        q_c, q_m, v_c, v_m = state[:4]
        total += per_step * _envelope(q_c + stretch_eq, q_m, v_c, v_m, omega, zeta)
        state = step @ state
    return total


@pytest.mark.parametrize("name", ["zv", "zvd"])
def test_mujoco_shaped_moves_leave_the_closed_form_residual(name):
    """20 belt frequencies within +-30 % of the design: MuJoCo's residual = V(omega) x the unshaped move's."""
    shaper = shaping.make_shaper(name, F_N, ZETA)
    per_half_period = 52
    dt = math.pi / (OMEGA * math.sqrt(1 - ZETA**2)) / per_half_period  # the shaper's times are whole steps
    n_half = math.ceil(math.sqrt(DISTANCE * TOTAL / FORCE) / dt)
    force = TOTAL * DISTANCE / (n_half * dt) ** 2  # the move ends at D on the grid, within the force limit
    errors = np.concatenate([np.linspace(-0.3, 0.3, 19), [0.0]])
    ends, steps, control = _shaped_runs(shaper, errors, dt, n_half, force)
    nq = 2
    for error, end in zip(errors, ends):
        omega, stiffness, damping = OMEGA * (1 + error), K * (1 + error) ** 2, C * (1 + error)
        q_c, q_m = end[1 : 1 + nq]
        v_c, v_m = end[1 + nq : 1 + 2 * nq]
        measured = _envelope(q_c, q_m, v_c, v_m, omega, ZETA)
        unshaped = _envelope(
            *_expm_move(stiffness, damping, [(n_half * dt, force), (n_half * dt, -force)]), omega, ZETA
        )
        expected = float(_vibration(shaper.amplitudes, shaper.times, omega, ZETA)) * unshaped
        bound = _rk4_bound(stiffness, damping, dt, control, omega) + 64 * EPS * DISTANCE * steps
        assert abs(measured - expected) <= bound, (error, measured, expected, bound)
        if expected > 1e3 * bound:
            assert abs(measured - expected) <= 1e-3 * expected
        if error == 0.0:
            assert measured <= bound  # nothing left at the design frequency, to the run's error


def test_mujoco_ei_move_on_the_grid_matches_its_realized_impulses():
    """EI's times are not whole steps of any common grid: run it rounded to the grid and compare with the closed
    form of the impulses actually applied (the formula holds for any impulse sequence)."""
    shaper = shaping.ei(F_N, ZETA)
    dt = 1e-4 / 2
    realized = shaping.Shaper("ei", shaper.amplitudes, np.round(shaper.times / dt) * dt, F_N, ZETA)
    n_half = math.ceil(math.sqrt(DISTANCE * TOTAL / FORCE) / dt)
    force = TOTAL * DISTANCE / (n_half * dt) ** 2
    errors = np.array([-0.2, -0.05, 0.0, 0.05, 0.2])
    ends, steps, control = _shaped_runs(realized, errors, dt, n_half, force)
    for error, end in zip(errors, ends):
        omega, stiffness, damping = OMEGA * (1 + error), K * (1 + error) ** 2, C * (1 + error)
        measured = _envelope(*end[1:5], omega, ZETA)
        unshaped = _envelope(
            *_expm_move(stiffness, damping, [(n_half * dt, force), (n_half * dt, -force)]), omega, ZETA
        )
        expected = float(_vibration(realized.amplitudes, realized.times, omega, ZETA)) * unshaped
        bound = _rk4_bound(stiffness, damping, dt, control, omega) + 64 * EPS * DISTANCE * steps
        assert abs(measured - expected) <= bound


# -- the damped bang-bang move ---------------------------------------------------------------------------------


def _peak_after_scan(durations):
    """Largest carriage deviation [m] after bang-bang moves of D lasting `durations` [s]: expm, then the free
    ring-down sampled at 1/4000 of a period over its first period (a peak reads low by (2 pi / 4000)^2 / 8)."""
    omega_d = OMEGA * math.sqrt(1 - ZETA**2)
    sigma = ZETA * OMEGA
    tau = np.linspace(0.0, 2 * math.pi / omega_d, 4001)
    peaks = []
    for duration in durations:
        force = 4 * TOTAL * DISTANCE / duration**2
        q_c, q_m, v_c, v_m = _expm_move(K, C, [(duration / 2, force), (duration / 2, -force)])
        s, rate = q_m - q_c, v_m - v_c
        # the free belt: s(tau) = e^{-sigma tau} (s cos + (rate + sigma s) / omega_d sin)
        free = np.exp(-sigma * tau) * (s * np.cos(omega_d * tau) + (rate + sigma * s) / omega_d * np.sin(omega_d * tau))
        peaks.append(M_M / TOTAL * np.max(np.abs(free)))
    return np.array(peaks)


def test_quietest_bang_bang_move_is_0_0890_s_by_an_exact_scan():
    quiet = positioning.quietest_move_time(OMEGA, ZETA, DISTANCE, BAND)
    assert round(quiet, 4) == 0.0890
    # the scan: every move from the quiet time to the damped worst case's bound stays inside the band ...
    sampling = (2 * math.pi / 4000) ** 2 / 8  # how low a sampled peak can read, relative
    bound = positioning.worst_case_envelope(OMEGA, ZETA, DISTANCE, quiet)
    longer = np.linspace(quiet, 0.0975, 1500)
    assert np.all(_peak_after_scan(longer) <= BAND * (1 + 1e-9))
    assert bound > BAND and positioning.worst_case_envelope(OMEGA, ZETA, DISTANCE, 0.0975) < BAND
    # ... and a move just shorter rings beyond it (the crossing is a transversal one)
    shorter = _peak_after_scan([quiet - 2e-6])[0]
    assert shorter > BAND * (1 + sampling)
    # undamped, the same belt would need (4 / omega) sqrt(D / band): the old claim, 0.1646 s
    assert positioning.undamped_quiet_time(OMEGA, DISTANCE, BAND) == pytest.approx(0.1646, abs=5e-5)


def test_worst_case_envelope_bounds_every_phase_and_is_reached():
    durations = np.linspace(0.07, 0.2, 400)
    for duration in durations:
        phasor = positioning.residual_phasor(OMEGA, ZETA, *positioning.bang_bang(DISTANCE, duration))
        assert abs(phasor) <= positioning.worst_case_envelope(OMEGA, ZETA, DISTANCE, duration) * (1 + 1e-12)
    # reached when each half-move lasts an odd number of half damped periods
    omega_d = OMEGA * math.sqrt(1 - ZETA**2)
    duration = 2 * 15 * math.pi / omega_d
    phasor = positioning.residual_phasor(OMEGA, ZETA, *positioning.bang_bang(DISTANCE, duration))
    assert abs(phasor) == pytest.approx(positioning.worst_case_envelope(OMEGA, ZETA, DISTANCE, duration), rel=1e-12)


def test_minimum_time_move_settles_by_the_damped_ring_down():
    """At full force the move takes 2 sqrt(D M / F); its exact ring-down enters the band for good 4.9 ms later."""
    fastest = 2 * math.sqrt(DISTANCE * TOTAL / FORCE)
    breaks, accelerations = positioning.bang_bang(DISTANCE, fastest)
    got = positioning.positioning_time(OMEGA, ZETA, breaks, accelerations, BAND)
    # reference: the exact free ring-down after the expm end state, sampled densely, its last exit from the band
    q_c, q_m, v_c, v_m = _expm_move(K, C, [(fastest / 2, FORCE), (fastest / 2, -FORCE)])
    s, rate = q_m - q_c, v_m - v_c
    sigma, omega_d = ZETA * OMEGA, OMEGA * math.sqrt(1 - ZETA**2)
    tau = np.arange(0.0, 0.05, 1e-8)
    free = (
        M_M
        / TOTAL
        * np.exp(-sigma * tau)
        * (s * np.cos(omega_d * tau) + (rate + sigma * s) / omega_d * np.sin(omega_d * tau))
    )
    last_outside = tau[np.flatnonzero(np.abs(free) > BAND)[-1]]
    assert fastest + last_outside <= got <= fastest + last_outside + 1e-8
    assert round(got, 4) == 0.0748


@pytest.mark.parametrize("zeta", [0.0, 0.03, 0.4])
def test_peak_after_is_the_free_vibrations_continuous_maximum(zeta):
    """positioning.peak_after (the residual amplitude's `_exact`) against a dense grid over the first damped
    period refined by a bounded scalar search on each grid maximum's neighbourhood (scipy, independent)."""
    import scipy.optimize

    omega = 2 * math.pi * 195.0
    rng = np.random.default_rng(7)
    s = complex(-zeta * omega, omega * math.sqrt(1 - zeta**2))
    for phasor in rng.normal(size=8) + 1j * rng.normal(size=8):

        def negative(tau, z=phasor):
            return -abs((z * np.exp(s * tau)).real)

        # later extrema decay (or repeat when undamped): the largest lies in [0, one damped period]
        period = 2 * math.pi / s.imag
        grid = np.linspace(0.0, period, 4001)
        values = -np.array([negative(t) for t in grid])
        k = int(np.argmax(values))
        low, high = grid[max(k - 1, 0)], grid[min(k + 1, len(grid) - 1)]
        found = scipy.optimize.minimize_scalar(negative, bounds=(low, high), method="bounded", options={"xatol": 1e-15})
        independent = max(values[0], -float(found.fun))
        # the search's tau is good to ~1e-15 s; the value's error is second order in it, round-off eps |Z|
        assert positioning.peak_after(phasor, omega, zeta) == pytest.approx(independent, rel=1e-9)
