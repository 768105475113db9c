"""Settling is certified on the continuous motion, not at the samples (issue 25, item 9).

Read at the samples (omega_n dt = 0.1), a vibration peak reads low by about (omega_n dt)^2 / 8 =
1.25e-3 of its amplitude: a peak that leaves the +-band between two samples inside it went
unseen, and the positioning time came out early by half a belt period (8 of the design grid's
2401 configurations, 1.8-4.9 ms). The reported exit is now the Hermite interpolant's.

The references are built here from the parameters alone: after the bang-bang move the centre of
mass rests at the target and the belt stretch s is a free damped oscillator
mu s'' + c s' + k s = 0, so the carriage deviation is d = -(m_m / M) s, a damped sinusoid whose
extrema and band exits are found in closed form (extrema at the zeros of d', exits by brentq
between consecutive extrema). The state at the end of the move is the belt mode's textbook
underdamped flow over the two force segments. The run's samples are compared with it directly (scene run)
or through textbook RK4, whose one-step map on a linear system is R(hA) = I + hA + ... + (hA)^4/24
(tests/scenes/printer_head/test_printer_head_integrators.py shows MuJoCo's RK4 step is that map), for the batched runs.

Tolerance: on a step interval the interpolant of the run's samples differs from the exact d by at
most E = e_q + (4/27) dt (2 e_v) + dt^4 / 384 max|d''''| (Hermite's basis: h00 + h01 = 1,
|h10|, |h11| <= 4/27; e_q, e_v the samples' position and velocity errors there; max|d''''| <=
omega_n^4 times d's envelope) plus round-off, so its exit from the band lies between the exact
motion's exits from band + E and band - E. Both must fall on the same vibration peak (E below
the peaks' distance from the band), which makes the window microseconds wide, against the half
period (1.8-4.9 ms) the samples lost.
"""

import dataclasses
import math

import numpy as np
import pytest
import scipy.optimize

import springlab
from springlab.studies.design import study as design
from springlab.studies.design.moves import simulate

#: the issue's configuration: 0.3175 kg carriage, 12.5 kN/m belt, zeta = 0.01, 7.94 N, dt = 0.1 / omega_n
ISSUE = {
    "carriage_mass": 0.31748021039363988,
    "belt_stiffness": 12500.0,
    "belt_damping": 0.4215390226731415,
    "drive_force": 7.9370052598409968,
}
ISSUE_DT = 0.00016827456217672474
#: the 8 configurations of the 7^4 design grid whose settling the samples missed, found by running
#: the whole grid once against the closed form below: grid exponents (in thirds of each span) of
#: (belt_stiffness, carriage_mass, damping_ratio, drive_force), the grid's order
MISSED = (
    (-3, 2, -3, 1),  # the issue's: 4.94 ms early
    (-3, 2, 0, -1),
    (-2, 2, -3, 2),
    (-2, 2, 0, 0),
    (-1, 2, -3, 3),
    (-1, 2, 0, 1),
    (0, 2, 0, 2),
    (1, 2, 0, 3),
)
EPS = np.finfo(float).eps


@dataclasses.dataclass(frozen=True)
class Belt:
    """The belt mode of one configuration: share m_m / M [-], omega_n [rad/s], sigma [1/s], omega_d
    [rad/s], the 2x2 system A of (s, s'), and the stretch s* [m] per newton of motor force."""

    share: float
    omega_n: float
    sigma: float
    omega_d: float
    system: np.ndarray
    per_newton: float


def _belt(m_c, m_m, k, c):
    total, mu = m_c + m_m, m_c * m_m / (m_c + m_m)
    sigma = c / (2 * mu)
    omega_n = math.sqrt(k / mu)
    system = np.array([[0.0, 1.0], [-k / mu, -c / mu]])
    return Belt(m_m / total, omega_n, sigma, math.sqrt(omega_n**2 - sigma**2), system, m_c / (total * k))


def _flow(belt, t):
    """The exact transition matrix of (s, s') over t [s]: the textbook underdamped oscillator's."""
    c, s = math.cos(belt.omega_d * t), math.sin(belt.omega_d * t)
    ratio = belt.sigma / belt.omega_d
    return math.exp(-belt.sigma * t) * np.array(
        [[c + ratio * s, s / belt.omega_d], [-(belt.omega_n**2) / belt.omega_d * s, c - ratio * s]]
    )


def _after_move(belt, force, power):
    """(s, s') at the end of +force then -force over equal halves, from rest at s = 0, each relaxing
    toward its equilibrium s* through `power` (the transition over one half)."""
    state = np.zeros(2)
    for f in (force, -force):
        rest = np.array([belt.per_newton * f, 0.0])
        state = rest + power @ (state - rest)
    return state


