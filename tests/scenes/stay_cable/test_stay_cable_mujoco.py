"""The generated stay-cable MJCF run in raw MuJoCo (mujoco.rollout, mj_step), held to the exact N-element model.

* The model MuJoCo compiles is the N-element model: springlab.exact.linearize's M, C, K (MuJoCo's mjd_inverseFD)
  against the matrices built from the parameters (springlab.exact.cable) to 1e-9.
* Damped complex modes: the linearization's eigenvalues, and free decays run in each mode (RK4 at a dt whose
  eigenvalue error (|lambda| dt)^4 / 120 is below 1e-9), against the quadratic eigenproblem to 1e-8.
* Rain-wind: the growth rate a run measures against Re(lambda) to 1e-6 relative; the stabilising damper's runs
  grow 0.1 % below it and decay 0.1 % above it.
* The wind: 40 seeds of held noise; each record's variance inside its own 99 % interval around the exact held
  value in at least 38 of them. The variance's bias from MuJoCo's own one-step maps falls with dt at the
  integrator's order.
"""

from __future__ import annotations

import math

import mujoco
import numpy as np
import pytest
import scipy.linalg
import scipy.stats
from mujoco import rollout

from springlab.errors import ParameterError
from springlab.exact import cable as cb
from springlab.exact import random_vibration as rv
from springlab.exact.linearize import linearize, one_step_map, step_input_column
from springlab.scenes.stay_cable import build
from springlab.scenes.stay_cable.wind import wind_controls
from springlab.sim.simulate import quiet_mujoco

EPS = float(np.finfo(float).eps)
#: the long stay of the docs (300 m, 6.1 MN, 70 kg/m)
DEFAULTS = {
    "n_elements": 9,
    "length": 300.0,
    "tension": 6.1e6,
    "mass_per_length": 70.0,
    "damper_position": 30.0,
    "damper_coefficient": 0.0,
    "structural_damping_ratio": 0.001,
    "aero_damping_ratio": 0.0,
    "aero_modes": 0,
    "wind_intensity": 30.0,
}
CABLE = cb.TautCable(300.0, 6.1e6, 70.0)
FULL = mujoco.mjtState.mjSTATE_FULLPHYSICS


def _compile(**overrides) -> tuple[mujoco.MjModel, dict]:
    params = {**DEFAULTS, **overrides}
    spec = build.scaffold()
    build.generate(spec, params)
    with quiet_mujoco() as messages:
        model = spec.compile()
    assert messages == []
    return model, params


def _exact(params: dict) -> cb.LumpedCable:
    """The N-element model from the parameters alone (springlab.exact.cable), not from the compiled model."""
    return cb.LumpedCable.build(
        CABLE,
        int(params["n_elements"]),
        structural_ratio=params["structural_damping_ratio"],
        damper_position=params["damper_position"],
        damper_coefficient=params["damper_coefficient"],
        aero_ratio=params["aero_damping_ratio"],
        aero_modes=int(params["aero_modes"]),
    )


def _states(model: mujoco.MjModel, x0: np.ndarray, steps: int, control: np.ndarray | None = None) -> np.ndarray:
    """(batch, steps + 1, 2 N) of (q, q') from `x0` (batch, 2 N), one mujoco.rollout call."""
    x0 = np.atleast_2d(x0)
    n = model.nv
    initial = np.zeros((len(x0), mujoco.mj_stateSize(model, FULL)))
    initial[:, 1 : 1 + n], initial[:, 1 + n : 1 + 2 * n] = x0[:, :n], x0[:, n:]
    if control is None:
        control = np.zeros((len(x0), steps, model.nu))
    datas = [mujoco.MjData(model) for _ in range(2)]
    state, _ = rollout.rollout(model, datas, initial, control, nstep=steps)
    out = np.concatenate([x0[:, None, :], state[:, :, 1 : 1 + 2 * n]], axis=1)
    assert np.all(np.diff(state[:, :, 0], axis=1) > 0)  # no silent reset (time never jumps back)
    return out


# -- the model ------------------------------------------------------------------------------------------------


