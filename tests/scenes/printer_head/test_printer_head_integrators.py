"""How MuJoCo's integrators treat the belt's TENDON damping, measured, and what it does to stability.

Joint damping is implicit in euler, implicit and implicitfast (docs/stability.md). The belt's damping is a
tendon's, and MuJoCo treats it differently; measured here on the printer head's own model, to
1e-9, from MuJoCo's one-step maps (mjd_transitionFD, and central differences of mj_step for rk4):

* euler: tendon damping fully explicit, v' = v + h M^-1 (-K x - C v), x' = x + h v';
* implicit, implicitfast: the damping on each joint's own row implicit, the belt's coupling
  explicit: W = (M + h diag(C))^-1 instead of (M + h C)^-1;
* rk4: R(hA) = I + hA + ... + (hA)^4 / 24 (the tendon is just a force);
* discrete: springs implicit (x -> v through (M + h C + h^2 K)^-1), velocity map (M + h C)^-1 M.

The hand-built maps use only M, C, K from the parameters; the stability limits are checked against
closed forms derived here (euler: the explicit-damping bound 2 sqrt(zeta^2 + 1) - 2 zeta) and by
running just inside and just outside them.
"""

import math

import mujoco
import numpy as np
import pytest

import springlab
from springlab import scenes
from springlab.errors import DivergedError
from springlab.exact.limits import stability_limit as joint_damping_limit

BELT = np.array([[1.0, -1.0], [-1.0, 1.0]])
I2 = np.eye(2)


def _model_and_matrices(**overrides):
    case = scenes.get("printer_head").case("settle", overrides)
    scenario, params, model = case.scenario, case.params, case.model
    mass = np.diag([params["carriage_mass"], params["motor_mass"]])
    return case, scenario, params, model, mass, params["belt_damping"] * BELT, params["belt_stiffness"] * BELT


def _belt_mode(params):
    reduced = params["carriage_mass"] * params["motor_mass"] / (params["carriage_mass"] + params["motor_mass"])
    omega = math.sqrt(params["belt_stiffness"] / reduced)
    return omega, params["belt_damping"] / (2 * math.sqrt(params["belt_stiffness"] * reduced))


def _measured_map(model, integrator: str, dt: float) -> np.ndarray:
    """MuJoCo's one-step Jacobian in (q_c, q_m, v_c, v_m): mjd_transitionFD, or mj_step differences for rk4."""
    model.opt.integrator = springlab.sim.simulate.INTEGRATORS[integrator]
    model.opt.timestep = dt
    data = mujoco.MjData(model)
    if integrator != "rk4":
        a = np.zeros((4, 4))
        mujoco.mjd_transitionFD(model, data, 1e-6, True, a, None, None, None)
        return a
    a = np.empty((4, 4))
    for j in range(4):
        columns = []
        for sign in (1.0, -1.0):
            mujoco.mj_resetData(model, data)
            (data.qpos if j < 2 else data.qvel)[j % 2] = sign * 1e-3
            mujoco.mj_step(model, data)
            columns.append(np.concatenate([data.qpos, data.qvel]))
        a[:, j] = (columns[0] - columns[1]) / 2e-3  # linear model: exact up to round-off
    return a


def _semi_implicit(dt, w_x, w_v, stiffness, damping):
    """x' = x + h v', v' = v - h w_x K x - h w_v C v, as a 4x4 map."""
    v_from_x = -dt * w_x @ stiffness
    v_from_v = I2 - dt * w_v @ damping
    return np.block([[I2 + dt * v_from_x, dt * v_from_v], [v_from_x, v_from_v]])


@pytest.mark.parametrize("omega_dt", [0.3, 1.2])
def test_euler_treats_tendon_damping_explicitly(omega_dt):
    scene, _, params, model, mass, damping, stiffness = _model_and_matrices(belt_damping=20.0)
    dt = omega_dt / _belt_mode(params)[0]
    inverse = np.linalg.inv(mass)
    measured = _measured_map(model, "euler", dt)
    explicit = _semi_implicit(dt, inverse, inverse, stiffness, damping)
    implicit = _semi_implicit(
        dt, np.linalg.inv(mass + dt * damping), np.linalg.inv(mass + dt * damping), stiffness, damping
    )
    scale = np.max(np.abs(measured))
    assert np.max(np.abs(measured - explicit)) <= 1e-9 * scale
    assert np.max(np.abs(measured - implicit)) > 1e-3 * scale  # the test tells the two apart