def _rk4(belt, dt):
    z = belt.system * dt
    return np.eye(2) + z + z @ z / 2 + z @ z @ z / 6 + z @ z @ z @ z / 24


def _free(belt, start):
    """d(tau), d'(tau) [m, m/s] and the envelope [m] of the carriage deviation after the move from (s, s')."""
    a = start[0]
    b = (start[1] + belt.sigma * start[0]) / belt.omega_d

    def d(tau):
        e = np.exp(-belt.sigma * tau)
        return -belt.share * e * (a * np.cos(belt.omega_d * tau) + b * np.sin(belt.omega_d * tau))

    def rate(tau):
        e = np.exp(-belt.sigma * tau)
        p, q = start[1], -belt.sigma * b - belt.omega_d * a  # s' = e^(-sigma tau) (p cos + q sin)
        return -belt.share * e * (p * np.cos(belt.omega_d * tau) + q * np.sin(belt.omega_d * tau))

    return d, rate, lambda tau: belt.share * math.hypot(a, b) * math.exp(-belt.sigma * tau)


def _last_exit(belt, start, level):
    """(last exit [s] after the move of |d| from `level` [m], the nearest extremum's distance from it [m])."""
    d, rate, _ = _free(belt, start)
    # d' = 0 at omega_d tau = alpha + pi/2 + j pi; successive extrema shrink by exp(-sigma pi / omega_d)
    p, q = start[1], -belt.sigma * (start[1] + belt.sigma * start[0]) / belt.omega_d - belt.omega_d * start[0]
    first = ((math.atan2(q, p) + math.pi / 2) % math.pi) / belt.omega_d

    def extremum(j):  # j = 0: tau = 0, counted as one; j >= 1: the zeros of d'
        return 0.0 if j == 0 else first + (j - 1) * math.pi / belt.omega_d

    peaks = np.abs(d(np.array([0.0, first])))
    j = 0  # the last extremum (tau = 0 counts as one) outside the level
    decay = math.exp(-belt.sigma * math.pi / belt.omega_d)
    if peaks[1] > level:
        j = 1 + int(math.log(peaks[1] / level) / -math.log(decay))
        while abs(d(extremum(j + 1))) > level:
            j += 1
        while abs(d(extremum(j))) <= level:
            j -= 1
    elif peaks[0] <= level:
        return 0.0, abs(level - peaks.max())
    lo, hi = extremum(j), extremum(j + 1)
    sign = math.copysign(1.0, d(lo))
    tau = scipy.optimize.brentq(lambda t: sign * d(t) - level, lo, hi, xtol=1e-15, rtol=1e-15)
    margin = min(abs(d(lo)) - level, level - abs(d(hi))) if j > 0 else level - abs(d(hi))
    return tau, margin


def _window(belt, start, band, sample_error, dt, move, distance):
    """(exact exit, earliest and latest exit the run may report [s after the move], E [m], margin [m]).

    sample_error(taus) -> (e_q, e_v): the run's position and velocity errors [m, m/s] at those times.
    """
    exact, margin = _last_exit(belt, start, band)
    _, _, envelope = _free(belt, start)
    near = (np.floor(exact / dt) + np.arange(-1, 3)) * dt  # the exit's interval and its neighbours
    near = near[near >= 0]
    e_q, e_v = sample_error(near)
    hermite = dt**4 / 384 * belt.omega_n**4 * envelope(near[0])
    roundoff = 4 * (move + near[-1]) / dt * EPS * distance  # positions are absolute (~ the move distance)
    error = e_q + 4 / 27 * dt * 2 * e_v + hermite + roundoff
    early, _ = _last_exit(belt, start, band + error)
    late, _ = _last_exit(belt, start, band - error)
    return exact, early, late, error, margin


def _configurations(grid_levels):
    """(base parameters, property values) of the design grid with `grid_levels` levels."""
    base = design.base_parameters("printer_head")
    return base, design.configurations(design.make_grids("printer_head", base, grid_levels))