@pytest.mark.parametrize("n", [2, 9, 99])
def test_the_generated_model_compiles_and_steps_without_warnings(n):
    model, _ = _compile(n_elements=n, damper_coefficient=3e5, aero_damping_ratio=-0.005, aero_modes=min(n, 3))
    assert model.opt.integrator == mujoco.mjtIntegrator.mjINT_IMPLICITFAST  # the damper's fast decay, implicitly
    data = mujoco.MjData(model)
    data.qvel[:] = 0.1
    with quiet_mujoco() as messages:
        for _ in range(200):
            mujoco.mj_step(model, data)
    assert messages == [] and all(w.number == 0 for w in data.warning)
    assert model.nv == n and model.nu == 1
    assert np.all(model.opt.gravity == 0) and model.opt.disableflags & mujoco.mjtDisableBit.mjDSBL_CONTACT


def test_the_wind_puts_its_load_times_the_spacing_on_every_node():
    model, _ = _compile(n_elements=9)
    data = mujoco.MjData(model)
    data.ctrl[0] = 2.5  # [N/m]
    mujoco.mj_forward(model, data)
    assert np.allclose(data.qfrc_actuator, 2.5 * CABLE.spacing(9), rtol=4 * EPS, atol=0)


def test_a_seeds_wind_is_the_same_in_any_batch_and_has_the_held_variance():
    alone = wind_controls(30.0, 0.01, 20000, [7])
    batch = wind_controls(30.0, 0.01, 20000, [3, 7, 11])
    assert np.array_equal(alone[0], batch[1]) and not np.array_equal(batch[0], batch[1])
    # p_k ~ N(0, S / dt): the sample variance of 20000 within 5 of its standard errors sqrt(2 / 20000)
    assert abs(np.var(batch) / (30.0 / 0.01) - 1) <= 5 * math.sqrt(2 / batch.size)
    for bad in ({"intensity": math.nan}, {"intensity": -1.0}, {"intensity": math.inf}):
        with pytest.raises(ParameterError, match="wind_intensity must be a finite number >= 0"):
            wind_controls(bad["intensity"], 0.01, 10, [0])


def test_the_damper_sits_on_the_node_nearest_its_position():
    model, params = _compile(n_elements=99, damper_position=7.4, damper_coefficient=1e5)
    node = int(np.argmax(model.dof_damping)) + 1
    assert node == 2 == round(7.4 / CABLE.spacing(99))
    assert model.dof_damping[node - 1] - model.dof_damping[0] == pytest.approx(1e5, rel=1e-12)


@pytest.mark.parametrize("n", [2, 9, 49])
def test_mujocos_linearization_is_the_n_element_model(n):
    model, params = _compile(n_elements=n, damper_coefficient=2e5, aero_damping_ratio=-0.004, aero_modes=min(n, 2))
    lin = linearize(model)
    exact = _exact(params)
    # a linear model's centred differences are exact but for round-off: eps |f| / h, h = 1e-6 (FD_STEP)
    for found, expected in ((lin.M, np.diag(exact.mass)), (lin.K, exact.stiffness), (lin.C, exact.damping)):
        assert np.max(np.abs(found - expected)) <= 1e-9 * np.max(np.abs(expected))


# -- damped modes ---------------------------------------------------------------------------------------------------


def test_the_damped_complex_modes_are_mujocos():
    model, params = _compile(damper_coefficient=3e5)
    exact = _exact(params).complex_modes()
    values = linearize(model).eigenvalues
    found = values[values.imag > 0]
    found = found[np.argsort(found.imag)]
    scale = float(np.max(np.abs(exact.oscillatory)))
    assert len(found) == len(exact.oscillatory)
    # M, K, C agree to 1e-9 relative (above); the eigenvalues move by at most that times |A| for these
    # well-separated modes
    assert np.max(np.abs(found - exact.oscillatory)) <= 1e-8 * scale