@pytest.mark.parametrize("integrator", ["implicit", "implicitfast"])
def test_implicit_solves_with_the_diagonal_of_the_belt_damping(integrator):
    scene, _, params, model, mass, damping, stiffness = _model_and_matrices(belt_damping=20.0)
    dt = 0.8 / _belt_mode(params)[0]
    measured = _measured_map(model, integrator, dt)
    diagonal = np.linalg.inv(mass + dt * np.diag(np.diag(damping)))
    expected = _semi_implicit(dt, diagonal, diagonal, stiffness, damping)
    full = np.linalg.inv(mass + dt * damping)
    scale = np.max(np.abs(measured))
    assert np.max(np.abs(measured - expected)) <= 1e-9 * scale
    assert np.max(np.abs(measured - _semi_implicit(dt, full, full, stiffness, damping))) > 1e-3 * scale
    # so a step moves the centre of mass's momentum by the belt force times the h c / m mismatch
    momentum = np.array([params["carriage_mass"], params["motor_mass"]])
    assert abs(momentum @ measured[2:4, 0]) > 1e-3 * params["belt_stiffness"] * dt * params["carriage_mass"] / (
        params["carriage_mass"] + dt * params["belt_damping"]
    )


def test_rk4_step_is_the_fourth_order_taylor_polynomial_of_the_exact_flow():
    scene, _, params, model, mass, damping, stiffness = _model_and_matrices(belt_damping=20.0)
    dt = 0.5 / _belt_mode(params)[0]
    inverse = np.linalg.inv(mass)
    a = np.block([[np.zeros((2, 2)), I2], [-inverse @ stiffness, -inverse @ damping]]) * dt
    taylor = np.eye(4) + a + a @ a / 2 + a @ a @ a / 6 + a @ a @ a @ a / 24
    measured = _measured_map(model, "rk4", dt)
    assert np.max(np.abs(measured - taylor)) <= 1e-9 * np.max(np.abs(taylor))


@pytest.mark.parametrize("omega_dt", [0.5, 5.0])
def test_discrete_makes_the_belt_spring_implicit(omega_dt):
    scene, _, params, model, mass, damping, stiffness = _model_and_matrices(belt_damping=20.0)
    dt = omega_dt / _belt_mode(params)[0]
    measured = _measured_map(model, "discrete", dt)
    spring = np.linalg.inv(mass + dt * damping + dt * dt * stiffness)
    v_from_x = -dt * spring @ stiffness
    v_from_v = np.linalg.inv(mass + dt * damping) @ mass
    expected = np.block([[I2 + dt * v_from_x, dt * v_from_v], [v_from_x, v_from_v]])
    assert np.max(np.abs(measured - expected)) <= 1e-9 * np.max(np.abs(measured))
    # and it stays stable far past every explicit limit. Not |mu| <= 1 on the whole map: the rigid-body
    # mode (both masses coasting together) is a Jordan block [[1, h], [0, 1]], whose double eigenvalue 1
    # finite differences move by ~sqrt(1e-10). In centre-of-mass and belt coordinates the map is block
    # triangular (the belt's forces are internal): the belt block is the reduced 1-DOF discrete map and
    # contracts, the rigid block is exactly coasting (velocity kept, position advanced by h v).
    m_c, m_m = params["carriage_mass"], params["motor_mass"]
    to_modes = np.array([[1.0, -1.0], [m_c / (m_c + m_m), m_m / (m_c + m_m)]])  # (q_c, q_m) -> (r, X)
    transform = np.kron(I2, to_modes)[[0, 2, 1, 3]]  # (q_c, q_m, v_c, v_m) -> (r, s, X, V)
    modal = transform @ measured @ np.linalg.inv(transform)
    scale = np.max(np.abs(modal))
    assert np.max(np.abs(modal[:2, 2:])) <= 1e-9 * scale  # the belt does not feel where the pair is
    np.testing.assert_allclose(modal[2:, 2:], [[1.0, dt], [0.0, 1.0]], rtol=0, atol=1e-9 * scale)
    reduced = m_c * m_m / (m_c + m_m)
    k, c = params["belt_stiffness"], params["belt_damping"]
    # the map above on the belt mode alone (reduced mass): s' = m s / (m + h c) - h k r / (m + h c + h^2 k),
    # r' = r + h s'
    s_from_r, s_from_s = -dt * k / (reduced + dt * c + dt * dt * k), reduced / (reduced + dt * c)
    belt = np.array([[1 + dt * s_from_r, dt * s_from_s], [s_from_r, s_from_s]])
    values, vectors = np.linalg.eig(belt)
    # eigenvalue error <= cond(V) x the map's error (Bauer-Fike); the map is measured to 1e-9 x its scale
    tolerance = np.linalg.cond(vectors) * 1e-9 * scale
    measured_values = np.linalg.eigvals(modal[:2, :2])
    assert np.max(np.abs(np.sort_complex(measured_values) - np.sort_complex(values))) <= tolerance
    assert np.max(np.abs(measured_values)) < 1 - 10 * tolerance