def _check_batched(base, values, positioning_time, timestep):
    """Every configuration's reported positioning time [s] (run at `timestep` [s]) inside its window.

    Returns the differences |reported - exact| [s].
    """
    m_m, band, distance = base["motor_mass"], base["positioning_band"], base["move_distance"]
    differences = []
    for i in range(len(timestep)):
        m_c, k, zeta, force = (
            float(values[p][i]) for p in ("carriage_mass", "belt_stiffness", "damping_ratio", "drive_force")
        )
        c = 2 * zeta * math.sqrt(k * m_c * m_m / (m_c + m_m))
        belt = _belt(m_c, m_m, k, c)
        dt = float(timestep[i])
        half = math.sqrt(distance * (m_c + m_m) / force)
        n = round(half / dt)
        assert n * dt == pytest.approx(half, rel=1e-12)  # the switch falls on the grid: full force
        exact_start = _after_move(belt, force, _flow(belt, n * dt))
        rk4 = _rk4(belt, dt)
        rk4_start = _after_move(belt, force, np.linalg.matrix_power(rk4, n))
        d, rate, _ = _free(belt, exact_start)

        def sample_error(taus, belt=belt, rk4=rk4, rk4_start=rk4_start, d=d, rate=rate, dt=dt):
            states = np.array([np.linalg.matrix_power(rk4, round(t / dt)) @ rk4_start for t in taus])
            e_q = np.max(np.abs(-belt.share * states[:, 0] - d(taus)))
            e_v = np.max(np.abs(-belt.share * states[:, 1] - rate(taus)))
            return e_q, e_v

        move = 2 * half
        exact, early, late, error, margin = _window(belt, exact_start, band, sample_error, dt, move, distance)
        assert error < margin, i  # the run's error decides which peak is the last one outside
        reported = positioning_time[i]
        assert move + early - 1e-12 <= reported <= move + late + 1e-12, (i, reported - move - exact)
        differences.append(abs(reported - move - exact))
    return np.array(differences)


def test_the_issue_run_reports_the_exact_last_exit_between_samples():
    # springlab run printer_head move --set ... --dt 0.000168... --duration 0.6: 0.388616 s reported
    # before (the samples), 0.393559 s the exact last exit
    result = springlab.run("printer_head", "move", dt=ISSUE_DT, duration=0.6, **ISSUE)
    p, q = result.parameters, result.to_dict()["quantities"]
    m_c, m_m = p["carriage_mass"], p["motor_mass"]
    belt = _belt(m_c, m_m, p["belt_stiffness"], p["belt_damping"])
    # the move on the run's grid: n steps each way at the force lowered to stop at D (no lowering here)
    n = math.ceil(math.sqrt(p["move_distance"] * (m_c + m_m) / p["drive_force"]) / ISSUE_DT - 1e-9)
    force = (m_c + m_m) * p["move_distance"] / (n * ISSUE_DT) ** 2
    move = 2 * n * ISSUE_DT
    start = _after_move(belt, force, _flow(belt, n * ISSUE_DT))
    d, rate, _ = _free(belt, start)
    deviation = result.pos["carriage"] - p["move_distance"]

    def sample_error(taus):
        steps = np.rint((taus + move) / ISSUE_DT).astype(int)
        e_q = np.max(np.abs(deviation[steps] - d(taus)))
        e_v = np.max(np.abs(result.vel["carriage"][steps] - rate(taus)))
        return e_q, e_v

    exact, early, late, error, margin = _window(
        belt, start, p["positioning_band"], sample_error, ISSUE_DT, move, p["move_distance"]
    )
    assert exact + move == pytest.approx(0.393559, abs=1e-6)  # the issue's figure
    assert error < margin
    assert late - early < 0.1 * ISSUE_DT  # the window: inside a step, let alone half a period (31 steps)
    assert q["move_time_s"] == pytest.approx(move, rel=1e-12)
    assert move + early <= q["positioning_time_s"] <= move + late
    assert q["settled_for_good"] is True


def test_the_eight_configurations_the_samples_missed_settle_when_the_exact_motion_does():
    base = design.base_parameters("printer_head")
    grids = design.make_grids("printer_head", base, design.DEFAULT_LEVELS)  # the default in the middle
    middle = design.DEFAULT_LEVELS // 2
    values = {name: np.array([grids[name][middle + e[j]] for e in MISSED]) for j, name in enumerate(grids)}
    np.testing.assert_allclose(values["carriage_mass"], 0.2 * 2 ** (2 / 3), rtol=1e-15)
    runs = simulate("printer_head", base, values)
    differences = _check_batched(base, values, runs.positioning_time_s, runs.dt_s)
    # the samples had them early by half a belt period (1.8-4.9 ms); now the run's error in time
    assert np.max(differences) < 1e-5


def test_the_coarse_design_grid_settles_when_the_exact_motion_does(small_design_study):
    study = small_design_study  # 3^4 = 81 configurations (tests/conftest.py)
    differences = _check_batched(study.base, study.values, study.positioning_time_s, study.dt_s)
    assert len(differences) == 81


@pytest.mark.slow
def test_the_whole_design_grid_settles_when_the_exact_motion_does(default_design_study):
    # all 2401 configurations, shared with tests/studies/design/test_design.py (tests/conftest.py)
    study = default_design_study
    differences = _check_batched(study.base, study.values, study.positioning_time_s, study.dt_s)
    assert len(differences) == 2401