def _measured_eigenvalue(model, a, mode_index, dt, steps):
    """lambda [1/s] of one mode from a free run started in it: z_k = w^H x_k with w its left eigenvector."""
    values, left, right = scipy.linalg.eig(a, left=True, right=True)
    k = mode_index
    v, w = right[:, k], left[:, k]
    w = w / np.conj(np.vdot(w, v))  # w^H v = 1
    model.opt.timestep = dt
    model.opt.integrator = mujoco.mjtIntegrator.mjINT_RK4
    x0 = np.real(v) / np.max(np.abs(np.real(v))) * 0.1  # 0.1 m at the largest node
    states = _states(model, x0, steps)[0]
    z = states @ np.conj(w)
    phase = np.unwrap(np.angle(z))
    growth = math.log(abs(z[-1]) / abs(z[0])) / (steps * dt)
    turning = (phase[-1] - phase[0]) / (steps * dt)
    return values[k], complex(growth, turning)


@pytest.mark.parametrize("mode", [1, 2])
def test_free_decays_measure_the_complex_eigenvalues_to_1e_8(mode):
    model, params = _compile(damper_coefficient=3e5)
    a = _exact(params).state_matrix()
    values = scipy.linalg.eigvals(a)
    oscillatory = np.flatnonzero(values.imag > 0)
    index = int(oscillatory[np.argsort(values[oscillatory].imag)][mode - 1])
    dt = 0.0025
    exact, measured = _measured_eigenvalue(model, a, index, dt, 8000)
    # RK4 is a polynomial of A dt: mode by mode z_{k+1} = p(lambda dt) z_k, p(h) = e^h - h^5 / 120 + ...
    bound = 2 * abs(exact) * (abs(exact) * dt) ** 4 / 120 + 8000 * EPS * abs(exact)
    assert bound <= 1e-8 * abs(exact)
    assert abs(measured - exact) <= bound


# -- rain-wind ------------------------------------------------------------------------------------------------------------

RAIN = {"aero_damping_ratio": -0.005, "aero_modes": 2, "damper_position": 30.0}


@pytest.mark.parametrize("damper", [0.0, 1e3])
def test_rain_wind_grows_at_the_rate_of_the_complex_eigenvalue(damper):
    model, params = _compile(**RAIN, damper_coefficient=damper)
    a = _exact(params).state_matrix()
    values = scipy.linalg.eigvals(a)
    index = int(np.argmax(values.real))
    assert values[index].real > 0
    dt = 0.002
    exact, measured = _measured_eigenvalue(model, a, index, dt, 50000)
    bound = abs(exact) * (abs(exact) * dt) ** 4 / 120 * 2 + 50000 * EPS * abs(exact)
    assert bound <= 1e-6 * exact.real
    assert abs(measured.real - exact.real) <= 1e-6 * exact.real


def test_the_stabilising_damper_stops_the_growth_in_runs():
    _, params = _compile(**RAIN)
    base = _exact(params)
    node = CABLE.damper_node(9, 30.0)
    c_stop = cb.stabilising_damper(base, node, guess=math.nan)
    for factor, sign in ((1 - 1e-3, 1.0), (1 + 1e-3, -1.0)):
        model, params = _compile(**RAIN, damper_coefficient=c_stop * factor)
        a = _exact(params).state_matrix()
        values = scipy.linalg.eigvals(a)
        index = int(np.argmax(values.real))
        dt = 0.005
        exact, measured = _measured_eigenvalue(model, a, index, dt, 20000)
        bound = abs(exact) * (abs(exact) * dt) ** 4 / 120 * 2 + 20000 * EPS * abs(exact)
        assert sign * exact.real > 2 * bound  # 0.1 % of the damper moves the rate well beyond the run's error
        assert sign * measured.real > 0
        assert abs(measured.real - exact.real) <= bound


# -- the wind --------------------------------------------------------------------------------------------------------------

#: a short-memory cable for the 40 seeds: 5 nodes, the damper near its optimum at node 1, 1 % intrinsic damping
WINDY = {"n_elements": 5, "damper_position": 50.0, "damper_coefficient": 4e4, "structural_damping_ratio": 0.01}


def _held_exact(params, dt):
    exact = _exact(params)
    n = exact.size
    a = exact.state_matrix()
    b = np.zeros((2 * n, 1))
    b[n:, 0] = CABLE.spacing(n) / exact.mass
    w = np.array([[params["wind_intensity"]]])
    phi, gamma = rv.zero_order_hold(a, b, dt)
    return rv.held_covariance(a, b, w, dt), phi, gamma, w