@pytest.mark.parametrize("belt_damping", [0.0, 2.45, 20.0, 80.0])
def test_euler_limit_on_the_belt_is_the_explicit_damping_bound(belt_damping):
    # explicit damping: trace 2 - a^2 - 2 zeta a, det 1 - 2 zeta a (a = omega dt) on the belt mode;
    # |trace| < 1 + det gives a < 2 sqrt(zeta^2 + 1) - 2 zeta, below joint damping's + 2 zeta
    case, scenario, params, model, *_ = _model_and_matrices(belt_damping=belt_damping)
    omega, zeta = _belt_mode(params)
    limit = case.stability_limit("euler", omega, zeta)
    assert limit == pytest.approx(2 * math.sqrt(zeta * zeta + 1) - 2 * zeta, rel=1e-8)
    if zeta > 0:
        assert limit < joint_damping_limit("euler", zeta)


@pytest.mark.parametrize("belt_damping", [0.0, 2.45, 20.0])
def test_rk4_limit_on_the_belt_is_rk4s_usual_limit(belt_damping):
    case, scenario, params, model, *_ = _model_and_matrices(belt_damping=belt_damping)
    omega, zeta = _belt_mode(params)
    limit = case.stability_limit("rk4", omega, zeta)
    assert limit == pytest.approx(joint_damping_limit("rk4", zeta), rel=1e-8)


def test_discrete_has_no_limit_on_the_belt():
    case, scenario, params, model, *_ = _model_and_matrices()
    assert math.isinf(case.stability_limit("discrete", *_belt_mode(params)))


@pytest.mark.parametrize("integrator", ["euler", "implicit"])
def test_runs_just_inside_the_measured_limit_stay_bounded_and_just_outside_diverge(integrator):
    case, scenario, params, model, *_ = _model_and_matrices(belt_damping=20.0)
    omega, zeta = _belt_mode(params)
    limit = case.stability_limit(integrator, omega, zeta)
    if integrator == "implicit":  # between the explicit and the joint-damping bounds, as measured above
        assert 2 * math.sqrt(zeta * zeta + 1) - 2 * zeta < limit < joint_damping_limit("euler", zeta)
    inside = 0.97 * limit / omega
    result = springlab.run(
        "printer_head", "settle", integrator=integrator, dt=inside, duration=3000 * inside, belt_damping=20.0
    )
    # bounded: no growth from the first half of the run to the second (a near-limit step map is
    # non-normal, so the first steps may overshoot the initial deflection)
    carriage = np.abs(result.pos["carriage"])
    assert np.max(carriage[1500:]) <= np.max(carriage[:1500])
    outside = 1.03 * limit / omega
    with pytest.raises(DivergedError, match=f"stability limit {limit:.4g}"):
        springlab.run(
            "printer_head", "settle", integrator=integrator, dt=outside, duration=3000 * outside, belt_damping=20.0
        )


@pytest.mark.parametrize("integrator", ["implicit", "implicitfast"])
def test_implicit_integrators_stop_the_carriage_short_by_2hc_over_m_of_the_move(integrator):
    # with W = diag(1/(m_c + hc), 1/(m_m + hc)) a step's momentum change is h [F_b m_c/(m_c + hc)
    # + (F - F_b) m_m/(m_m + hc)], and with the belt force at its quasi-static F_b = F m_c / M that is
    # h F (1 - 2 h c / M) to first order: the centre of mass moves as under a force 2hc/M too small
    # and stops 2 h c D / M short of D (52 um at the defaults: five times the +-10 um band, so the
    # carriage never settles). rk4 and euler apply the belt force equally and oppositely: exact.
    result = springlab.run("printer_head", "move", integrator=integrator, dt=1e-4)
    p = result.parameters
    total = p["carriage_mass"] + p["motor_mass"]
    centre = (p["carriage_mass"] * result.pos["carriage"][-1] + p["motor_mass"] * result.pos["motor"][-1]) / total
    shortfall = 2 * 1e-4 * p["belt_damping"] * p["move_distance"] / total
    assert p["move_distance"] - centre == pytest.approx(shortfall, rel=0.02)
    assert shortfall > 5 * p["positioning_band"]
    assert result.to_dict()["quantities"]["settled_for_good"] is False
    for exact in ("rk4", "euler"):
        other = springlab.run("printer_head", "move", integrator=exact, dt=1e-4)
        centre = (p["carriage_mass"] * other.pos["carriage"][-1] + p["motor_mass"] * other.pos["motor"][-1]) / total
        assert centre == pytest.approx(p["move_distance"], abs=1e-14)