@pytest.mark.slow
def test_the_rms_of_40_seeds_falls_inside_its_own_interval_of_the_exact_held_value():
    """At a 99 % level, a correct model leaves at most 2 of 40 seeds outside with probability
    1 - P(Binomial(40, 0.01) <= 2) = 0.8 % (a 95 % interval would fail this rule 32 % of the time)."""
    model, params = _compile(**WINDY)
    n, dt, steps, seeds, level = 5, 0.02, 10000, 40, 0.99
    model.opt.timestep = dt
    model.opt.integrator = mujoco.mjtIntegrator.mjINT_RK4
    held, phi, gamma, w = _held_exact(params, dt)
    middle = np.zeros(2 * n)
    middle[n // 2] = 1.0  # node 3 of 5: mid-span
    interval = rv.variance_interval(
        float(held[n // 2, n // 2]), math.sqrt(rv.record_variance(held, phi, middle, steps)), level
    )
    # the integrator's own bias (MuJoCo's RK4 map, linearized) is far inside the scatter it is judged against
    transition = one_step_map(model, "rk4", dt)
    input_map = step_input_column(model, "rk4", "ctrl", 0, dt)[:, None]
    bias = rv.map_bias(held, transition, input_map, w / dt)[n // 2, n // 2]
    assert abs(bias) <= 0.01 * interval.spread
    rng = np.random.default_rng(20240615)
    x0 = rng.multivariate_normal(np.zeros(2 * n), held, size=seeds)  # stationary from the start
    control = wind_controls(params["wind_intensity"], dt, steps, range(seeds))
    states = _states(model, x0, steps, control)
    estimates = np.mean(states[:, 1:, n // 2] ** 2, axis=1)
    inside = sum(interval.contains(float(s)) for s in estimates)
    assert inside >= 38, (inside, interval, estimates)
    # the 40 records together: their mean variance within 3 standard errors of the exact one
    assert abs(np.mean(estimates) - interval.variance) <= 3 * interval.spread / math.sqrt(seeds)
    assert 1 - scipy.stats.binom.cdf(2, 40, 1 - level) == pytest.approx(0.0075, abs=5e-4)


@pytest.mark.parametrize(
    ("integrator", "order", "dts"), [("euler", 1, (0.02, 0.01, 0.005)), ("implicitfast", 1, (0.02, 0.01, 0.005))]
)
def test_the_variance_bias_falls_at_the_integrators_order(integrator, order, dts):
    model, params = _compile(**WINDY)
    n = 5
    biases = []
    for dt in dts:
        held, _, _, w = _held_exact(params, dt)
        transition = one_step_map(model, integrator, dt)
        input_map = step_input_column(model, integrator, "ctrl", 0, dt)[:, None]
        biases.append(rv.map_bias(held, transition, input_map, w / dt)[n // 2, n // 2] / held[n // 2, n // 2])
    orders = np.log2(np.array(biases[:-1]) / np.array(biases[1:]))
    assert np.all(np.abs(orders - order) <= 0.1), (biases, orders)


def test_rk4s_variance_bias_falls_at_least_at_its_order():
    """RK4's stationary-variance bias mixes a term zeta (w dt)^4 with (w dt)^5 / zeta of the other sign (its
    amplitude error per step is (w dt)^6 / 144, its decay's (w dt)^4 zeta): where it is resolvable (above the
    linearization's round-off) each halving of dt divides it by at least 2^4."""
    model, params = _compile(**WINDY)
    n = 5
    biases = []
    for dt in (0.16, 0.08, 0.04):
        held, _, _, w = _held_exact(params, dt)
        transition = one_step_map(model, "rk4", dt)
        input_map = step_input_column(model, "rk4", "ctrl", 0, dt)[:, None]
        biases.append(abs(rv.map_bias(held, transition, input_map, w / dt)[n // 2, n // 2] / held[n // 2, n // 2]))
    orders = np.log2(np.array(biases[:-1]) / np.array(biases[1:]))
    assert np.all(orders >= 4 - 0.1), (biases, orders)
